// Shapes: geometry that Embree intersects, refined in double precision, and
// that area lights sample.
#pragma once
#include <memory>
#include <vector>

#include "core/transform.h"
#include "core/interaction.h"

namespace gradus {

// One primitive that can carry an area light (a triangle, a sphere, ...).
class Shape {
  public:
    virtual ~Shape() = default;
    virtual Float area() const = 0;
    virtual Bounds3 worldBound() const = 0;
    // Uniform point on the surface; *pdf is w.r.t. area.
    virtual Interaction sampleArea(Point2 u, Float *pdf) const = 0;
    // Area density of sampleArea() at a surface point (1 / area unless the
    // world transform scales non-uniformly).
    virtual Float pdfArea(const Interaction &it) const {
        Float a = area();
        return a > 0 ? 1 / a : 0;
    }
    // Point as seen from `ref`; *pdf is w.r.t. solid angle at ref (0 on failure).
    virtual Interaction sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const;
    // Solid-angle pdf of sampleFrom() producing direction wi from ref.
    virtual Float pdfFrom(const Interaction &ref, const Vec3 &wi) const;
    // Intersects a ray with this single shape (used by pdfFrom); world space.
    virtual bool intersectP(const Ray &r, Float *tHit, Interaction *hit) const = 0;
};

}  // namespace gradus
