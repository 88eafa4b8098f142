#include "shapes/sphere.h"

#include "core/error.h"
#include "samplers/sampling.h"

namespace gradus {

Sphere::Sphere(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg)
    : AnalyticShape(w, ro) {
    radius_ = radius;
    zMin_ = Clamp(std::min(zMin, zMax), -radius, radius);
    zMax_ = Clamp(std::max(zMin, zMax), -radius, radius);
    thetaZMin_ = std::acos(Clamp<Float>(zMin_ / radius, -1, 1));
    thetaZMax_ = std::acos(Clamp<Float>(zMax_ / radius, -1, 1));
    phiMax_ = Radians(Clamp<Float>(phiMaxDeg, 0, 360));
    full_ = zMin_ <= -radius && zMax_ >= radius && phiMax_ >= 2 * Pi;
}

Float Sphere::objectArea() const { return phiMax_ * radius_ * (zMax_ - zMin_); }

Bounds3 Sphere::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, zMin_));
    b.expand(Point3(radius_, radius_, zMax_));
    return b;
}

bool Sphere::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    Float a = r.d.lengthSquared();
    if (!(a > 0)) return false;
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
        if (PhiOf(p.x, p.y) > phiMax_) continue;
        *tHit = t;
        return true;
    }
    return false;
}

AnalyticShape::Patch Sphere::patch(const Point3 &pObj) const {
    Patch pt;
    Float len = pObj.length();
    Point3 p = len > 0 ? pObj * (radius_ / len) : Point3(0, 0, radius_);  // reproject onto the surface
    if (p.x == 0 && p.y == 0) p.x = 1e-9 * radius_;
    Float phi = PhiOf(p.x, p.y);
    Float cosTheta = Clamp<Float>(p.z / radius_, -1, 1);
    Float theta = std::acos(cosTheta);
    Float dTheta = thetaZMax_ - thetaZMin_;
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? phi / phiMax_ : 0, dTheta != 0 ? (theta - thetaZMin_) / dTheta : 0);
    Float zRadius = std::sqrt(p.x * p.x + p.y * p.y);
    Float cosPhi = p.x / zRadius, sinPhi = p.y / zRadius;
    Float sinTheta = SafeSqrt(1 - cosTheta * cosTheta);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(p.z * cosPhi, p.z * sinPhi, -radius_ * sinTheta) * dTheta;
    pt.d2pduu = Vec3(p.x, p.y, 0) * (-phiMax_ * phiMax_);
    pt.d2pduv = Vec3(-sinPhi, cosPhi, 0) * (dTheta * p.z * phiMax_);
    pt.d2pdvv = Vec3(p.x, p.y, p.z) * (-dTheta * dTheta);
    return pt;
}

Point3 Sphere::sampleObjectPoint(Point2 u) const {
    // Uniform in z and phi is uniform in area on a sphere zone (Archimedes).
    Float z = Lerp(u.x, zMin_, zMax_);
    Float phi = u.y * phiMax_;
    Float rz = SafeSqrt(radius_ * radius_ - z * z);
    return Point3(rz * std::cos(phi), rz * std::sin(phi), z);
}

bool Sphere::coneSamplable(Point3 *center, Float *radius) const {
    if (!full_) return false;
    Float rw = worldFromObject_.applyVector(Vec3(radius_, 0, 0)).length();
    Float rw2 = worldFromObject_.applyVector(Vec3(0, radius_, 0)).length();
    Float rw3 = worldFromObject_.applyVector(Vec3(0, 0, radius_)).length();
    if (!(std::abs(rw - rw2) < 1e-9 * rw && std::abs(rw - rw3) < 1e-9 * rw)) return false;
    *center = worldFromObject_.applyPoint(Point3(0, 0, 0));
    *radius = rw;
    return true;
}

Interaction Sphere::sampleFrom(const Interaction &ref, Point2 u, Float *pdf) const {
    Point3 pCenter;
    Float rw;
    if (!coneSamplable(&pCenter, &rw)) return Shape::sampleFrom(ref, u, pdf);
    Float d2 = DistanceSquared(ref.p, pCenter);
    if (d2 <= rw * rw * 1.0001) return Shape::sampleFrom(ref, u, pdf);
    // Sample the cone of directions subtended by the sphere.
    Float dc = std::sqrt(d2);
    Vec3 wc = (pCenter - ref.p) / dc;
    Float cosThetaMax = SafeSqrt(1 - rw * rw / d2);
    Frame frame(wc);
    Vec3 w = frame.toWorld(SampleUniformCone(u, cosThetaMax));
    // Nearest intersection of the sampled ray with the sphere (tangent point if grazing).
    Float b = Dot(ref.p - pCenter, w);
    Float c = d2 - rw * rw;
    Float disc = b * b - c;
    Float t = disc > 0 ? (-b - std::sqrt(disc)) : -b;
    if (t < 0) t = -b;
    Interaction it;
    Vec3 nOut = Normalize(ref.p + w * t - pCenter);
    it.p = pCenter + nOut * rw;
    it.n = flip_ ? -nOut : nOut;
    *pdf = UniformConePdf(cosThetaMax);
    return it;
}

Float Sphere::pdfFrom(const Interaction &ref, const Vec3 &wi) const {
    Point3 pCenter;
    Float rw;
    if (!coneSamplable(&pCenter, &rw)) return Shape::pdfFrom(ref, wi);
    Float d2 = DistanceSquared(ref.p, pCenter);
    if (d2 <= rw * rw * 1.0001) return Shape::pdfFrom(ref, wi);
    Float cosThetaMax = SafeSqrt(1 - rw * rw / d2);
    // Only directions inside the cone can be produced.
    if (Dot(Normalize(pCenter - ref.p), wi) < cosThetaMax) return 0;
    return UniformConePdf(cosThetaMax);
}

}  // namespace gradus
