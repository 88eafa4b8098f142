// The concrete samplers. Each one stores only its position (pixel, sample
// index, dimension); every value it returns is a pure function of
// (seed, pixel, sample index, dimension), so clones, threads and call order
// never change a render. get1D consumes one dimension, get2D two.
#pragma once
#include "samplers/rng.h"
#include "samplers/sampler.h"

namespace gradus {

// Common bookkeeping of the current (pixel, sample index, dimension).
class AddressedSampler : public Sampler {
  public:
    void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) override {
        pixel_ = pixel;
        index_ = sampleIndex;
        dim_ = dimension;
    }
    int dimension() const override { return dim_; }
    void setDimension(int dimension) override { dim_ = dimension; }

  protected:
    AddressedSampler(int spp, uint64_t seed) : Sampler(spp, seed) {}
    uint64_t pixelKey() const { return (uint64_t(uint32_t(pixel_.x)) << 32) | uint32_t(pixel_.y); }
    Point2i pixel_;
    int64_t index_ = 0;
    int dim_ = 0;
};

// "random": independent uniform values, each a hash of its address.
class RandomSampler : public AddressedSampler {
  public:
    RandomSampler(int spp, uint64_t seed) : AddressedSampler(spp, seed) {}
    void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) override;
    Float get1D() override;
    Point2 get2D() override;
    std::unique_ptr<Sampler> clone() const override { return std::make_unique<RandomSampler>(*this); }
    std::string name() const override { return "random"; }

  private:
    uint64_t sampleHash_ = 0;  // the hash state after (seed, pixel, index), per sample
};

// "stratified": xs*ys strata per pixel; 1D dimensions use xs*ys strata of
// [0,1), 2D dimensions an xs-by-ys grid. The stratum of a sample in each
// dimension is a hashed permutation of the sample index (per pixel, dimension
// and block of xs*ys samples), so any sample can be generated alone.
// Indices beyond xs*ys start a new, independently permuted block.
class StratifiedSampler : public AddressedSampler {
  public:
    StratifiedSampler(int xs, int ys, bool jitter, uint64_t seed)
        : AddressedSampler(xs * ys, seed), xs_(xs), ys_(ys), jitter_(jitter) {}
    void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) override;
    Float get1D() override;
    Point2 get2D() override;
    std::unique_ptr<Sampler> clone() const override { return std::make_unique<StratifiedSampler>(*this); }
    std::string name() const override { return "stratified"; }
    int xSamples() const { return xs_; }
    int ySamples() const { return ys_; }
    bool jitter() const { return jitter_; }

  private:
    Float jitterValue(int dim, uint64_t salt) const;
    uint32_t stratum(int dim) const;
    int xs_, ys_;
    bool jitter_;
    // Hash states kept per sample: after (seed, pixel) for the strata's
    // permutations, after (seed, pixel, index) for the jitter.
    uint64_t permHash_ = 0, jitterHash_ = 0;
};

// "halton": dimension d is the radical inverse of the sample index in the
// d-th prime base (cycling after PrimeTableSize bases), with a nested
// (Owen-type) scramble whose permutations are hashed from (seed, pixel,
// dimension, digit prefix); see NestedAffineRadicalInverse.
class HaltonSampler : public AddressedSampler {
  public:
    HaltonSampler(int spp, uint64_t seed) : AddressedSampler(spp, seed) {}
    void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) override;
    Float get1D() override;
    Point2 get2D() override;
    std::unique_ptr<Sampler> clone() const override { return std::make_unique<HaltonSampler>(*this); }
    std::string name() const override { return "halton"; }

  private:
    Float value(int dim) const;
    uint64_t pixelHash_ = 0;  // Hash(seed, pixel), cached per sample
};

// "sobol" = padded scrambled (0,2)-sequence. Every 2D request takes the first
// two Sobol' dimensions (a (0,2)-sequence), every 1D request the first one
// (van der Corput). Each dimension (pair) has its own Owen scrambling and its
// own shuffle of the sample index within aligned blocks of spp samples, both
// hashed from (seed, pixel, dimension). With spp a power of two, the spp
// samples of a pixel form a scrambled (0,m,2)-net in every pair.
class SobolSampler : public AddressedSampler {
  public:
    SobolSampler(int spp, uint64_t seed);  // spp must be a power of two
    void startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension = 0) override;
    Float get1D() override;
    Point2 get2D() override;
    std::unique_ptr<Sampler> clone() const override { return std::make_unique<SobolSampler>(*this); }
    std::string name() const override { return "sobol"; }

  private:
    uint32_t shuffledIndex(int dim, uint64_t h) const;
    uint64_t dimHash(int d) const { return MixBits(pixelHash_ ^ (uint64_t(d + 1) * 0x9e3779b97f4a7c15ULL)); }
    int log2spp_;
    uint64_t pixelHash_ = 0;  // Hash(seed, pixel), cached per sample
};

// Smallest power of two >= n (n >= 1).
int RoundUpPow2(int n);

}  // namespace gradus
