#include <algorithm>

#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kPermTag = 0x7374726174000001ULL;
constexpr uint64_t kJitterTag = 0x7374726174000002ULL;
}  // namespace

void StratifiedSampler::startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension) {
    AddressedSampler::startPixelSample(pixel, sampleIndex, dimension);
    permHash_ = HashWord2(HashWord1(seed_ ^ kPermTag), pixelKey());
    jitterHash_ = HashWord3(HashWord2(HashWord1(seed_ ^ kJitterTag), pixelKey()), uint64_t(index_));
}

// = BitsToUniform(Hash(seed ^ kJitterTag, pixel, index, 2 dim + salt)).
Float StratifiedSampler::jitterValue(int dim, uint64_t salt) const {
    if (!jitter_) return 0.5;
    return BitsToUniform(HashWord4(jitterHash_, (uint64_t(dim) << 1) | salt));
}

// Stratum of the current sample in dimension `dim` among spp strata: element
// (index mod spp) of the permutation hashed from (seed ^ kPermTag, pixel, dim, block).
uint32_t StratifiedSampler::stratum(int dim) const {
    uint32_t n = uint32_t(spp_);
    uint64_t block = uint64_t(index_) / n;
    uint32_t local = uint32_t(uint64_t(index_) % n);
    return PermutationElement(local, n, HashWord4(HashWord3(permHash_, uint64_t(dim)), block));
}

Float StratifiedSampler::get1D() {
    int d = dim_++;
    uint32_t n = uint32_t(spp_);
    uint32_t s = stratum(d);
    return std::min<Float>((s + jitterValue(d, 0)) / n, OneMinusEpsilon);
}

Point2 StratifiedSampler::get2D() {
    int d = dim_;
    dim_ += 2;
    uint32_t s = stratum(d);
    uint32_t sx = s % uint32_t(xs_), sy = s / uint32_t(xs_);
    return {std::min<Float>((sx + jitterValue(d, 0)) / xs_, OneMinusEpsilon),
            std::min<Float>((sy + jitterValue(d, 1)) / ys_, OneMinusEpsilon)};
}

}  // namespace gradus
