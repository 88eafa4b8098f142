// pbrt-v3's "curve" shape with pbrt-v3's intersection semantics (PBR3 Sec. 3.7,
// pbrt-v3's Curve::Intersect and recursiveIntersect), as Embree user geometry.
//
// Every segment is a cubic Bezier in world space (degree-2 and B-spline input
// converted by blossoming, as pbrt-v3 does) with a width linear in u from its
// width0 to its width1, split into 2^splitdepth pieces (pbrt-v3's separate
// shapes; one Embree primitive each). A ray hits a piece as pbrt-v3 decides, for
// every type: in a frame where the ray runs along z, the piece is refined into
// 2^d sub-pieces (d from the piece's flatness, 0..10) and each is treated as
// its chord: the ray's projection on the chord gives w, the point c(w) of the
// sub-piece at that parameter must lie within width(u)/2 of the ray (ribbon:
// width scaled by |n . d|) and ahead of it, beyond the perpendiculars at the
// sub-piece's ends. Where the Bezier parameter is uneven along the curve, c(w)
// is not the nearest point, and fibres come out narrower than a tube would;
// the hit lies on the ray at the depth of c(w) (a ribbon through the axis that
// faces the ray), also for "cylinder", whose normal only turns across the width.
//
// Interaction: u from w (the segment's parameter), v = 1/2 +- |c(w) - ray| /
// width, greater than 1/2 on the side of d x dpdu (d the ray's direction; hair
// reads h = -1 + 2 v, as pbrt-v3); dpdu the segment's derivative at u; dpdv of
// length width, along d x dpdu (flat), rotated about dpdu by -90 (2 v - 1)
// degrees (cylinder), or n(u) x dpdu (ribbon); n = dpdu x dpdv normalised
// (negated for ReverseOrientation or a handedness-swapping transform); no
// normal derivatives. pbrt-v3 bounds the hit's error by 2 width in every axis,
// so rays leaving a curve start sum_i |n_i| 2 width off it along +-n
// (Interaction::spawnOffset): they pass over fibres that near.
//
// Differences kept: the geometry is transformed to world space first (pbrt-v3
// intersects in object space; the same for rigid transforms with uniform
// scale), with the width scaled by the transform's mean linear scale.
#pragma once
#include <memory>
#include <vector>

#include "core/interaction.h"
#include "core/transform.h"
#include "parser/paramset.h"

namespace gradus {

enum class CurveType { Flat, Cylinder, Ribbon };

class CurveShape {
  public:
    struct Segment {
        Point3 cp[4];    // world-space Bezier control points
        Float w0, w1;    // width at u = 0 and 1 (linear in between)
        Normal3 n0, n1;  // ribbon: unit normals at u = 0 and 1
    };
    // flipNormal: ReverseOrientation xor a transform that swaps handedness.
    // errorScale: sum_j |m_ij| of the object-to-world matrix over its mean scale
    // (pbrt-v3 transforms its object-space error bound by |M|); 1 for rigid ones.
    CurveShape(CurveType type, std::vector<Segment> segments, bool flipNormal, int splitDepth = 3,
               Vec3 errorScale = Vec3(1, 1, 1));

    CurveType type() const { return type_; }
    const std::vector<Segment> &segments() const { return segs_; }
    int numSegments() const { return int(segs_.size()); }
    int splitDepth() const { return splitDepth_; }
    int numPieces() const { return int(segs_.size()) << splitDepth_; }
    int segmentOf(int piece) const { return piece >> splitDepth_; }
    Bounds3 worldBound() const;
    Bounds3 pieceBound(int piece) const;  // pbrt-v3's Curve::ObjectBound

    Point3 point(int seg, Float u, Vec3 *dpdu = nullptr) const;
    Float width(int seg, Float u) const { return Lerp(u, segs_[seg].w0, segs_[seg].w1); }
    // pbrt-v3's (unnormalised) interpolation of the end normals.
    Vec3 ribbonNormal(int seg, Float u) const;

    // pbrt-v3's test of a ray against one piece: t in units of ray.d (within
    // (0, ray.tMax]), the segment's u and v. Double precision.
    bool intersect(int piece, const Ray &ray, Float *t, Float *u, Float *v) const;
    // The interaction at a hit (u, v from intersect) at p, seen along -wo (wo unit).
    void interaction(int piece, Float u, Float v, const Point3 &p, const Vec3 &wo, SurfaceInteraction *si) const;
    // The same from the point alone (bidirectional vertices): u and v of the
    // line through p along wo, as its hit would have them.
    void interaction(int piece, const Point3 &p, const Vec3 &wo, SurfaceInteraction *si) const;

  private:
    bool recursiveIntersect(int seg, const Point3 cp[4], const Vec3 &dir, Float zMax, Float u0, Float u1, int depth,
                            Float *z, Float *u, Float *v) const;
    CurveType type_;
    std::vector<Segment> segs_;
    bool flip_;
    int splitDepth_;
    Vec3 errorScale_;
};

// Shape "curve": pbrt-v3's parameters (P, basis bezier|bspline, degree 2|3, type
// flat|cylinder|ribbon (default flat), width / width0 / width1, N for ribbons,
// splitdepth 0..10 (default 3)). Bad input throws a located Error.
std::shared_ptr<CurveShape> CreateCurveShape(const ParamSet &ps, const Transform &worldFromObject,
                                             bool reverseOrientation, const FileLoc &loc);

}  // namespace gradus
