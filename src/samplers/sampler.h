// Samplers: every random number is addressed by (pixel, sample index,
// dimension) and the render seed, so a render is identical for any thread
// count and one sample can be re-run alone (--debugpixel).
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "core/geometry.h"
#include "parser/scene_desc.h"

namespace gradus {

class Sampler {
  public:
    virtual ~Sampler() = default;
    int samplesPerPixel() const { return spp_; }
    uint64_t seed() const { return seed_; }  // the render seed (RenderStats::seed, PassContext::seed)
    // Positions the sampler on sample `sampleIndex` of `pixel`, starting at
    // dimension `dimension`. Subsequent get1D/get2D calls advance the dimension.
    virtual void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) = 0;
    // Uniform values in [0, 1) (never exactly 1).
    virtual Float get1D() = 0;
    virtual Point2 get2D() = 0;
    // The dimension the next get1D/get2D takes, and a jump to another one, for
    // estimators that give each of their parts a fixed block of dimensions
    // (bdpt: a strategy's connection numbers stay stratified over a pixel's
    // samples whatever the subpaths' lengths). Samplers without dimensions
    // (RNGSampler) report -1 and ignore the jump.
    virtual int dimension() const { return -1; }
    virtual void setDimension(int) {}
    virtual std::unique_ptr<Sampler> clone() const = 0;
    virtual std::string name() const = 0;

  protected:
    explicit Sampler(int spp, uint64_t seed) : spp_(spp), seed_(seed) {}
    int spp_;
    uint64_t seed_;
};

// Creates the sampler named by desc.type ("random", "stratified", "halton",
// "sobol"; pbrt-v3's "lowdiscrepancy"/"02sequence" and "maxmindist" map to the
// closest one, see sampler.cpp). sppOverride > 0 replaces pixelsamples.
// Consumes its parameters; unused ones are reported by desc.params.checkUnused.
std::unique_ptr<Sampler> CreateSampler(const EntityDesc &desc, uint64_t seed, int sppOverride);

}  // namespace gradus
