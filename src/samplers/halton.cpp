#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kHaltonTag = 0x68616c746f6e0002ULL;
}

void HaltonSampler::startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension) {
    AddressedSampler::startPixelSample(pixel, sampleIndex, dimension);
    pixelHash_ = Hash(seed_ ^ kHaltonTag, pixelKey());
}

// Digits are kept while b^j < spp: the spp samples of a pixel fill the
// radical-inverse strata of every dimension.
Float HaltonSampler::value(int dim) const {
    const PrimeBase &B = PrimeBaseOf(dim % PrimeTableSize);
    uint64_t seed = MixBits(pixelHash_ ^ (uint64_t(dim + 1) * 0x9e3779b97f4a7c15ULL));
    return NestedAffineRadicalInverse(B, uint64_t(index_), seed, uint64_t(spp_));
}

Float HaltonSampler::get1D() { return value(dim_++); }

Point2 HaltonSampler::get2D() {
    Point2 p{value(dim_), value(dim_ + 1)};
    dim_ += 2;
    return p;
}

}  // namespace gradus
