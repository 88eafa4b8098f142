#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kShuffleTag = 0x736f626f6c000001ULL;
constexpr uint64_t kScrambleTag = 0x736f626f6c000002ULL;
}  // namespace

int RoundUpPow2(int n) {
    int p = 1;
    while (p < n) p <<= 1;
    return p;
}

SobolSampler::SobolSampler(int spp, uint64_t seed) : AddressedSampler(spp, seed), log2spp_(0) {
    GRADUS_CHECK(spp >= 1 && RoundUpPow2(spp) == spp);
    while ((1 << log2spp_) < spp) ++log2spp_;
}

// Permutes the index within its aligned block of spp samples: each block of a
// (0,2)-sequence is a (0,m,2)-net, so the block stays one.
uint32_t SobolSampler::shuffledIndex(int dim) const {
    uint64_t i = uint64_t(index_);
    uint64_t block = i >> log2spp_;
    uint32_t local = uint32_t(i & uint64_t(spp_ - 1));
    uint32_t p = PermutationElement(local, uint32_t(spp_), Hash(seed_ ^ kShuffleTag, pixelKey(), uint64_t(dim), block));
    return uint32_t((block << log2spp_) | p);
}

Float SobolSampler::get1D() {
    int d = dim_++;
    uint32_t i = shuffledIndex(d);
    return OwenScrambledBinary(SobolDim0(i), Hash(seed_ ^ kScrambleTag, pixelKey(), uint64_t(d), 0), log2spp_);
}

Point2 SobolSampler::get2D() {
    int d = dim_;
    dim_ += 2;
    uint32_t i = shuffledIndex(d);
    return {OwenScrambledBinary(SobolDim0(i), Hash(seed_ ^ kScrambleTag, pixelKey(), uint64_t(d), 0), log2spp_),
            OwenScrambledBinary(SobolDim1(i), Hash(seed_ ^ kScrambleTag, pixelKey(), uint64_t(d), 1), log2spp_)};
}

}  // namespace gradus
