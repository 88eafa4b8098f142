#include "integrators/common/photon_grid.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "core/error.h"

namespace gradus {

void PhotonGrid::build(size_t numPoints, std::function<Point3(size_t)> positionFn, Float radius,
                       const ParallelFor &pf) {
    position_ = std::move(positionFn);
    const std::function<Point3(size_t)> &position = position_;
    GRADUS_CHECK(radius > 0 && numPoints < (uint64_t(1) << 32));
    radius_ = radius;
    r2_ = radius * radius;
    invCell_ = 1 / (2 * radius);
    const int64_t n = int64_t(numPoints);
    uint64_t tableSize = 1;
    while (tableSize < uint64_t(std::max<int64_t>(n, 1))) tableSize <<= 1;
    mask_ = tableSize - 1;
    // Counting sort: bucket of every point, counts, exclusive prefix sums, scatter.
    std::vector<uint32_t> bucketOf(static_cast<size_t>(n));
    std::unique_ptr<std::atomic<uint32_t>[]> count(new std::atomic<uint32_t>[tableSize + 1]);
    pf(int64_t(tableSize) + 1, 1 << 16, [&](int64_t b0, int64_t b1) {
        for (int64_t b = b0; b < b1; ++b) count[b].store(0, std::memory_order_relaxed);
    });
    pf(n, 4096, [&](int64_t i0, int64_t i1) {
        for (int64_t i = i0; i < i1; ++i) {
            const Point3 p = position(size_t(i));
            const Float fx = std::floor(p.x * invCell_), fy = std::floor(p.y * invCell_), fz = std::floor(p.z * invCell_);
            // Points beyond +-4e18 cells (|p| > 8e18 r) cannot be queried; they go to bucket 0 and are never near.
            const bool ok = std::abs(fx) < 4e18 && std::abs(fy) < 4e18 && std::abs(fz) < 4e18;
            bucketOf[i] = ok ? bucket(int64_t(fx), int64_t(fy), int64_t(fz)) : 0;
            count[bucketOf[i]].fetch_add(1, std::memory_order_relaxed);
        }
    });
    start_.assign(tableSize + 1, 0);
    uint32_t sum = 0;
    for (uint64_t b = 0; b < tableSize; ++b) {
        start_[b] = sum;
        sum += count[b].load(std::memory_order_relaxed);
        count[b].store(start_[b], std::memory_order_relaxed);  // next free slot
    }
    start_[tableSize] = sum;
    index_.assign(size_t(n), 0);
    pf(n, 4096, [&](int64_t i0, int64_t i1) {
        for (int64_t i = i0; i < i1; ++i) index_[count[bucketOf[i]].fetch_add(1, std::memory_order_relaxed)] = uint32_t(i);
    });
    // The scatter order depends on the threads: sort each bucket by index.
    pf(int64_t(tableSize), 4096, [&](int64_t b0, int64_t b1) {
        for (int64_t b = b0; b < b1; ++b) std::sort(index_.begin() + start_[b], index_.begin() + start_[b + 1]);
    });
    points_.resize(size_t(n));
    // margin_: |float(x) - x| <= 2^-24 |x| per coordinate, so a point lies within
    // 2^-23 max|coordinate| of its float position (an infinite bound accepts all).
    std::atomic<uint64_t> maxBits{0};  // the largest |coordinate| (non-negative doubles order as their bits)
    pf(n, 4096, [&](int64_t k0, int64_t k1) {
        double m = 0;
        for (int64_t k = k0; k < k1; ++k) {
            const Point3 p = position(index_[k]);
            points_[k] = {float(p.x), float(p.y), float(p.z)};
            for (double c : {p.x, p.y, p.z}) m = std::max(m, std::abs(c));  // NaN: ignored (never found)
        }
        uint64_t bits;
        std::memcpy(&bits, &m, 8);
        for (uint64_t cur = maxBits.load(); bits > cur && !maxBits.compare_exchange_weak(cur, bits);) {
        }
    });
    double maxAbs;
    const uint64_t bits = maxBits.load();
    std::memcpy(&maxAbs, &bits, 8);
    margin_ = Float(std::ldexp(maxAbs, -23));
    if (!(maxAbs < 1e38)) {  // beyond the float range: no rejection, every point is tested exactly
        margin_ = std::numeric_limits<Float>::infinity();
        std::fill(points_.begin(), points_.end(), Point3f{0, 0, 0});
    }
}

}  // namespace gradus
