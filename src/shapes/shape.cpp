#include "shapes/shape.h"

namespace gradus {

Interaction Shape::sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const {
    Interaction it = sampleArea(u, pdf);
    Vec3 wi = it.p - ref.p;
    Float d2 = wi.lengthSquared();
    if (d2 == 0) { *pdf = 0; return it; }
    wi = wi / std::sqrt(d2);
    Float cosL = AbsDot(it.n, -wi);
    if (cosL == 0) { *pdf = 0; return it; }
    *pdf *= d2 / cosL;  // area -> solid angle
    if (!std::isfinite(*pdf)) *pdf = 0;
    return it;
}

Float Shape::pdfFrom(const Interaction &ref, const Vec3 &wi) const {
    Ray ray = ref.spawnRay(wi);
    Float tHit;
    Interaction hit;
    if (!intersectP(ray, &tHit, &hit)) return 0;
    Float cosL = AbsDot(hit.n, -wi);
    if (cosL == 0) return 0;
    Float pdf = DistanceSquared(ref.p, hit.p) * pdfArea(hit) / cosL;
    return std::isfinite(pdf) ? pdf : 0;
}

}  // namespace gradus
