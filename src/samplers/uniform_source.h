// Where an estimator that takes an unbounded number of uniform numbers (the
// media: distance sampling, delta and ratio tracking) draws them: a caller's
// RNG (path, bdpt, mbdpt, vcm: a per-sample stream, never the pixel sampler's
// dimensions) or a sampler's successive dimensions (mlt: its primary-sample
// state, so that mutations perturb them, as pbrt-v3's MLTSampler serves
// Medium::Sample and Medium::Tr). A value holding a pointer: copies share the
// underlying stream. Empty (false) when neither is given.
#pragma once
#include "samplers/rng.h"
#include "samplers/sampler.h"

namespace gradus {

class UniformSource {
  public:
    UniformSource() = default;
    UniformSource(RNG *rng) : rng_(rng) {}  // nullptr: empty
    UniformSource(RNG &rng) : rng_(&rng) {}
    explicit UniformSource(Sampler &sampler) : sampler_(&sampler) {}
    explicit operator bool() const { return rng_ || sampler_; }
    // The next uniform number in [0, 1).
    double uniform() const { return sampler_ ? double(sampler_->get1D()) : rng_->uniform(); }

  private:
    RNG *rng_ = nullptr;
    Sampler *sampler_ = nullptr;
};

}  // namespace gradus
