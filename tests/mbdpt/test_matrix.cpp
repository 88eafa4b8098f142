// Unit tests of the connection-matrix building blocks (matrix.h): sort keys,
// the stratification of the column points, and the uniform marginal of every
// point that makes the M-BDPT estimator unbiased.
// Statistical checks use fixed seeds; each states its false-positive rate
// for a random seed.
#include <gtest/gtest.h>

#include <set>

#include "integrators/mbdpt/matrix.h"

namespace gradus::mbdpt {
namespace {

// Chi-square quantile by the Wilson-Hilferty approximation; z = 4.265 is the
// one-sided normal quantile of 1e-5.
double ChiSquareThreshold(int dof, double z = 4.265) {
    double a = 2.0 / (9.0 * dof);
    return dof * std::pow(1 - a + z * std::sqrt(a), 3);
}

TEST(MBDPTMatrix, DistanceMetricIsSumOfSquaredSegments) {
    PathVertex v[3];
    v[0].p = Point3(0, 0, 0);
    v[1].p = Point3(1, 2, 2);   // |.|^2 = 9
    v[2].p = Point3(1, 2, 4);   // |.|^2 = 4
    EXPECT_DOUBLE_EQ(DistanceMetric(v, 1), 0);
    EXPECT_DOUBLE_EQ(DistanceMetric(v, 2), 9);
    EXPECT_DOUBLE_EQ(DistanceMetric(v, 3), 13);
    EXPECT_LT(DistanceKey(9), DistanceKey(13));
    EXPECT_LT(DistanceKey(0), DistanceKey(1e-300));
    EXPECT_LT(DistanceKey(1e10), DistanceKey(1e11));
}

TEST(MBDPTMatrix, MortonKeyOrdersCellsAndClamps) {
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    EXPECT_EQ(MortonKey(Point3(-1, -1, -1), b), 0u);
    EXPECT_EQ(MortonKey(Point3(-5, -5, -5), b), 0u);
    EXPECT_EQ(MortonKey(Point3(1, 1, 1), b), (uint64_t(1) << 63) - 1);
    EXPECT_LT(MortonKey(Point3(-0.5, -0.5, -0.5), b), MortonKey(Point3(0.5, 0.5, 0.5), b));
    // Along one axis with the others fixed, the code increases.
    EXPECT_LT(MortonKey(Point3(0.1, 0, 0), b), MortonKey(Point3(0.2, 0, 0), b));
}

TEST(MBDPTMatrix, LatticeHasOnePointPerColumnStratum) {
    for (uint64_t rows : {1, 2, 7, 64, 100, 1000, 4097})
        for (int m : {1, 2, 4}) {
            uint64_t K = rows * m;
            EXPECT_EQ(std::gcd(LatticeGenerator(K), K), 1u) << K;
            // Shifts whose offset within a stratum is away from 0 and 1 (no rounding across strata).
            for (double shift : {0.25 / K, 0.3141 + 0.5 / K, (K - 0.3) / K}) {
                ColumnSampler cs(MatrixSampling::Lattice, rows, m, shift, 7);
                std::set<uint64_t> strata;
                for (uint64_t r = 0; r < rows; ++r)
                    for (int c = 0; c < m; ++c) {
                        double y = cs.coordinate(r, c, 0.5);
                        ASSERT_GE(y, 0);
                        ASSERT_LT(y, 1);
                        strata.insert(uint64_t(std::floor(y * K)));
                    }
                EXPECT_EQ(strata.size(), K) << "rows " << rows << " m " << m;
            }
        }
}

TEST(MBDPTMatrix, LatinHypercubeStrataAndBands) {
    for (uint64_t rows : {1, 5, 64, 333})
        for (int m : {1, 2, 4}) {
            ColumnSampler cs(MatrixSampling::LHS, rows, m, 0, 12345);
            std::set<uint64_t> strata;
            RNG rng(3);
            for (uint64_t r = 0; r < rows; ++r)
                for (int c = 0; c < m; ++c) {
                    double y = cs.coordinate(r, c, rng.uniform());
                    strata.insert(uint64_t(std::floor(y * rows * m)));
                    EXPECT_EQ(int(std::floor(y * m)), c);  // the m points of a row are in distinct 1/m bands
                }
            EXPECT_EQ(strata.size(), rows * m);
        }
}

// Each column is selected with probability 1 / columns whatever the row rank:
// lattice and random points one by one, LHS points as the mixture over the m
// points of a row (point c lies in band c). Chi-square over columns with fresh
// per-iteration randomness (shift, seed, u); false-positive rate 1e-5 per case.
TEST(MBDPTMatrix, EveryPointSelectsColumnsUniformly) {
    const uint64_t rows = 11, cols = 7;
    const int m = 2, n = 70000;
    for (MatrixSampling mode : {MatrixSampling::Lattice, MatrixSampling::LHS, MatrixSampling::Random})
        for (uint64_t rank : {0, 5, 10})
            for (int c = 0; c < m; ++c) {
                const bool mixture = mode == MatrixSampling::LHS;
                if (mixture && c > 0) continue;
                std::vector<int> hist(cols, 0);
                RNG rng(1000 + int(mode) * 100 + rank * 10 + c);
                for (int i = 0; i < n; ++i) {
                    uint64_t seed = (uint64_t(rng.uniformU32()) << 32) | rng.uniformU32();
                    ColumnSampler cs(mode, rows, m, rng.uniform(), seed);
                    int cc = mixture ? i % m : c;
                    ++hist[ColumnSampler::Column(cs.coordinate(rank, cc, rng.uniform()), cols)];
                }
                double chi2 = 0, e = double(n) / cols;
                for (int h : hist) chi2 += (h - e) * (h - e) / e;
                EXPECT_LT(chi2, ChiSquareThreshold(int(cols) - 1))
                    << "mode " << int(mode) << " rank " << rank << " c " << c;
            }
}

// Power of the uniformity check: a column choice that ignores the shift for
// one point of ten (a plausible bug) is detected.
TEST(MBDPTMatrix, UniformityCheckDetectsBias) {
    const uint64_t rows = 11, cols = 7;
    const int n = 70000;
    std::vector<int> hist(cols, 0);
    RNG rng(99);
    for (int i = 0; i < n; ++i) {
        ColumnSampler cs(MatrixSampling::Lattice, rows, 1, i % 10 == 0 ? 0.0 : rng.uniform(), 0);
        ++hist[ColumnSampler::Column(cs.coordinate(3, 0, 0.5), cols)];
    }
    double chi2 = 0, e = double(n) / cols;
    for (int h : hist) chi2 += (h - e) * (h - e) / e;
    EXPECT_GT(chi2, ChiSquareThreshold(int(cols) - 1));
}

TEST(MBDPTMatrix, RowParticipation) {
    // Over iterations (random shifts) each row takes part with probability rho:
    // binomial z-test, |z| < 5 (false-positive rate 6e-7 per case).
    for (double rho : {0.05, 0.5, 0.9})
        for (uint64_t rank : {0, 17, 999}) {
            RNG rng(uint64_t(rho * 1000) + rank);
            const int n = 100000;
            int k = 0;
            for (int i = 0; i < n; ++i) {
                ColumnSampler cs(MatrixSampling::Lattice, 1000, 1, 0, 0, rng.uniform());
                k += cs.participates(rank, rho);
            }
            double z = (k - n * rho) / std::sqrt(n * rho * (1 - rho));
            EXPECT_LT(std::abs(z), 5) << "rho " << rho << " rank " << rank;
        }
    // Within one iteration about rho * rows rows take part (low-discrepancy Weyl sequence).
    for (double shift : {0.0, 0.77}) {
        ColumnSampler cs(MatrixSampling::Lattice, 10000, 1, 0, 0, shift);
        for (double rho : {0.01, 0.3, 0.75}) {
            int k = 0;
            for (uint64_t r = 0; r < 10000; ++r) k += cs.participates(r, rho);
            EXPECT_NEAR(k, 10000 * rho, 5);
        }
    }
}

// The reordering's radix sort gives std::sort's total order on (key, index)
// pairs in index order: many ties, keys sharing high bytes, doubles' bit patterns.
TEST(MBDPTMatrix, RadixSortEqualsStdSort) {
    RNG rng(7);
    for (int trial = 0; trial < 40; ++trial) {
        const size_t n = 1 + size_t(rng.uniform() * 5000);
        std::vector<std::pair<uint64_t, uint32_t>> a(n), tmp;
        for (size_t i = 0; i < n; ++i) {
            uint64_t key;
            switch (trial % 4) {
            case 0: key = uint64_t(rng.uniform() * 16); break;                      // few distinct keys
            case 1: key = DistanceKey(rng.uniform() * 100); break;                  // sort keys of d(y)
            case 2: key = 0x3ff0000000000000ULL | uint64_t(rng.uniform() * 300); break;  // shared high bytes
            default: key = uint64_t(rng.uniform() * 18446744073709549568.0); break;
            }
            a[i] = {key, uint32_t(i)};
        }
        std::vector<std::pair<uint64_t, uint32_t>> ref = a;
        std::sort(ref.begin(), ref.end());
        RadixSortKeys(a, tmp);
        ASSERT_EQ(a, ref) << "trial " << trial;
    }
}

}  // namespace
}  // namespace gradus::mbdpt
