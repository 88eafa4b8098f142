#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kHaltonTag = 0x68616c746f6e0001ULL;
}

Float HaltonSampler::value(int dim) const {
    uint32_t base = Prime(dim % PrimeTableSize);
    return OwenScrambledRadicalInverse(base, uint64_t(index_), Hash(seed_ ^ kHaltonTag, pixelKey(), uint64_t(dim)),
                                       DigitsFor(uint64_t(spp_), base));
}

Float HaltonSampler::get1D() { return value(dim_++); }

Point2 HaltonSampler::get2D() {
    Point2 p{value(dim_), value(dim_ + 1)};
    dim_ += 2;
    return p;
}

}  // namespace gradus
