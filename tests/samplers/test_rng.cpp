#include <gtest/gtest.h>

#include <random>

#include <cmath>
#include <set>
#include <vector>

#include "common/chi2_test.h"
#include "samplers/lowdiscrepancy.h"
#include "samplers/rng.h"

using namespace gradus;

TEST(RNG, StreamsAreReproducibleAndDistinct) {
    RNG a(5), b(5), c(6);
    bool differs = false;
    for (int i = 0; i < 100; ++i) {
        uint32_t x = a.uniformU32();
        EXPECT_EQ(x, b.uniformU32());
        differs |= x != c.uniformU32();
    }
    EXPECT_TRUE(differs);
    RNG d;
    d.setSequence(5);
    RNG e(5);
    EXPECT_EQ(d, e);
}

TEST(RNG, AdvanceMatchesStepping) {
    for (int64_t n : {0, 1, 2, 7, 1000, 65537}) {
        RNG a(42, 17), b(42, 17);
        for (int64_t i = 0; i < n; ++i) a.uniformU32();
        b.advance(n);
        EXPECT_EQ(a, b) << n;
        EXPECT_EQ(a.uniformU32(), b.uniformU32());
        b.advance(-(n + 1));
        EXPECT_EQ(b, RNG(42, 17)) << n;
    }
}

// z-tests on mean and variance of uniform(): |z| < 3.29 has a false-positive
// rate of 0.1% per test under the null hypothesis.
TEST(RNG, UniformMoments) {
    RNG rng(99);
    const int n = 1000000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        double u = rng.uniform();
        ASSERT_TRUE(u >= 0 && u < 1);
        sum += u;
        sum2 += (u - 0.5) * (u - 0.5);
    }
    double zMean = (sum / n - 0.5) / std::sqrt(1.0 / 12 / n);
    double zVar = (sum2 / n - 1.0 / 12) / std::sqrt(1.0 / 180 / n);
    EXPECT_LT(std::abs(zMean), 3.29);
    EXPECT_LT(std::abs(zVar), 3.29);
}

TEST(Hash, SensitiveToEveryArgumentAndOrder) {
    std::set<uint64_t> seen;
    for (uint64_t a = 0; a < 8; ++a)
        for (uint64_t b = 0; b < 8; ++b)
            for (uint64_t c = 0; c < 8; ++c) seen.insert(Hash(a, b, c));
    EXPECT_EQ(seen.size(), 512u);
    EXPECT_NE(Hash(1, 2), Hash(2, 1));
    EXPECT_NE(MixBits(0), MixBits(1));
    // Avalanche: flipping one input bit flips about half of the output bits.
    RNG rng(3);
    double flips = 0;
    const int n = 2000;
    for (int i = 0; i < n; ++i) {
        uint64_t x = (uint64_t(rng.uniformU32()) << 32) | rng.uniformU32();
        int bit = rng.uniformU32() % 64;
        flips += __builtin_popcountll(MixBits(x) ^ MixBits(x ^ (1ULL << bit)));
    }
    EXPECT_NEAR(flips / n, 32, 0.5);  // sd of the mean is 4/sqrt(2000) ~ 0.09
}

TEST(Permutation, IsABijection) {
    for (uint32_t n : {1u, 2u, 3u, 4u, 5u, 9u, 16u, 17u, 100u, 1024u, 1000u}) {
        for (uint64_t seed = 0; seed < 20; ++seed) {
            std::vector<int> hit(n, 0);
            for (uint32_t i = 0; i < n; ++i) {
                uint32_t p = PermutationElement(i, n, seed);
                ASSERT_LT(p, n);
                ++hit[p];
            }
            for (uint32_t i = 0; i < n; ++i) ASSERT_EQ(hit[i], 1) << "n=" << n << " seed=" << seed;
        }
    }
}

// For a fixed index, the image over random seeds must be uniform (this is
// what makes hashed stratification unbiased). 1% false-positive rate overall.
TEST(Permutation, ElementUniformOverSeeds) {
    const int tests = 6;
    double alpha = chi2::SidakAlpha(0.01, tests);
    int k = 0;
    for (uint32_t n : {4u, 9u, 13u}) {
        for (uint32_t i : {0u, n - 1}) {
            std::vector<double> obs(n, 0), exp(n, 0);
            const int samples = 20000;
            for (int s = 0; s < samples; ++s) obs[PermutationElement(i, n, Hash(s, 77))] += 1;
            for (auto &e : exp) e = double(samples) / n;
            auto r = chi2::TestCounts(obs, exp, alpha);
            EXPECT_TRUE(r.pass) << "n=" << n << " i=" << i << ": " << r.message;
            ++k;
        }
    }
    EXPECT_EQ(k, tests);
}

TEST(LowDiscrepancy, SobolGeneratorsAndPrimes) {
    EXPECT_EQ(SobolDim0(1), 0x80000000u);
    EXPECT_EQ(SobolDim0(6), 0x60000000u);
    // Second Sobol' dimension: 0, 1/2, 3/4, 1/4, 5/8, 1/8, 3/8, 7/8 (Joe-Kuo ordering).
    const double expect[8] = {0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875};
    for (uint32_t i = 0; i < 8; ++i) EXPECT_EQ(SobolDim1(i) * 0x1p-32, expect[i]) << i;
    // (0,m,2)-net: first 2^m points, every elementary interval of area 2^-m holds one.
    for (int m = 1; m <= 8; ++m) {
        uint32_t n = 1u << m;
        for (int k = 0; k <= m; ++k) {
            std::vector<int> cell(n, 0);
            for (uint32_t i = 0; i < n; ++i) {
                uint32_t x = uint32_t(uint64_t(SobolDim0(i)) >> (32 - k));
                uint32_t y = uint32_t(uint64_t(SobolDim1(i)) >> (32 - (m - k)));
                ++cell[(x << (m - k)) | y];
            }
            for (uint32_t c = 0; c < n; ++c) ASSERT_EQ(cell[c], 1) << "m=" << m << " k=" << k;
        }
    }
    // The byte tables against the generator matrix column by column, over all
    // four bytes (v_0 = 2^31, v_{k+1} = v_k ^ (v_k >> 1)).
    std::mt19937 rng(11);
    for (int n = 0; n < 100000; ++n) {
        const uint32_t i = n < 32 ? (1u << n) : n == 32 ? 0xffffffffu : uint32_t(rng());
        uint32_t v = 0x80000000U, r = 0;
        for (uint32_t j = i; j != 0; j >>= 1, v ^= v >> 1)
            if (j & 1) r ^= v;
        ASSERT_EQ(SobolDim1(i), r) << i;
    }
    EXPECT_EQ(Prime(0), 2u);
    EXPECT_EQ(Prime(1), 3u);
    EXPECT_EQ(Prime(9), 29u);
    EXPECT_EQ(Prime(999), 7919u);
}

// Owen scrambling keeps the stratification of the radical inverse (b^k points
// fill the b^k intervals once each) and makes each point uniform over seeds.
TEST(LowDiscrepancy, OwenScramblingStratifiesAndIsUniform) {
    for (uint32_t base : {2u, 3u, 5u, 7u}) {
        uint32_t n = base * base * base;
        for (uint64_t seed = 1; seed < 6; ++seed) {
            std::vector<int> cell(n, 0);
            for (uint32_t i = 0; i < n; ++i) {
                double v = base == 2 ? OwenScrambledBinary(SobolDim0(i), seed, 3)
                                     : OwenScrambledRadicalInverse(base, i, seed, 3);
                ASSERT_TRUE(v >= 0 && v < 1);
                ++cell[int(v * n)];
            }
            for (uint32_t c = 0; c < n; ++c) ASSERT_EQ(cell[c], 1) << base << " " << seed;
        }
    }
    // Point 5 of base 3 over 20000 seeds, 30 bins (false-positive rate 0.1% per test, 2 tests).
    for (uint32_t base : {2u, 3u}) {
        std::vector<double> obs(30, 0), exp(30, 20000.0 / 30);
        for (int s = 0; s < 20000; ++s) {
            double v = base == 2 ? OwenScrambledBinary(SobolDim0(5), Hash(s), 4)
                               : OwenScrambledRadicalInverse(3, 5, Hash(s), 4);
            obs[int(v * 30)] += 1;
        }
        auto r = chi2::TestCounts(obs, exp, 0.001);
        EXPECT_TRUE(r.pass) << base << ": " << r.message;
    }
}

// The constants of PrimeBase divide and reduce every 32-bit value exactly.
TEST(LowDiscrepancy, PrimeBaseDivisionIsExact) {
    RNG rng(41);
    for (int i = 0; i < PrimeTableSize; ++i) {
        const PrimeBase &B = PrimeBaseOf(i);
        ASSERT_EQ(B.b, Prime(i));
        std::vector<uint32_t> ns{0u, 1u, B.b - 1, B.b, B.b + 1, B.b * B.b - 1, 0xffffffffu, 0xfffffffeu};
        for (int k = 0; k < 200; ++k) ns.push_back(rng.uniformU32());
        for (uint32_t n : ns) {
            ASSERT_EQ(B.div(n), n / B.b) << B.b << " " << n;
            ASSERT_EQ(B.mod(n), n % B.b) << B.b << " " << n;
        }
    }
}

// The nested affine scramble keeps the radical-inverse strata (b^3 consecutive
// indices from a multiple of b^3 fill the b^-3 intervals once each, also for
// indices past 2^32) and makes each point uniform over seeds.
TEST(LowDiscrepancy, NestedAffineScramblingStratifiesAndIsUniform) {
    for (int bi : {0, 1, 2, 3, 25}) {
        const PrimeBase &B = PrimeBaseOf(bi);
        uint64_t n = uint64_t(B.b) * B.b * (bi < 4 ? B.b : 1);
        for (uint64_t start : {uint64_t(0), n * ((uint64_t(1) << 40) + 3)})
            for (uint64_t seed = 1; seed < 6; ++seed) {
                std::vector<int> cell(n, 0);
                for (uint64_t i = 0; i < n; ++i) {
                    double v = NestedAffineRadicalInverse(B, start + i, Hash(seed), n);
                    ASSERT_TRUE(v >= 0 && v < 1);
                    ++cell[size_t(v * n)];
                }
                for (uint64_t c = 0; c < n; ++c) ASSERT_EQ(cell[c], 1) << B.b << " " << seed << " " << start;
            }
    }
    // Index 5 in bases 3 and 101 over 20000 seeds, 30 bins.
    for (int bi : {1, 25}) {
        std::vector<double> obs(30, 0), exp(30, 20000.0 / 30);
        for (int s = 0; s < 20000; ++s) obs[int(NestedAffineRadicalInverse(PrimeBaseOf(bi), 5, Hash(s), 16) * 30)] += 1;
        auto r = chi2::TestCounts(obs, exp, 0.001);
        EXPECT_TRUE(r.pass) << bi << ": " << r.message;
    }
}

// Over seeds, the scrambled digits of two indices have Owen scrambling's joint
// law (which fixes the estimator's variance): where their digits first differ
// (at the root for 2 and 5, at the second level for 3 and 17 = 3 + 2 * 7), the
// pair of scrambled digits is uniform over the 42 pairs of distinct digits;
// below a difference (second digits of 7 = (0,1) and 8 = (1,1) in base 7)
// the scrambled digits are independent (uniform over all 49 pairs). Cyclic
// shifts alone fail the first (a fixed difference), one permutation per
// level instead of per node fails the last (equal digits). Chi-square on 49
// cells, 20000 seeds, 0.1% false-positive rate per case (3 cases).
TEST(LowDiscrepancy, NestedAffineScramblingPairsAreOwens) {
    const PrimeBase &B = PrimeBaseOf(3);  // base 7
    struct Case {
        uint64_t i1, i2;
        int level;  // digit compared (0 = first)
        bool distinct;
    };
    for (Case c : {Case{2, 5, 0, true}, Case{3, 17, 1, true}, Case{7, 8, 1, false}}) {
        std::vector<double> obs(49, 0), exp(49, 0);
        const int n = 20000;
        for (int s = 0; s < n; ++s) {
            uint64_t seed = Hash(s, 991);
            double v1 = NestedAffineRadicalInverse(B, c.i1, seed, 49);
            double v2 = NestedAffineRadicalInverse(B, c.i2, seed, 49);
            int scale = c.level == 0 ? 7 : 49;
            int d1 = int(v1 * scale) % 7, d2 = int(v2 * scale) % 7;
            obs[d1 * 7 + d2] += 1;
        }
        for (int a = 0; a < 7; ++a)
            for (int b = 0; b < 7; ++b) exp[a * 7 + b] = c.distinct ? (a == b ? 0 : n / 42.0) : n / 49.0;
        auto r = chi2::TestCounts(obs, exp, 0.001);
        EXPECT_TRUE(r.pass) << c.i1 << "," << c.i2 << ": " << r.message;
    }
}

// The reversed Sobol' tables are the bit reversal of dimension 1, and the
// scramble of dimension 0 needs no reversal of the index (the sampler's
// shortcuts give FastOwenScramble's values).
TEST(LowDiscrepancy, ReversedSobolShortcuts) {
    RNG rng(43);
    for (int k = 0; k < 20000; ++k) {
        uint32_t i = k < 1000 ? uint32_t(k) : rng.uniformU32(), seed = rng.uniformU32();
        ASSERT_EQ(SobolDim1Reversed(i), ReverseBits32(SobolDim1(i)));
        ASSERT_EQ(ReverseBits32(LaineKarrasPermutation(i, seed)), FastOwenScramble(SobolDim0(i), seed));
        ASSERT_EQ(ReverseBits32(LaineKarrasPermutation(SobolDim1Reversed(i), seed)),
                  FastOwenScramble(SobolDim1(i), seed));
    }
}
