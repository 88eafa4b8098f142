// Building blocks of the samplers: hashed permutations, randomised radical
// inverses with Owen scrambling, and the first two Sobol' dimensions.
#pragma once
#include <cstdint>

#include "samplers/rng.h"

namespace gradus {

// Element i of a pseudo-random permutation of [0, n) chosen by `seed`
// (a bijection for each fixed seed). Several rounds of invertible operations
// on w-bit integers (xor with a key, multiplication by an odd number, xor with
// a right shift of itself), with cycle walking when n is not a power of two.
inline uint32_t PermutationElement(uint32_t i, uint32_t n, uint64_t seed) {
    if (n <= 1) return 0;
    uint32_t mask = n - 1;
    mask |= mask >> 1; mask |= mask >> 2; mask |= mask >> 4; mask |= mask >> 8; mask |= mask >> 16;
    int w = 32 - __builtin_clz(mask);  // bits of mask (mask >= 1)
    int shift = (w + 1) / 2;
    uint64_t k = MixBits(seed ^ 0x4f1bbcdcbfa53e0bULL);
    uint32_t k0 = uint32_t(k), k1 = uint32_t(k >> 32);
    uint32_t m0 = (k0 * 0x9e3779b9U) | 1, m1 = (k1 * 0x85ebca6bU) | 1;
    do {
        i = (i ^ k0) & mask;
        i = (i * m0) & mask;
        i ^= i >> shift;
        i = (i + k1) & mask;
        i = (i * m1) & mask;
        i ^= i >> shift;
        i = (i ^ (k0 >> 16)) & mask;
        i = (i * 0x2c1b3c6dU) & mask;
        i ^= i >> (w > 2 ? w / 3 + 1 : 1);
    } while (i >= n);
    // A final keyed rotation makes every element exactly uniform over seeds
    // (cycle walking alone is biased when n is not a power of two).
    uint32_t r = uint32_t(MixBits(k ^ 0x94d049bb133111ebULL) % n);
    return i + r < n ? i + r : i + r - n;  // (i + r) mod n for i, r < n
}

// Radical inverse of `a` in `base` with Owen (nested uniform) scrambling: the
// permutation applied to digit j is chosen by hashing `seed` with digits
// 0..j-1 (the node of the digit tree). After the first max(minDigits, number
// of digits of a) digits, the rest of the scrambled value is a uniform value
// in the last interval hashed from the node, which is the distribution of the
// scrambled remaining (zero) digits. The joint distribution of the points
// a < base^minDigits is therefore exactly that of Owen scrambling (they have
// distinct minDigits-digit prefixes, hence independent tails), e.g. with
// base^minDigits >= spp the samples of a pixel keep their stratification.
// Result in [0, 1).
inline double OwenScrambledRadicalInverse(uint32_t base, uint64_t a, uint64_t seed, int minDigits = 0) {
    uint64_t h = MixBits(seed ^ (uint64_t(base) << 40));
    uint64_t digits = 0;
    double scale = 1;
    const double invBase = 1.0 / base;
    for (int j = 0; a != 0 || j < minDigits; ++j) {
        uint32_t d = uint32_t(a % base);
        a /= base;
        digits = digits * base + PermutationElement(d, base, h);
        scale *= invBase;
        h = MixBits(h ^ (d + 0x9e3779b97f4a7c15ULL));
    }
    double v = (double(digits) + BitsToUniform(MixBits(h + 0x5bd1e995ULL))) * scale;
    return v < OneMinusEpsilon ? v : OneMinusEpsilon;
}

// Number of base-b digits needed so that b^digits >= n.
inline int DigitsFor(uint64_t n, uint32_t base) {
    int d = 0;
    for (uint64_t p = 1; p < n; p *= base) ++d;
    return d;
}

// Owen scrambling of a base-2 fraction given by its 32 most significant bits
// `x` (bit 31 = 1/2). Same construction as above with base 2 (minBits <= 32).
inline double OwenScrambledBinary(uint32_t x, uint64_t seed, int minBits = 0) {
    uint64_t h = MixBits(seed ^ 0x2545f4914f6cdd1dULL);
    uint64_t bits = 0;
    double scale = 1;
    for (int j = 0; x != 0 || j < minBits; ++j) {
        uint32_t b = x >> 31;
        x <<= 1;
        bits = (bits << 1) | (b ^ uint32_t(h >> 63));
        scale *= 0.5;
        h = MixBits(h ^ (b + 0x9e3779b97f4a7c15ULL));
    }
    double v = (double(bits) + BitsToUniform(MixBits(h + 0x5bd1e995ULL))) * scale;
    return v < OneMinusEpsilon ? v : OneMinusEpsilon;
}

// Sobol' dimension 0 (van der Corput): bits of the index reversed.
inline uint32_t ReverseBits32(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffU) << 8) | ((i & 0xff00ff00U) >> 8);
    i = ((i & 0x0f0f0f0fU) << 4) | ((i & 0xf0f0f0f0U) >> 4);
    i = ((i & 0x33333333U) << 2) | ((i & 0xccccccccU) >> 2);
    i = ((i & 0x55555555U) << 1) | ((i & 0xaaaaaaaaU) >> 1);
    return i;
}
inline uint32_t SobolDim0(uint32_t i) { return ReverseBits32(i); }

// Sobol' dimension 1: generator matrix columns v_0 = 2^31, v_{k+1} = v_k ^ (v_k >> 1)
// (Pascal's triangle mod 2). With dimension 0 it forms a (0,2)-sequence in base 2.
// The matrix is linear over GF(2): the image of i is the XOR of the images of
// its four bytes, looked up in tables of the columns' 256 combinations per
// byte (no loop over the index's bits and its unpredictable branches).
struct SobolDim1Tables {
    uint32_t byte[4][256];
};
constexpr SobolDim1Tables MakeSobolDim1Tables() {
    SobolDim1Tables t{};
    uint32_t col[32] = {};
    uint32_t v = 0x80000000U;
    for (int k = 0; k < 32; ++k, v ^= v >> 1) col[k] = v;
    for (int b = 0; b < 4; ++b)
        for (int x = 0; x < 256; ++x) {
            uint32_t r = 0;
            for (int m = 0; m < 8; ++m)
                if (x & (1 << m)) r ^= col[8 * b + m];
            t.byte[b][x] = r;
        }
    return t;
}
inline constexpr SobolDim1Tables kSobolDim1 = MakeSobolDim1Tables();
inline uint32_t SobolDim1(uint32_t i) {
    return kSobolDim1.byte[0][i & 255] ^ kSobolDim1.byte[1][(i >> 8) & 255] ^ kSobolDim1.byte[2][(i >> 16) & 255] ^
           kSobolDim1.byte[3][i >> 24];
}
// The same tables with each entry's bits reversed: ReverseBits32(SobolDim1(i))
// (bit reversal is linear over GF(2), so it commutes with the XOR).
constexpr uint32_t ReverseBits32Constexpr(uint32_t v) {
    uint32_t r = 0;
    for (int k = 0; k < 32; ++k) r |= ((v >> k) & 1u) << (31 - k);
    return r;
}
constexpr SobolDim1Tables MakeSobolDim1ReversedTables() {
    SobolDim1Tables t = MakeSobolDim1Tables();
    for (auto &row : t.byte)
        for (uint32_t &e : row) e = ReverseBits32Constexpr(e);
    return t;
}
inline constexpr SobolDim1Tables kSobolDim1Reversed = MakeSobolDim1ReversedTables();
inline uint32_t SobolDim1Reversed(uint32_t i) {
    return kSobolDim1Reversed.byte[0][i & 255] ^ kSobolDim1Reversed.byte[1][(i >> 8) & 255] ^
           kSobolDim1Reversed.byte[2][(i >> 16) & 255] ^ kSobolDim1Reversed.byte[3][i >> 24];
}

// Hash-based Owen scrambling of 32-bit binary fractions (Burley 2020,
// "Practical Hash-based Owen Scrambling", JCGT 9(4)): the Laine-Karras
// permutation applied to the bit-reversed value flips each bit depending only
// on the bits above it, so it is a nested (Owen) scramble: elementary
// intervals, hence (0,m,2)-nets, are preserved exactly. A few multiplies
// instead of one hash per digit.
inline uint32_t LaineKarrasPermutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cU;
    x ^= x * 0xb82f1e52U;
    x ^= x * 0xc7afe638U;
    x ^= x * 0x8d22f6e6U;
    return x;
}
inline uint32_t ReverseBits32(uint32_t i);
inline uint32_t FastOwenScramble(uint32_t x, uint32_t seed) {
    return ReverseBits32(LaineKarrasPermutation(ReverseBits32(x), seed));
}

// The i-th prime (i >= 0), for Halton bases; i < PrimeTableSize.
constexpr int PrimeTableSize = 1024;
uint32_t Prime(int i);

// A prime base with the constant of Lemire, Kaser and Kurz's division by
// multiplication ("Faster remainder by direct computation", 2019):
// M = floor((2^64 - 1) / b) + 1 gives n / b and n % b exactly for every
// 32-bit n.
struct PrimeBase {
    uint32_t b;
    uint64_t M;
    uint32_t div(uint32_t n) const { return uint32_t((__uint128_t(M) * n) >> 64); }
    uint32_t mod(uint32_t n) const { return uint32_t((__uint128_t(M * n) * b) >> 64); }
};
struct PrimeBaseTable {
    PrimeBase base[PrimeTableSize];
};
constexpr PrimeBaseTable MakePrimeBaseTable() {
    PrimeBaseTable t{};
    int count = 0;
    for (uint32_t n = 2; count < PrimeTableSize; ++n) {
        bool prime = true;
        for (int k = 0; k < count && t.base[k].b * t.base[k].b <= n; ++k)
            if (n % t.base[k].b == 0) prime = false;
        if (prime) t.base[count++] = {n, ~uint64_t(0) / n + 1};
    }
    return t;
}
inline constexpr PrimeBaseTable kPrimeBases = MakePrimeBaseTable();
// Base of prime i (i < PrimeTableSize), without a bounds check.
inline const PrimeBase &PrimeBaseOf(int i) { return kPrimeBases.base[i]; }

// Radical inverse of `a` in prime base B with a nested scramble (Owen 1995,
// "Randomly permuted (t,m,s)-nets and (t,s)-sequences"): digit j goes through
// a permutation chosen by hashing `seed` with digits 0..j-1 (the node of the
// digit tree). Each node's permutation is affine, d -> (alpha d + kappa) mod b
// with alpha uniform in [1, b) and kappa uniform in [0, b) (from 32 hash bits
// each, a bias below b / 2^32): for prime b these maps are sharply
// 2-transitive, so two distinct digits go to a uniform pair of distinct
// digits, as under a uniformly random permutation. The variance of an
// estimate sum f(x_i) depends on the scramble only through the joint law of
// pairs (x_i, x_j) (Owen 1997, "Scrambled net variance for integrals of
// smooth functions", sec. 2), which is therefore that of Owen scrambling; in
// base 2 the maps are the two permutations of {0, 1}, Owen scrambling itself.
// Digits are taken while a != 0 or b^j < minCount; the remaining (zero)
// digits' scrambled value is a uniform value in the last interval hashed from
// the node. The points a < b^j of one seed keep the radical-inverse strata
// (each b^-j interval holds one), and each value is uniform on [0, 1).
inline double NestedAffineRadicalInverse(const PrimeBase &B, uint64_t a, uint64_t seed, uint64_t minCount) {
    const uint32_t b = B.b;
    uint64_t h = seed;
    uint64_t digits = 0, pw = 1;  // pw = b^j
    int j = 0;
    for (; a != 0 || pw < minCount; ++j) {
        uint64_t q;
        if (a <= 0xffffffffULL) q = B.div(uint32_t(a));
        else q = a / b;
        uint32_t d = uint32_t(a - q * b);
        a = q;
        uint32_t alpha = 1 + uint32_t((uint64_t(uint32_t(h >> 32)) * (b - 1)) >> 32);
        uint32_t kappa = uint32_t((uint64_t(uint32_t(h)) * b) >> 32);
        digits = digits * b + B.mod(alpha * d + kappa);  // alpha d + kappa < b^2 < 2^32
        pw *= b;
        h = MixBits(h ^ (d + 0x9e3779b97f4a7c15ULL));
    }
    // h is the hash of the node below the last digit (its bits, unused by the
    // permutations above, are the tail's).
    double v = (double(digits) + BitsToUniform(j == 0 ? MixBits(h + 0x5bd1e995ULL) : h)) / double(pw);
    return v < OneMinusEpsilon ? v : OneMinusEpsilon;
}

}  // namespace gradus
