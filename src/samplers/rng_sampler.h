// A Sampler that draws every value from a caller's RNG (per-item random
// numbers of pass work: light subpaths of vcm, mutations of pmlt).
#pragma once
#include <algorithm>

#include "core/error.h"
#include "samplers/rng.h"
#include "samplers/sampler.h"

namespace gradus {

class RNGSampler final : public Sampler {
  public:
    explicit RNGSampler(RNG &rng) : Sampler(1, 0), rng_(&rng) {}
    void setRNG(RNG &rng) { rng_ = &rng; }
    void startPixelSample(Point2i, int64_t, int) override {}
    Float get1D() override { return std::min<Float>(rng_->uniform(), OneMinusEpsilon); }
    Point2 get2D() override {
        Float a = get1D();
        return Point2(a, get1D());
    }
    std::unique_ptr<Sampler> clone() const override {
        GRADUS_CHECK(false);
        return nullptr;
    }
    std::string name() const override { return "rng"; }

  private:
    RNG *rng_;
};

}  // namespace gradus
