// Hash grid for fixed-radius queries over the light vertices of a VCM
// iteration (vertex merging). Cells are cubes of side 2r addressed by
// floor(p / 2r), hashed into a table of the next power of two >= the number of
// points; the grid is unbounded (no bounding box to grow), so points anywhere
// are found. A query visits the (at most) 8 buckets of the cells that the
// ball of radius r around the query point overlaps, each bucket once
// (27 for the larger radii of a varying kernel).
// Built by a counting sort; each bucket lists its points by increasing index,
// so queries visit them in an order that does not depend on the thread count.
// The grid keeps the points' positions as floats (12 bytes a point, in bucket
// order) to reject far points, and reads the exact position through the
// position function for the others: the points found and their distances are
// those of the exact positions. The position function (and what it reads)
// must stay valid and unchanged while the grid is queried.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/geometry.h"

namespace gradus {

class PhotonGrid {
  public:
    // fn(begin, end) over fixed ranges of [0, n); may run ranges in parallel.
    using ParallelFor = std::function<void(int64_t n, int64_t grain, const std::function<void(int64_t, int64_t)> &)>;
    // Indexes the points position(0..n) for queries of radius `radius` (> 0).
    void build(size_t n, std::function<Point3(size_t)> position, Float radius, const ParallelFor &pf);
    // Calls fn(index, squared distance) for every point closer than the radius to p.
    template <typename Fn>
    void query(const Point3 &p, Fn &&fn) const {
        query(p, radius_, fn);
    }
    // The same for a radius r <= 2 radius() (a kernel that varies per query,
    // merge_kernel.h): up to 27 cells when r > radius().
    template <typename Fn>
    void query(const Point3 &p, Float r, Fn &&fn) const;

    Float radius() const { return radius_; }
    size_t size() const { return points_.size(); }
    size_t bytes() const { return points_.capacity() * sizeof(Point3f) + start_.capacity() * 4 + index_.capacity() * 4; }

  private:
    uint32_t bucket(int64_t x, int64_t y, int64_t z) const {
        uint64_t h = uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u ^ uint64_t(z) * 83492791u;
        h ^= h >> 29;
        h *= 0xbf58476d1ce4e5b9ULL;
        h ^= h >> 32;
        return uint32_t(h & mask_);
    }
    struct Point3f {
        float x, y, z;
    };
    Float radius_ = 0, r2_ = 0, invCell_ = 0;
    Float margin_ = 0;  // bounds the distance between a point and its float position
    uint64_t mask_ = 0;
    std::vector<uint32_t> start_;  // bucket b: index_[start_[b], start_[b+1])
    std::vector<uint32_t> index_;  // point indices, bucket by bucket, increasing within a bucket
    std::vector<Point3f> points_;  // float positions in index_ order (locality of queries)
    std::function<Point3(size_t)> position_;  // exact positions
};

template <typename Fn>
void PhotonGrid::query(const Point3 &p, Float r, Fn &&fn) const {
    if (points_.empty() || !(r > 0)) return;
    r = std::min(r, 2 * radius_);
    const Float r2 = r * r;
    // Float positions within margin_ of the exact ones: a point closer than r
    // is closer than rf to its float position (relative slack for rounding).
    const Float rf = r * (1 + 1e-9) + margin_, rf2 = rf * rf;
    // Cells overlapped by the ball's bounding box: at most 2 per axis for
    // r <= radius (half a cell), 3 for r <= 2 radius.
    const Float inv = invCell_;
    const Float lo[3] = {std::floor((p.x - r) * inv), std::floor((p.y - r) * inv), std::floor((p.z - r) * inv)};
    const Float hi[3] = {std::floor((p.x + r) * inv), std::floor((p.y + r) * inv), std::floor((p.z + r) * inv)};
    for (int a = 0; a < 3; ++a)
        if (!(std::abs(lo[a]) < 4e18 && std::abs(hi[a]) < 4e18)) return;
    uint32_t seen[27];
    int nSeen = 0;
    for (int64_t z = int64_t(lo[2]); z <= int64_t(hi[2]); ++z)
        for (int64_t y = int64_t(lo[1]); y <= int64_t(hi[1]); ++y)
            for (int64_t x = int64_t(lo[0]); x <= int64_t(hi[0]); ++x) {
                const uint32_t b = bucket(x, y, z);
                bool dup = false;
                for (int k = 0; k < nSeen; ++k) dup |= seen[k] == b;
                if (dup) continue;
                seen[nSeen++] = b;
                for (uint32_t k = start_[b]; k < start_[b + 1]; ++k) {
                    const Point3f &q = points_[k];
                    const Float dx = Float(q.x) - p.x, dy = Float(q.y) - p.y, dz = Float(q.z) - p.z;
                    if (!(dx * dx + dy * dy + dz * dz < rf2)) continue;
                    const Float d2 = (position_(index_[k]) - p).lengthSquared();
                    if (d2 < r2) fn(index_[k], d2);
                }
            }
}

}  // namespace gradus
