#include "shapes/quadrics.h"

#include <algorithm>
#include <cmath>

namespace gradus {

namespace {

Float PhiMaxRadians(Float deg) { return Radians(Clamp<Float>(deg, 0, 360)); }

// Tries the two roots of a quadratic in order; accept(t) decides validity.
template <typename Accept>
bool NearestRoot(Float a, Float b, Float c, const Ray &r, Float tMin, Accept accept, Float *tHit) {
    Float t0, t1;
    if (!SolveQuadratic(a, b, c, &t0, &t1)) return false;
    for (Float t : {t0, t1}) {
        if (!(t > tMin && t < r.tMax)) continue;
        if (!accept(r(t))) continue;
        *tHit = t;
        return true;
    }
    return false;
}

// Keeps a point off the axis so that phi and dp/du stay defined.
Point3 OffAxis(Point3 p, Float scale) {
    if (p.x == 0 && p.y == 0) p.x = 1e-9 * std::max<Float>(scale, 1e-30);
    return p;
}

}  // namespace

// ------------------------------------------------------------------- disk
Disk::Disk(const Transform &w, bool ro, Float height, Float radius, Float innerRadius, Float phiMaxDeg)
    : AnalyticShape(w, ro), height_(height), radius_(radius), innerRadius_(Clamp<Float>(innerRadius, 0, radius)),
      phiMax_(PhiMaxRadians(phiMaxDeg)) {}

Float Disk::objectArea() const { return 0.5 * phiMax_ * (radius_ * radius_ - innerRadius_ * innerRadius_); }

Bounds3 Disk::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, height_));
    b.expand(Point3(radius_, radius_, height_));
    return b;
}

bool Disk::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    if (r.d.z == 0) return false;
    Float t = (height_ - r.o.z) / r.d.z;
    if (!(t > tMin && t < r.tMax)) return false;
    Point3 p = r(t);
    Float rho2 = p.x * p.x + p.y * p.y;
    if (rho2 > radius_ * radius_ || rho2 < innerRadius_ * innerRadius_) return false;
    if (phiMax_ < 2 * Pi && PhiOf(p.x, p.y) > phiMax_) return false;
    *tHit = t;
    return true;
}

AnalyticShape::Patch Disk::patch(const Point3 &pObj) const {
    Patch pt;
    Point3 p = OffAxis(Point3(pObj.x, pObj.y, height_), radius_);
    Float rho = std::sqrt(p.x * p.x + p.y * p.y);
    Float dr = radius_ - innerRadius_;
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? PhiOf(p.x, p.y) / phiMax_ : 0, dr > 0 ? (radius_ - rho) / dr : 0);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(p.x, p.y, 0) * (-dr / rho);
    pt.d2pduu = pt.d2pduv = pt.d2pdvv = Vec3(0, 0, 0);  // flat: dn = 0
    return pt;
}

Point3 Disk::sampleObjectPoint(Point2 u) const {
    // rho^2 uniform between the radii, phi uniform: uniform by area.
    Float rho = std::sqrt(Lerp(u.x, innerRadius_ * innerRadius_, radius_ * radius_));
    Float phi = u.y * phiMax_;
    return Point3(rho * std::cos(phi), rho * std::sin(phi), height_);
}

// --------------------------------------------------------------- cylinder
Cylinder::Cylinder(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg)
    : AnalyticShape(w, ro), radius_(radius), zMin_(std::min(zMin, zMax)), zMax_(std::max(zMin, zMax)),
      phiMax_(PhiMaxRadians(phiMaxDeg)) {}

Float Cylinder::objectArea() const { return (zMax_ - zMin_) * radius_ * phiMax_; }

Bounds3 Cylinder::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, zMin_));
    b.expand(Point3(radius_, radius_, zMax_));
    return b;
}

bool Cylinder::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    Float a = r.d.x * r.d.x + r.d.y * r.d.y;
    if (!(a > 0)) return false;
    Float od = r.o.x * r.d.x + r.o.y * r.d.y;
    // Discriminant from the ray's distance to the axis (robust for distant origins).
    Float fx = r.o.x - r.d.x * (od / a), fy = r.o.y - r.d.y * (od / a);
    Float disc = 4 * a * (radius_ * radius_ - (fx * fx + fy * fy));
    if (disc < 0) return false;
    Float b = 2 * od, c = r.o.x * r.o.x + r.o.y * r.o.y - radius_ * radius_;
    Float root = std::sqrt(disc);
    Float q = b < 0 ? -0.5 * (b - root) : -0.5 * (b + root);
    Float t0 = q / a, t1 = q != 0 ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    for (Float t : {t0, t1}) {
        if (!(t > tMin && t < r.tMax)) continue;
        Point3 p = r(t);
        if (p.z < zMin_ || p.z > zMax_) continue;
        if (phiMax_ < 2 * Pi && PhiOf(p.x, p.y) > phiMax_) continue;
        *tHit = t;
        return true;
    }
    return false;
}

AnalyticShape::Patch Cylinder::patch(const Point3 &pObj) const {
    Patch pt;
    Point3 p = OffAxis(pObj, radius_);
    Float rho = std::sqrt(p.x * p.x + p.y * p.y);
    p.x *= radius_ / rho;  // reproject onto the surface
    p.y *= radius_ / rho;
    Float dz = zMax_ - zMin_;
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? PhiOf(p.x, p.y) / phiMax_ : 0, dz > 0 ? (p.z - zMin_) / dz : 0);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(0, 0, dz);
    pt.d2pduu = Vec3(p.x, p.y, 0) * (-phiMax_ * phiMax_);
    pt.d2pduv = pt.d2pdvv = Vec3(0, 0, 0);
    return pt;
}

Point3 Cylinder::sampleObjectPoint(Point2 u) const {
    Float z = Lerp(u.x, zMin_, zMax_), phi = u.y * phiMax_;
    return Point3(radius_ * std::cos(phi), radius_ * std::sin(phi), z);
}

// ------------------------------------------------------------------- cone
Cone::Cone(const Transform &w, bool ro, Float height, Float radius, Float phiMaxDeg)
    : AnalyticShape(w, ro), height_(height), radius_(radius), phiMax_(PhiMaxRadians(phiMaxDeg)) {}

Float Cone::objectArea() const {
    return 0.5 * phiMax_ * radius_ * std::sqrt(height_ * height_ + radius_ * radius_);
}

Bounds3 Cone::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, 0));
    b.expand(Point3(radius_, radius_, height_));
    return b;
}

bool Cone::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    // x^2 + y^2 = k (z - h)^2 with k = (radius / height)^2.
    Float k = (radius_ / height_) * (radius_ / height_);
    Float oz = r.o.z - height_;
    Float a = r.d.x * r.d.x + r.d.y * r.d.y - k * r.d.z * r.d.z;
    Float b = 2 * (r.d.x * r.o.x + r.d.y * r.o.y - k * r.d.z * oz);
    Float c = r.o.x * r.o.x + r.o.y * r.o.y - k * oz * oz;
    auto accept = [&](const Point3 &p) {
        if (p.z < 0 || p.z > height_) return false;
        return !(phiMax_ < 2 * Pi && PhiOf(p.x, p.y) > phiMax_);
    };
    return NearestRoot(a, b, c, r, tMin, accept, tHit);
}

AnalyticShape::Patch Cone::patch(const Point3 &pObj) const {
    Patch pt;
    Point3 p = OffAxis(pObj, radius_);
    Float v = Clamp<Float>(p.z / height_, 0, 1 - 1e-9);
    // Reproject radially onto the cone at this height.
    Float rho = std::sqrt(p.x * p.x + p.y * p.y), rhoS = radius_ * (1 - v);
    p.x *= rhoS / rho;
    p.y *= rhoS / rho;
    p.z = v * height_;
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? PhiOf(p.x, p.y) / phiMax_ : 0, v);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(-p.x / (1 - v), -p.y / (1 - v), height_);
    pt.d2pduu = Vec3(p.x, p.y, 0) * (-phiMax_ * phiMax_);
    pt.d2pduv = Vec3(p.y, -p.x, 0) * (phiMax_ / (1 - v));
    pt.d2pdvv = Vec3(0, 0, 0);
    return pt;
}

Point3 Cone::sampleObjectPoint(Point2 u) const {
    // Area grows linearly with the distance f from the apex: f = sqrt(u).
    Float f = std::sqrt(u.x), phi = u.y * phiMax_;
    Float rho = radius_ * f;
    return Point3(rho * std::cos(phi), rho * std::sin(phi), height_ * (1 - f));
}

// ------------------------------------------------------------- paraboloid
Paraboloid::Paraboloid(const Transform &w, bool ro, Float radius, Float zMin, Float zMax, Float phiMaxDeg)
    : AnalyticShape(w, ro), radius_(radius), phiMax_(PhiMaxRadians(phiMaxDeg)) {
    zMin_ = std::max<Float>(0, std::min(zMin, zMax));
    zMax_ = std::max(zMin, zMax);
    k_ = zMax_ / (radius_ * radius_);
}

Float Paraboloid::objectArea() const {
    // phimax * integral of rho sqrt(1 + (dz/drho)^2) drho, with z = k rho^2.
    return phiMax_ / (12 * k_ * k_) * (std::pow(1 + 4 * k_ * zMax_, 1.5) - std::pow(1 + 4 * k_ * zMin_, 1.5));
}

Bounds3 Paraboloid::objectBound() const {
    Bounds3 b;
    b.expand(Point3(-radius_, -radius_, zMin_));
    b.expand(Point3(radius_, radius_, zMax_));
    return b;
}

bool Paraboloid::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    Float a = k_ * (r.d.x * r.d.x + r.d.y * r.d.y);
    Float b = 2 * k_ * (r.d.x * r.o.x + r.d.y * r.o.y) - r.d.z;
    Float c = k_ * (r.o.x * r.o.x + r.o.y * r.o.y) - r.o.z;
    auto accept = [&](const Point3 &p) {
        if (p.z < zMin_ || p.z > zMax_) return false;
        return !(phiMax_ < 2 * Pi && PhiOf(p.x, p.y) > phiMax_);
    };
    return NearestRoot(a, b, c, r, tMin, accept, tHit);
}

AnalyticShape::Patch Paraboloid::patch(const Point3 &pObj) const {
    Patch pt;
    Point3 p = OffAxis(pObj, radius_);
    p.z = std::max<Float>(k_ * (p.x * p.x + p.y * p.y), 1e-12 * zMax_);  // onto the surface, off the apex
    Float dz = zMax_ - zMin_;
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? PhiOf(p.x, p.y) / phiMax_ : 0, dz > 0 ? (p.z - zMin_) / dz : 0);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(p.x / (2 * p.z), p.y / (2 * p.z), 1) * dz;
    pt.d2pduu = Vec3(p.x, p.y, 0) * (-phiMax_ * phiMax_);
    pt.d2pduv = Vec3(-p.y / (2 * p.z), p.x / (2 * p.z), 0) * (dz * phiMax_);
    pt.d2pdvv = Vec3(p.x / (4 * p.z * p.z), p.y / (4 * p.z * p.z), 0) * (-dz * dz);
    return pt;
}

Point3 Paraboloid::sampleObjectPoint(Point2 u) const {
    // The area below height z is proportional to (1 + 4 k z)^(3/2): invert it.
    Float a = std::pow(1 + 4 * k_ * zMin_, 1.5), b = std::pow(1 + 4 * k_ * zMax_, 1.5);
    Float z = (std::pow(Lerp(u.x, a, b), 2.0 / 3.0) - 1) / (4 * k_);
    z = Clamp(z, zMin_, zMax_);
    Float rho = std::sqrt(z / k_), phi = u.y * phiMax_;
    return Point3(rho * std::cos(phi), rho * std::sin(phi), z);
}

// ------------------------------------------------------------ hyperboloid
Hyperboloid::Hyperboloid(const Transform &w, bool ro, const Point3 &p1, const Point3 &p2, Float phiMaxDeg)
    : AnalyticShape(w, ro), p1_(p1), d_(p2 - p1), phiMax_(PhiMaxRadians(phiMaxDeg)) {
    // rho^2(s) = alpha s^2 + beta s + gamma along the segment p1 + s d.
    alpha_ = d_.x * d_.x + d_.y * d_.y;
    beta_ = 2 * (p1.x * d_.x + p1.y * d_.y);
    gamma_ = p1.x * p1.x + p1.y * p1.y;
    // Table of the area density for sampling, integrated piecewise linearly.
    const int n = 1024;
    g_.resize(n + 1);
    cdf_.assign(n + 1, 0);
    for (int i = 0; i <= n; ++i) g_[i] = density(Float(i) / n);
    for (int i = 0; i < n; ++i) cdf_[i + 1] = cdf_[i] + 0.5 * (g_[i] + g_[i + 1]) / n;
    area_ = phiMax_ * cdf_[n];
}

Float Hyperboloid::density(Float s) const {
    // |dP/dphi x dP/ds|^2 = dz^2 rho^2 + ((p1 + s d)_xy . d_xy)^2.
    Float rho2 = std::max<Float>(0, alpha_ * s * s + beta_ * s + gamma_);
    Float ld = 0.5 * beta_ + alpha_ * s;
    return std::sqrt(d_.z * d_.z * rho2 + ld * ld);
}

Bounds3 Hyperboloid::objectBound() const {
    // rho^2 is convex in s: its maximum is at an end of the segment.
    Float rMax = std::sqrt(std::max(gamma_, alpha_ + beta_ + gamma_));
    Bounds3 b;
    b.expand(Point3(-rMax, -rMax, p1_.z));
    b.expand(Point3(rMax, rMax, p1_.z + d_.z));
    return b;
}

bool Hyperboloid::intersectObject(const Ray &r, Float tMin, Float *tHit) const {
    // Segment parameter along the ray: s(t) = s0 + t s1.
    Float s0 = (r.o.z - p1_.z) / d_.z, s1 = r.d.z / d_.z;
    Float a = r.d.x * r.d.x + r.d.y * r.d.y - alpha_ * s1 * s1;
    Float b = 2 * (r.o.x * r.d.x + r.o.y * r.d.y) - 2 * alpha_ * s0 * s1 - beta_ * s1;
    Float c = r.o.x * r.o.x + r.o.y * r.o.y - alpha_ * s0 * s0 - beta_ * s0 - gamma_;
    auto accept = [&](const Point3 &p) {
        Float s = (p.z - p1_.z) / d_.z;
        if (s < 0 || s > 1) return false;
        if (phiMax_ >= 2 * Pi) return true;
        Point3 l = p1_ + d_ * s;
        return PhiOf(l.x * p.x + l.y * p.y, l.x * p.y - l.y * p.x) <= phiMax_;
    };
    return NearestRoot(a, b, c, r, tMin, accept, tHit);
}

AnalyticShape::Patch Hyperboloid::patch(const Point3 &pObj) const {
    Patch pt;
    Float s = Clamp<Float>((pObj.z - p1_.z) / d_.z, 0, 1);
    Point3 l = p1_ + d_ * s;
    // Rotation angle from the generating segment to the point.
    Float phi = (l.x == 0 && l.y == 0) ? 0 : PhiOf(l.x * pObj.x + l.y * pObj.y, l.x * pObj.y - l.y * pObj.x);
    Float c = std::cos(phi), sn = std::sin(phi);
    Point3 p(l.x * c - l.y * sn, l.x * sn + l.y * c, l.z);
    p = OffAxis(p, std::sqrt(alpha_ + gamma_));
    pt.p = p;
    pt.uv = Point2(phiMax_ > 0 ? phi / phiMax_ : 0, s);
    pt.dpdu = Vec3(-phiMax_ * p.y, phiMax_ * p.x, 0);
    pt.dpdv = Vec3(d_.x * c - d_.y * sn, d_.x * sn + d_.y * c, d_.z);
    pt.d2pduu = Vec3(p.x, p.y, 0) * (-phiMax_ * phiMax_);
    pt.d2pduv = Vec3(-pt.dpdv.y, pt.dpdv.x, 0) * phiMax_;
    pt.d2pdvv = Vec3(0, 0, 0);
    return pt;
}

Point3 Hyperboloid::sampleObjectPoint(Point2 u) const {
    // Invert the piecewise-linear cumulative density in s.
    Float target = u.x * cdf_.back();
    int n = int(g_.size()) - 1;
    int i = int(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin()) - 1;
    i = Clamp(i, 0, n - 1);
    Float h = Float(1) / n, rem = target - cdf_[i];
    Float g0 = g_[i], slope = (g_[i + 1] - g_[i]) / h;
    // Solve g0 x + slope x^2 / 2 = rem for x in [0, h].
    Float x;
    if (std::abs(slope) * h < 1e-9 * std::max<Float>(g0, 1e-300)) {
        x = g0 > 0 ? rem / g0 : 0;
    } else {
        Float disc = std::max<Float>(0, g0 * g0 + 2 * slope * rem);
        x = 2 * rem / (g0 + std::sqrt(disc));
    }
    Float s = Clamp<Float>(i * h + x, 0, 1);
    Float phi = u.y * phiMax_;
    Point3 l = p1_ + d_ * s;
    Float c = std::cos(phi), sn = std::sin(phi);
    return Point3(l.x * c - l.y * sn, l.x * sn + l.y * c, l.z);
}

}  // namespace gradus
