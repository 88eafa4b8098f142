#include "samplers/rng.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {
constexpr uint64_t kRandomTag = 0x72616e646f6d0001ULL;
}

Float RandomSampler::get1D() {
    uint64_t h = Hash(seed_ ^ kRandomTag, pixelKey(), uint64_t(index_), uint64_t(dim_++));
    return BitsToUniform(h);
}

Point2 RandomSampler::get2D() {
    Float x = get1D();
    return {x, get1D()};
}

}  // namespace gradus
