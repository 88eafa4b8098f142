// pbrt-v3's "curve" shape, traced by Embree 3's curve primitives.
//
// Every segment is a cubic Bezier in world space (degree-2 and B-spline input
// converted by blossoming, as pbrt-v3 does) with a radius linear in u from
// width0/2 to width1/2. Embree geometry per type:
//   cylinder -> RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE: a real tube, Embree 3.13's
//               sweep of circles normal to the axis, open at both ends (no
//               swept-sphere caps). pbrt-v3 instead intersects a ray-facing ribbon
//               and only bends the normal as on a cylinder: its hit points lie in
//               the axis plane, ours up to r closer to the viewer,
//   flat     -> RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE (ray-facing quads, tessellated),
//   ribbon   -> RTC_GEOMETRY_TYPE_NORMAL_ORIENTED_BEZIER_CURVE (normal spline from
//               pbrt-v3's slerp between the segment's end normals, sampled at
//               u = 0, 1/3, 2/3, 1 as Bezier control normals: approximate).
// Hits on a tube from its inside are ignored (Embree filter functions): a ray
// leaving a fibre inwards (hair's transmission lobes) passes through it, as it
// passes through pbrt-v3's ribbon; the hair BSDF accounts for the inside path.
//
// Interaction (shared by the ray hit and by rebuilding a vertex from its point):
// u = segment parameter of the closest point on the axis, dpdu along the curve,
// n = outward tube normal (cylinder), the direction to the viewer projected
// normal to the curve (flat), the interpolated ribbon normal (ribbon); dpdv =
// 2 r (n x dpdu)/|.|, dndv = dpdv / r on tubes (0 otherwise); v = (1 + h)/2 with h the signed offset of the hit from the
// axis across the ray, in units of r: h = ((p - c(u)) . (wo x T)/|wo x T|) / r,
// sin(gamma_o) of Chiang et al. 2016 on a tube; hair reads h = -1 + 2 v as in
// pbrt-v3. (Its sign makes R reflect to phi = -2 gamma_o in the BSDF frame.)
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
        Point3 cp[4];    // world-space Bezier control points (float-rounded: what Embree traces)
        Float r0, r1;    // radius at u = 0 and 1 (linear in between)
        Normal3 n0, n1;  // ribbon: unit normals at u = 0 and 1
    };
    CurveShape(CurveType type, std::vector<Segment> segments, bool reverseOrientation);

    CurveType type() const { return type_; }
    const std::vector<Segment> &segments() const { return segs_; }
    int numSegments() const { return int(segs_.size()); }
    Bounds3 worldBound() const;

    Point3 point(int seg, Float u, Vec3 *dpdu = nullptr) const;
    Float radius(int seg, Float u) const { return Lerp(u, segs_[seg].r0, segs_[seg].r1); }
    Normal3 ribbonNormal(int seg, Float u) const;  // slerp of n0, n1
    // Axis parameter closest to p (Newton from uHint; uHint < 0: from a coarse search).
    Float closestU(int seg, const Point3 &p, Float uHint) const;
    // Fills si for a point p on segment seg seen from direction wo (unit). For
    // the cylinder type p is moved onto the tube (double precision).
    void interaction(int seg, Float uHint, const Point3 &p, const Vec3 &wo, SurfaceInteraction *si) const;

  private:
    CurveType type_;
    std::vector<Segment> segs_;
    bool reverseOrientation_;
};

// Shape "curve": pbrt-v3's parameters (P, basis bezier|bspline, degree 2|3, type
// flat|cylinder|ribbon (default flat), width / width0 / width1, N for ribbons,
// splitdepth accepted and unused). Bad input throws a located Error.
std::shared_ptr<CurveShape> CreateCurveShape(const ParamSet &ps, const Transform &worldFromObject,
                                             bool reverseOrientation, const FileLoc &loc);

}  // namespace gradus
