// pbrt-v3 sphere (radius, zmin, zmax, phimax), intersected analytically in
// double precision in object space.
#pragma once
#include "shapes/shape.h"

namespace gradus {

class Sphere : public Shape {
  public:
    Sphere(const Transform &worldFromObject, bool reverseOrientation, Float radius, Float zMin, Float zMax,
           Float phiMaxDeg);
    Float area() const override;
    Bounds3 worldBound() const override;
    Bounds3 objectBound() const;
    Interaction sampleArea(Point2 u, Float *pdf) const override;
    Interaction sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const override;
    Float pdfFrom(const Interaction &ref, const Vec3 &wi) const override;
    bool intersectP(const Ray &r, Float *tHit, Interaction *hit) const override;
    // Object-space ray test; returns the nearest valid t in (tMin, r.tMax).
    bool intersectObject(const Ray &objRay, Float tMin, Float *tHit) const;
    // Full surface interaction for a world ray hitting at tHit.
    void interaction(const Ray &worldRay, Float tHit, SurfaceInteraction *si) const;
    bool isFull() const { return full_; }

  private:
    Normal3 orientNormal(const Normal3 &nWorld) const { return flip_ ? -nWorld : nWorld; }
    Transform worldFromObject_, objectFromWorld_;
    bool reverseOrientation_, flip_;
    Float radius_, zMin_, zMax_, thetaZMin_, thetaZMax_, phiMax_;
    bool full_;
};

}  // namespace gradus
