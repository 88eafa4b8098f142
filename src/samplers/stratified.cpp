#include <algorithm>

#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kPermTag = 0x7374726174000001ULL;
constexpr uint64_t kJitterTag = 0x7374726174000002ULL;
}  // namespace

Float StratifiedSampler::jitterValue(int dim, uint64_t salt) const {
    if (!jitter_) return 0.5;
    return BitsToUniform(Hash(seed_ ^ kJitterTag, pixelKey(), uint64_t(index_), (uint64_t(dim) << 1) | salt));
}

// Stratum of the current sample in dimension `dim` among n strata.
static uint32_t Stratum(uint64_t seed, uint64_t pixelKey, int64_t index, int dim, uint32_t n) {
    uint64_t block = uint64_t(index) / n;
    uint32_t local = uint32_t(uint64_t(index) % n);
    return PermutationElement(local, n, Hash(seed ^ kPermTag, pixelKey, uint64_t(dim), block));
}

Float StratifiedSampler::get1D() {
    int d = dim_++;
    uint32_t n = uint32_t(spp_);
    uint32_t s = Stratum(seed_, pixelKey(), index_, d, n);
    return std::min<Float>((s + jitterValue(d, 0)) / n, OneMinusEpsilon);
}

Point2 StratifiedSampler::get2D() {
    int d = dim_;
    dim_ += 2;
    uint32_t s = Stratum(seed_, pixelKey(), index_, d, uint32_t(spp_));
    uint32_t sx = s % uint32_t(xs_), sy = s / uint32_t(xs_);
    return {std::min<Float>((sx + jitterValue(d, 0)) / xs_, OneMinusEpsilon),
            std::min<Float>((sy + jitterValue(d, 1)) / ys_, OneMinusEpsilon)};
}

}  // namespace gradus
