// Hashing and the PCG32 random number generator (O'Neill 2014, "PCG: a family
// of simple fast space-efficient statistically good algorithms").
#pragma once
#include <cstdint>
#include <cstring>

namespace gradus {

// 64-bit finaliser (the "Moremur"-style xor-shift-multiply mix): every input
// bit affects every output bit; bijective.
inline uint64_t MixBits(uint64_t v) {
    v ^= v >> 27;
    v *= 0x3c79ac492ba7b653ULL;
    v ^= v >> 33;
    v *= 0x1c69b3f74ac4ae35ULL;
    v ^= v >> 27;
    return v;
}

// Order-sensitive hash of up to four 64-bit words, a chain of MixBits whose
// intermediate states can be kept: Hash(a, b, c, d) ==
// HashWord4(HashWord3(HashWord2(HashWord1(a), b), c), d), so a caller that
// hashes many words after the same (a, b) computes that prefix once.
inline uint64_t HashWord1(uint64_t a) { return MixBits(a + 0x9e3779b97f4a7c15ULL); }
inline uint64_t HashWord2(uint64_t h, uint64_t b) { return MixBits(h ^ (b + 0x632be59bd9b4e019ULL)); }
inline uint64_t HashWord3(uint64_t h, uint64_t c) { return MixBits(h ^ (c + 0x8cb92ba72f3d8dd7ULL)); }
inline uint64_t HashWord4(uint64_t h, uint64_t d) { return MixBits(h ^ (d + 0xa0761d6478bd642fULL)); }
inline uint64_t Hash(uint64_t a, uint64_t b = 0, uint64_t c = 0, uint64_t d = 0) {
    return HashWord4(HashWord3(HashWord2(HashWord1(a), b), c), d);
}

// The bits of a double (hash keys).
inline uint64_t FloatBits(double v) {
    uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
}

// Largest double below 1.
constexpr double OneMinusEpsilon = 0x1.fffffffffffffp-1;

// Maps 64 random bits to a double in [0, 1) with 53-bit resolution.
inline double BitsToUniform(uint64_t bits) { return double(bits >> 11) * 0x1p-53; }

class RNG {
  public:
    RNG() : state_(0x853c49e6748fea9bULL), inc_(0xda3e39cb94b95bdbULL) {}
    explicit RNG(uint64_t seq, uint64_t state = 0x853c49e6748fea9bULL) { setSequence(seq, state); }

    // Selects stream `seq` (2^63 distinct streams) and start offset.
    void setSequence(uint64_t seq, uint64_t offset = 0x853c49e6748fea9bULL) {
        state_ = 0;
        inc_ = (seq << 1) | 1;
        uniformU32();
        state_ += offset;
        uniformU32();
    }

    uint32_t uniformU32() {
        uint64_t old = state_;
        state_ = old * kMult + inc_;
        uint32_t xorshifted = uint32_t(((old >> 18) ^ old) >> 27);
        uint32_t rot = uint32_t(old >> 59);
        return (xorshifted >> rot) | (xorshifted << ((32 - rot) & 31));
    }

    // Uniform in [0, 1) with 32-bit resolution; (2^32-1)/2^32 < 1 exactly in double.
    double uniform() { return uniformU32() * 0x1p-32; }

    // Jumps the state by `delta` steps (negative = backwards, mod 2^64) in
    // O(log delta): the LCG x -> m x + c composed n times is x -> M x + C with
    // M = m^n and C = c (m^(n-1) + ... + 1), built by repeated squaring.
    void advance(int64_t delta) {
        uint64_t curMult = kMult, curPlus = inc_, accMult = 1, accPlus = 0;
        uint64_t n = uint64_t(delta);
        while (n > 0) {
            if (n & 1) {
                accMult *= curMult;
                accPlus = accPlus * curMult + curPlus;
            }
            curPlus = (curMult + 1) * curPlus;
            curMult *= curMult;
            n >>= 1;
        }
        state_ = accMult * state_ + accPlus;
    }

    bool operator==(const RNG &o) const { return state_ == o.state_ && inc_ == o.inc_; }
    bool operator!=(const RNG &o) const { return !(*this == o); }

  private:
    static constexpr uint64_t kMult = 0x5851f42d4c957f2dULL;
    uint64_t state_, inc_;
};

}  // namespace gradus
