// pbrt-v3's other quadrics: disk, cylinder, cone, paraboloid, hyperboloid.
// Parameters and (u, v) parameterisations follow pbrt-v3; phimax in degrees.
// Area sampling is uniform in area for all of them (pbrt-v3 samples only the
// full disk and leaves cone, paraboloid and hyperboloid unsampled).
#pragma once
#include <vector>

#include "shapes/analytic.h"

namespace gradus {

// Annulus z = height, innerRadius <= rho <= radius, 0 <= phi <= phimax; n = +z.
class Disk : public AnalyticShape {
  public:
    Disk(const Transform &w, bool ro, Float height, Float radius, Float innerRadius, Float phiMaxDeg);
    Float objectArea() const override;
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &r, Float tMin, Float *tHit) const override;

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    Float height_, radius_, innerRadius_, phiMax_;
};

// rho = radius, zmin <= z <= zmax; normal away from the axis.
class Cylinder : public AnalyticShape {
  public:
    Cylinder(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg);
    Float objectArea() const override;
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &r, Float tMin, Float *tHit) const override;

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    Float radius_, zMin_, zMax_, phiMax_;
};

// Apex at (0, 0, height), base circle of `radius` at z = 0.
class Cone : public AnalyticShape {
  public:
    Cone(const Transform &w, bool ro, Float height, Float radius, Float phiMaxDeg);
    Float objectArea() const override;
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &r, Float tMin, Float *tHit) const override;

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    Float height_, radius_, phiMax_;
};

// z = zmax rho^2 / radius^2 clipped to zmin <= z <= zmax.
class Paraboloid : public AnalyticShape {
  public:
    Paraboloid(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg);
    Float objectArea() const override;
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &r, Float tMin, Float *tHit) const override;

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    Float radius_, zMin_, zMax_, phiMax_, k_;
};

// The segment p1-p2 swept around the z axis by phimax (requires p1.z != p2.z;
// a horizontal segment is an annulus: use a disk). v runs from p1 to p2.
class Hyperboloid : public AnalyticShape {
  public:
    Hyperboloid(const Transform &w, bool ro, const Point3 &p1, const Point3 &p2, Float phiMaxDeg);
    Float objectArea() const override { return area_; }
    Bounds3 objectBound() const override;
    bool intersectObject(const Ray &r, Float tMin, Float *tHit) const override;

  protected:
    Patch patch(const Point3 &pObj) const override;
    Point3 sampleObjectPoint(Point2 u) const override;

  private:
    // Area per unit phi and unit v at v = s.
    Float density(Float s) const;
    Point3 p1_;
    Vec3 d_;
    Float alpha_, beta_, gamma_, phiMax_, area_;
    std::vector<Float> g_, cdf_;  // density at table nodes, cumulative (piecewise linear)
};

}  // namespace gradus
