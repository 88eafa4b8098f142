#include "shapes/sphere.h"

#include "core/error.h"
#include "samplers/sampling.h"

namespace gradus {

Sphere::Sphere(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg)
    : worldFromObject_(w), objectFromWorld_(w.inverse()), reverseOrientation_(ro) {
    flip_ = ro ^ w.swapsHandedness();
    radius_ = radius;
    zMin_ = Clamp(std::min(zMin, zMax), -radius, radius);
    zMax_ = Clamp(std::max(zMin, zMax), -radius, radius);
    thetaZMin_ = std::acos(Clamp<Float>(zMin_ / radius, -1, 1));
    thetaZMax_ = std::acos(Clamp<Float>(zMax_ / radius, -1, 1));
    phiMax_ = Radians(Clamp<Float>(phiMaxDeg, 0, 360));
    full_ = zMin_ <= -radius && zMax_ >= radius && phiMax_ >= 2 * Pi;
}

Float Sphere::area() const { return phiMax_ * radius_ * (zMax_ - zMin_); }

Bounds3 Sphere::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, zMin_));
    b.expand(Point3(radius_, radius_, zMax_));
    return b;
}

Bounds3 Sphere::worldBound() const { return worldFromObject_.applyBounds(objectBound()); }

bool Sphere::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    // Quadratic a t^2 + b t + c = 0 in a numerically stable form.
    Float a = r.d.lengthSquared();
    Float b = 2 * Dot(r.d, r.o);
    Float c = r.o.lengthSquared() - radius_ * radius_;
    // Discriminant via the distance of the ray to the centre (more robust than b^2-4ac).
    Vec3 f = r.o - r.d * (Dot(r.o, r.d) / a);
    Float disc = 4 * a * (radius_ * radius_ - f.lengthSquared());
    if (disc < 0) return false;
    Float root = std::sqrt(disc);
    Float q = (b < 0) ? -0.5 * (b - root) : -0.5 * (b + root);
    Float t0 = q / a, t1 = c / q;
    if (q == 0) { t0 = t1 = 0; }
    if (t0 > t1) std::swap(t0, t1);
    for (Float t : {t0, t1}) {
        if (t <= tMin || t >= r.tMax) continue;
        Point3 p = r(t);
        if (full_) { *tHit = t; return true; }
        if (p.z < zMin_ || p.z > zMax_) continue;
        Float phi = std::atan2(p.y, p.x);
        if (phi < 0) phi += 2 * Pi;
        if (phi > phiMax_) continue;
        *tHit = t;
        return true;
    }
    return false;
}

void Sphere::interaction(const Ray &worldRay, Float tHit, SurfaceInteraction *si) const {
    Ray r = objectFromWorld_.applyRay(worldRay);
    Point3 p = r(tHit);
    p = p * (radius_ / p.length());  // reproject onto the surface
    if (p.x == 0 && p.y == 0) p.x = 1e-9 * radius_;
    Float phi = std::atan2(p.y, p.x);
    if (phi < 0) phi += 2 * Pi;
    Float u = phi / phiMax_;
    Float cosTheta = Clamp<Float>(p.z / radius_, -1, 1);
    Float theta = std::acos(cosTheta);
    Float v = (theta - thetaZMin_) / (thetaZMax_ - thetaZMin_);
    Float zRadius = std::sqrt(p.x * p.x + p.y * p.y);
    Float cosPhi = p.x / zRadius, sinPhi = p.y / zRadius;
    Vec3 dpdu(-phiMax_ * p.y, phiMax_ * p.x, 0);
    Float sinTheta = SafeSqrt(1 - cosTheta * cosTheta);
    Vec3 dpdv = Vec3(p.z * cosPhi, p.z * sinPhi, -radius_ * sinTheta) * (thetaZMax_ - thetaZMin_);
    // Normal derivatives via the Weingarten equations (sphere: dn = dp / r).
    Normal3 dndu = dpdu / radius_, dndv = dpdv / radius_;
    Point3 pw = worldFromObject_.applyPoint(p);
    Vec3 dpduW = worldFromObject_.applyVector(dpdu), dpdvW = worldFromObject_.applyVector(dpdv);
    Normal3 n = Normalize(Cross(dpduW, dpdvW));
    if (flip_) n = -n;
    si->p = pw;
    si->uv = Point2(u, v);
    si->wo = -Normalize(worldRay.d);
    si->n = n;
    si->dpdu = dpduW;
    si->dpdv = dpdvW;
    si->dndu = worldFromObject_.applyNormal(dndu);
    si->dndv = worldFromObject_.applyNormal(dndv);
    si->shading.n = n;
    si->shading.dpdu = dpduW;
    si->shading.dpdv = dpdvW;
    si->shading.dndu = si->dndu;
    si->shading.dndv = si->dndv;
}

Interaction Sphere::sampleArea(Point2 u, Float *pdf) const {
    // Uniform in z and phi is uniform in area on a sphere zone (Archimedes).
    Float z = Lerp(u.x, zMin_, zMax_);
    Float phi = u.y * phiMax_;
    Float rz = SafeSqrt(radius_ * radius_ - z * z);
    Point3 pObj(rz * std::cos(phi), rz * std::sin(phi), z);
    Interaction it;
    it.p = worldFromObject_.applyPoint(pObj);
    it.n = orientNormal(Normalize(worldFromObject_.applyNormal(pObj)));
    Float a = area();
    *pdf = a > 0 ? 1 / a : 0;
    return it;
}

Interaction Sphere::sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const {
    Point3 pCenter = worldFromObject_.applyPoint(Point3(0, 0, 0));
    // World-space radius (uniform scale assumed for cone sampling; otherwise area sampling).
    Float rw = worldFromObject_.applyVector(Vec3(radius_, 0, 0)).length();
    Float rw2 = worldFromObject_.applyVector(Vec3(0, radius_, 0)).length();
    Float rw3 = worldFromObject_.applyVector(Vec3(0, 0, radius_)).length();
    bool uniformScale = std::abs(rw - rw2) < 1e-9 * rw && std::abs(rw - rw3) < 1e-9 * rw;
    Float d2 = DistanceSquared(ref.p, pCenter);
    if (!full_ || !uniformScale || d2 <= rw * rw * 1.0001) return Shape::sampleFrom(ref, u, pdf);
    // Sample the cone of directions subtended by the sphere.
    Float dc = std::sqrt(d2);
    Vec3 wc = (pCenter - ref.p) / dc;
    Float sinThetaMax2 = rw * rw / d2;
    Float cosThetaMax = SafeSqrt(1 - sinThetaMax2);
    Frame frame(wc);
    Vec3 w = frame.toWorld(SampleUniformCone(u, cosThetaMax));
    // Nearest intersection of the sampled ray with the sphere (tangent point if grazing).
    Float b = Dot(ref.p - pCenter, w);
    Float c = d2 - rw * rw;
    Float disc = b * b - c;
    Float t = disc > 0 ? (-b - std::sqrt(disc)) : -b;
    if (t < 0) t = -b;
    Interaction it;
    Point3 p = ref.p + w * t;
    Vec3 nOut = Normalize(p - pCenter);
    it.p = pCenter + nOut * rw;
    it.n = flip_ ? -nOut : nOut;
    *pdf = UniformConePdf(cosThetaMax);
    return it;
}

Float Sphere::pdfFrom(const Interaction &ref, const Vec3 &wi) const {
    Point3 pCenter = worldFromObject_.applyPoint(Point3(0, 0, 0));
    Float rw = worldFromObject_.applyVector(Vec3(radius_, 0, 0)).length();
    Float rw2 = worldFromObject_.applyVector(Vec3(0, radius_, 0)).length();
    Float rw3 = worldFromObject_.applyVector(Vec3(0, 0, radius_)).length();
    bool uniformScale = std::abs(rw - rw2) < 1e-9 * rw && std::abs(rw - rw3) < 1e-9 * rw;
    Float d2 = DistanceSquared(ref.p, pCenter);
    if (!full_ || !uniformScale || d2 <= rw * rw * 1.0001) return Shape::pdfFrom(ref, wi);
    Float cosThetaMax = SafeSqrt(1 - rw * rw / d2);
    // Only directions inside the cone can be produced.
    if (Dot(Normalize(pCenter - ref.p), wi) < cosThetaMax) return 0;
    return UniformConePdf(cosThetaMax);
}

bool Sphere::intersectP(const Ray &r, Float *tHit, Interaction *hit) const {
    Ray ro = objectFromWorld_.applyRay(r);
    Float t;
    if (!intersectObject(ro, 0, &t)) return false;
    *tHit = t;
    Point3 p = ro(t);
    hit->p = worldFromObject_.applyPoint(p);
    hit->n = orientNormal(Normalize(worldFromObject_.applyNormal(p)));
    hit->wo = -r.d;
    return true;
}

}  // namespace gradus
