// pbrt-v3 sphere (radius, zmin, zmax, phimax), intersected analytically in
// double precision in object space. Full spheres seen from outside under a
// uniform scale are sampled by the cone of directions they subtend.
#pragma once
#include "shapes/analytic.h"

namespace gradus {

class Sphere : public AnalyticShape {
  public:
    Sphere(const Transform &worldFromObject, bool reverseOrientation, Float radius, Float zMin, Float zMax,
           Float phiMaxDeg);
    Float objectArea() const override;
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &objRay, Float tMin, Float *tHit) const override;
    Interaction sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const override;
    Float pdfFrom(const Interaction &ref, const Vec3 &wi) const override;
    bool isFull() const { return full_; }

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    // World centre and radius when cone sampling applies (full sphere, uniform scale).
    bool coneSamplable(Point3 *center, Float *radius) const;
    Float radius_, zMin_, zMax_, thetaZMin_, thetaZMax_, phiMax_;
    bool full_;
};

}  // namespace gradus
