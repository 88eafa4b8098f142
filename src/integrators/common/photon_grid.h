// Hash grid for fixed-radius queries over the light vertices of a VCM
// iteration (vertex merging). Cells are cubes of side 2r addressed by
// floor(p / 2r), hashed into a table of the next power of two >= the number of
// points; the grid is unbounded (no bounding box to grow), so points anywhere
// are found. A query visits the (at most) 8 buckets of the cells that the
// ball of radius r around the query point overlaps, each bucket once.
// Built by a counting sort; each bucket lists its points by increasing index,
// so queries visit them in an order that does not depend on the thread count.
#pragma once
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
    void build(size_t n, const std::function<Point3(size_t)> &position, Float radius, const ParallelFor &pf);
    // Calls fn(index, squared distance) for every point closer than the radius to p.
    template <typename Fn>
    void query(const Point3 &p, Fn &&fn) const;

    Float radius() const { return radius_; }
    size_t size() const { return points_.size(); }
    size_t bytes() const { return points_.capacity() * sizeof(Point3) + start_.capacity() * 4 + index_.capacity() * 4; }

  private:
    uint32_t bucket(int64_t x, int64_t y, int64_t z) const {
        uint64_t h = uint64_t(x) * 73856093u ^ uint64_t(y) * 19349663u ^ uint64_t(z) * 83492791u;
        h ^= h >> 29;
        h *= 0xbf58476d1ce4e5b9ULL;
        h ^= h >> 32;
        return uint32_t(h & mask_);
    }
    Float radius_ = 0, r2_ = 0, invCell_ = 0;
    uint64_t mask_ = 0;
    std::vector<uint32_t> start_;  // bucket b: index_[start_[b], start_[b+1])
    std::vector<uint32_t> index_;  // point indices, bucket by bucket, increasing within a bucket
    std::vector<Point3> points_;   // positions in index_ order (locality of queries)
};

template <typename Fn>
void PhotonGrid::query(const Point3 &p, Fn &&fn) const {
    if (points_.empty()) return;
    const Float cx = p.x * invCell_, cy = p.y * invCell_, cz = p.z * invCell_;
    const Float fx = std::floor(cx), fy = std::floor(cy), fz = std::floor(cz);
    if (!(std::abs(fx) < 4e18 && std::abs(fy) < 4e18 && std::abs(fz) < 4e18)) return;
    const int64_t ix = int64_t(fx), iy = int64_t(fy), iz = int64_t(fz);
    // The ball (radius r = half a cell) reaches into the neighbour on the nearer side only.
    const int64_t dx = cx - fx < 0.5 ? -1 : 1, dy = cy - fy < 0.5 ? -1 : 1, dz = cz - fz < 0.5 ? -1 : 1;
    uint32_t seen[8];
    int nSeen = 0;
    for (int c = 0; c < 8; ++c) {
        const uint32_t b = bucket(ix + (c & 1 ? dx : 0), iy + (c & 2 ? dy : 0), iz + (c & 4 ? dz : 0));
        bool dup = false;
        for (int k = 0; k < nSeen; ++k) dup |= seen[k] == b;
        if (dup) continue;
        seen[nSeen++] = b;
        for (uint32_t k = start_[b]; k < start_[b + 1]; ++k) {
            const Float d2 = (points_[k] - p).lengthSquared();
            if (d2 < r2_) fn(index_[k], d2);
        }
    }
}

}  // namespace gradus
