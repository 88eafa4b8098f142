#include "samplers/rng.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kRandomTag = 0x72616e646f6d0001ULL;
}

void RandomSampler::startPixelSample(Point2i pixel, int64_t sampleIndex, int dimension) {
    AddressedSampler::startPixelSample(pixel, sampleIndex, dimension);
    sampleHash_ = HashWord3(HashWord2(HashWord1(seed_ ^ kRandomTag), pixelKey()), uint64_t(index_));
}

// = BitsToUniform(Hash(seed ^ tag, pixel, index, dim)).
Float RandomSampler::get1D() { return BitsToUniform(HashWord4(sampleHash_, uint64_t(dim_++))); }

Point2 RandomSampler::get2D() {
    Float x = get1D();
    return {x, get1D()};
}

}  // namespace gradus
