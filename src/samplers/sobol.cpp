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
// The local index (k = log2 spp bits) is permuted by a hashed Owen scramble of
// the k-bit binary fraction local / spp, which is a bijection of [0, spp).
uint32_t SobolSampler::shuffledIndex(int dim, uint64_t h) const {
    uint64_t i = uint64_t(index_);
    uint64_t block = i >> log2spp_;
    uint32_t local = uint32_t(i & uint64_t(spp_ - 1));
    if (log2spp_ == 0) return uint32_t(block);
    uint32_t seed = uint32_t(MixBits(h ^ kShuffleTag ^ (block * 0x9e3779b97f4a7c15ULL)));
    uint32_t p = FastOwenScramble(local << (32 - log2spp_), seed) >> (32 - log2spp_);
    return uint32_t((block << log2spp_) | p);
}

void SobolSampler::startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension) {
    AddressedSampler::startPixelSample(pixel, sampleIndex, dimension);
    pixelHash_ = Hash(seed_ ^ kScrambleTag, pixelKey());
}

namespace {
// Scrambled 32-bit fraction to [0, 1) (resolution 2^-32, centred in its cell).
inline Float ToUnit(uint32_t bits) { return (double(bits) + 0.5) * 0x1p-32; }
}  // namespace

// FastOwenScramble(x, seed) = Reverse(LK(Reverse(x), seed)): with x =
// SobolDim0(i) = Reverse(i) the inner reversal cancels, and for SobolDim1 the
// reversed tables give Reverse(SobolDim1(i)) directly (same values).
Float SobolSampler::get1D() {
    int d = dim_++;
    uint64_t h = dimHash(d);
    uint32_t i = shuffledIndex(d, h);
    return ToUnit(ReverseBits32(LaineKarrasPermutation(i, uint32_t(h))));
}

Point2 SobolSampler::get2D() {
    int d = dim_;
    dim_ += 2;
    uint64_t h = dimHash(d);
    uint32_t i = shuffledIndex(d, h);
    return {ToUnit(ReverseBits32(LaineKarrasPermutation(i, uint32_t(h)))),
            ToUnit(ReverseBits32(LaineKarrasPermutation(SobolDim1Reversed(i), uint32_t(h >> 32))))};
}

}  // namespace gradus
