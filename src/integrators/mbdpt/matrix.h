// Connection-matrix building blocks of M-BDPT (Chaitanya et al., "Matrix
// Bidirectional Path Tracing", Sec. 4.2-4.3): sort keys of subpaths and the
// choice of matrix columns (light subpaths) for a row (camera subpath).
// Pure functions, unit-tested in tests/mbdpt/.
#pragma once
#include <cmath>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <utility>
#include <vector>

#include "core/geometry.h"
#include "integrators/common/path_vertex.h"
#include "samplers/lowdiscrepancy.h"
#include "samplers/rng.h"

namespace gradus::mbdpt {

enum class Reorder { Distance, Morton, None };
// How the columns of a row are chosen: rank-1 lattice (2D low-discrepancy),
// Latin hypercube, independent uniform, the diagonal (plain BDPT pairing), or
// Pixel: each pixel's column coordinates (and row participation) are
// dimensions of its own sample, so over the iterations a pixel's connections
// are stratified along the sorted light subpaths (no row order needed).
enum class MatrixSampling { Lattice, LHS, Random, Diagonal, Pixel };

// Sec. 4.2: d(y) = sum_{k=0}^{n-2} |y_k - y_{k+1}|^2 over the first n vertices.
inline double DistanceMetric(const PathVertex *v, int n) {
    double d = 0;
    for (int k = 0; k + 1 < n; ++k) d += DistanceSquared(v[k].p, v[k + 1].p);
    return d;
}

// Order-preserving map of a non-negative double to an integer sort key.
inline uint64_t DistanceKey(double d) {
    uint64_t bits;
    static_assert(sizeof(bits) == sizeof(d), "double must be 64-bit");
    std::memcpy(&bits, &d, sizeof d);
    return d > 0 ? bits : 0;
}

// Spreads the low 21 bits of v to every third bit.
inline uint64_t SpreadBits3(uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
}

// 63-bit Morton code of p quantised to 2^21 cells per axis of `b` (clamped).
inline uint64_t MortonKey(const Point3 &p, const Bounds3 &b) {
    uint64_t c[3];
    for (int a = 0; a < 3; ++a) {
        double lo = b.pMin[a], ext = b.pMax[a] - b.pMin[a];
        double f = ext > 0 ? (p[a] - lo) / ext : 0;
        f = std::isfinite(f) ? std::min(std::max(f, 0.0), 1.0) : 0;
        c[a] = uint64_t(f * double((1 << 21) - 1));
    }
    return (SpreadBits3(c[0]) << 2) | (SpreadBits3(c[1]) << 1) | SpreadBits3(c[2]);
}

// Sorts (key, index) pairs by key, ties in input order: with the input in
// increasing index order this is the total order of std::sort on the pairs
// (the reordering's), as an LSD radix sort on the key's bytes (a stable
// counting sort per byte; bytes equal in every key are skipped). tmp: scratch.
inline void RadixSortKeys(std::vector<std::pair<uint64_t, uint32_t>> &a,
                          std::vector<std::pair<uint64_t, uint32_t>> &tmp) {
    const size_t n = a.size();
    if (n < 2) return;
    uint32_t count[8][256] = {};
    for (const auto &e : a)
        for (int d = 0; d < 8; ++d) ++count[d][(e.first >> (8 * d)) & 0xff];
    tmp.resize(n);
    for (int d = 0; d < 8; ++d) {
        uint32_t *c = count[d];
        if (c[(a[0].first >> (8 * d)) & 0xff] == n) continue;  // every key has this byte
        uint32_t sum = 0;
        for (int b = 0; b < 256; ++b) {
            const uint32_t k = c[b];
            c[b] = sum;
            sum += k;
        }
        for (const auto &e : a) tmp[c[(e.first >> (8 * d)) & 0xff]++] = e;
        a.swap(tmp);
    }
}

// Generator g of the rank-1 lattice {(k/K, k g / K mod 1)}: coprime with K and
// close to K (sqrt(5) - 1) / 2 (the Fibonacci lattice when K is a Fibonacci number),
// so that the K points have exactly one point in each of the K column strata.
inline uint64_t LatticeGenerator(uint64_t K) {
    if (K <= 2) return 1;
    uint64_t g = uint64_t(std::llround(double(K) * 0.6180339887498949));
    g = std::max<uint64_t>(1, std::min(g, K - 1));
    while (std::gcd(g, K) != 1) ++g;
    return g;
}

// The column coordinate (Sec. 4.3: q = floor(L eps_2)) of the points of one
// (s, t) matrix in one iteration. The K = rows * m points have row coordinate
// (rank * m + c + 1/2) / K, i.e. each row (camera subpath, in reordered order)
// owns m consecutive row strata; their column coordinates are
//   Lattice: frac(((rank m + c) g mod K) / K + shift)   (Cranley-Patterson rotation of a rank-1 lattice)
//   LHS:     (c rows + perm_c(rank) + u) / K            (one point per column stratum, row's points in distinct 1/m bands)
//   Random:  u
// With `shift` and u uniform on [0, 1), the column coordinate is uniform on
// [0, 1) whatever the ordering: for every point (lattice, random), or for the
// mixture of a row's m points (LHS: point c is uniform on band c). So each
// column of the matrix is selected with probability 1 / (number of columns)
// on average over a row's points, which makes the estimator unbiased (mbdpt.cpp).
struct ColumnSampler {
    MatrixSampling mode = MatrixSampling::Lattice;
    uint64_t rows = 0;   // eligible rows of the matrix
    int m = 1;           // connections per row
    uint64_t g = 1;      // lattice generator for K = rows * m
    double shift = 0;    // lattice rotation, uniform per (iteration, s, t)
    uint64_t seed = 0;   // LHS permutations, per (iteration, s, t)

    double rowShift = 0; // participation rotation, uniform per (iteration, s, t)

    ColumnSampler() = default;
    ColumnSampler(MatrixSampling mode_, uint64_t rows_, int m_, double shift_, uint64_t seed_, double rowShift_ = 0)
        : mode(mode_), rows(rows_), m(m_), g(LatticeGenerator(std::max<uint64_t>(1, rows_ * uint64_t(m_)))),
          shift(shift_), seed(seed_), rowShift(rowShift_) {}

    // Whether the row with rank `rank` takes part (probability rho for every
    // row; about rho * rows rows do, evenly spread over the ranks): a randomly
    // rotated Weyl sequence with the plastic-number increment, independent of
    // the golden-ratio lattice of the columns.
    bool participates(uint64_t rank, double rho) const {
        double v = double(rank) * 0.7548776662466927 + rowShift;
        v -= std::floor(v);
        return v < rho;
    }

    // Column coordinate in [0, 1) of connection c of the row with rank `rank`;
    // `u` is a uniform value private to (row, c).
    double coordinate(uint64_t rank, int c, double u) const {
        const uint64_t K = rows * uint64_t(m);
        double y;
        switch (mode) {
        case MatrixSampling::Lattice: {
            // Rotation by shift = (a + b) / K, a integer, b in [0, 1): stratum (k g + a) mod K, offset b.
            uint64_t k = rank * uint64_t(m) + uint64_t(c);
            double sk = shift * double(K), a = std::floor(sk);
            const uint64_t kk = k < K ? k : k % K;  // k < K for every row rank: one division saved
            y = (double((kk * g + uint64_t(a)) % K) + (sk - a)) / double(K);
            break;
        }
        case MatrixSampling::LHS: {
            uint64_t stratum = uint64_t(c) * rows +
                               PermutationElement(uint32_t(rank), uint32_t(rows), Hash(seed, uint64_t(c)));
            y = (double(stratum) + u) / double(K);
            break;
        }
        default: y = u; break;
        }
        return y < OneMinusEpsilon ? y : OneMinusEpsilon;
    }
    // Column index in [0, cols).
    static uint64_t Column(double y, uint64_t cols) {
        uint64_t q = uint64_t(y * double(cols));
        return q < cols ? q : cols - 1;
    }
};

}  // namespace gradus::mbdpt
