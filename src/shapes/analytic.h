// Analytic (quadric) shapes: intersected in double precision in object space
// and attached to Embree as user geometry. The base class turns a shape's
// object-space parameterisation (point, uv, first and second derivatives) into
// world-space interactions with pbrt-v3 normal orientation:
//   n = normalize(Cross(dpdu, dpdv)) in object space, carried to world space as
//   a normal, and flipped when ReverseOrientation XOR the transform swaps
//   handedness.
// Area sampling is uniform in object-space area; its pdf is converted to
// world-space area per point (exact under any affine transform).
#pragma once
#include "shapes/shape.h"

namespace gradus {

class AnalyticShape : public Shape {
  public:
    AnalyticShape(const Transform &worldFromObject, bool reverseOrientation);

    virtual Bounds3 objectBound() const = 0;
    // Surface area in object space.
    virtual Float objectArea() const = 0;
    // Object-space ray test: nearest t in (tMin, objRay.tMax) on the surface.
    virtual bool intersectObject(const Ray &objRay, Float tMin, Float *tHit) const = 0;

    // World-space area: exact for similarity transforms (object area times the
    // squared scale), an approximation under non-uniform scaling.
    Float area() const override { return objectArea() * areaScale_; }
    Bounds3 worldBound() const override { return worldFromObject_.applyBounds(objectBound()); }
    Interaction sampleArea(Point2 u, Float *pdf) const override;
    Float pdfArea(const Interaction &it) const override;
    bool intersectP(const Ray &r, Float *tHit, Interaction *hit) const override;
    // Full surface interaction for a world ray that hits at tHit.
    void interaction(const Ray &worldRay, Float tHit, SurfaceInteraction *si) const;

    const Transform &worldFromObject() const { return worldFromObject_; }
    bool flipsNormal() const { return flip_; }

  protected:
    struct Patch {
        Point3 p;  // point on the surface (reprojected)
        Point2 uv;
        Vec3 dpdu, dpdv, d2pduu, d2pduv, d2pdvv;
    };
    // Differential geometry at the surface point nearest to pObj.
    virtual Patch patch(const Point3 &pObj) const = 0;
    // Object-space point uniformly distributed by object-space area.
    virtual Point3 sampleObjectPoint(Point2 u) const = 0;
    // Oriented world normal for a patch.
    Normal3 worldNormal(const Patch &pt) const;
    // Object-to-world area ratio at a patch (Nanson: |det L| |L^-T n|).
    Float areaRatio(const Patch &pt) const;
    // Keeps phi in [0, 2 pi).
    static Float PhiOf(Float x, Float y) {
        Float phi = std::atan2(y, x);
        return phi < 0 ? phi + 2 * Pi : phi;
    }

    Transform worldFromObject_, objectFromWorld_;
    bool reverseOrientation_, flip_;
    Float detLinear_, areaScale_;
};

// Real roots t0 <= t1 of a t^2 + b t + c = 0 in double precision (linear when
// a == 0, then t0 == t1). Returns false when there is none.
bool SolveQuadratic(Float a, Float b, Float c, Float *t0, Float *t1);

}  // namespace gradus
