// Basic geometry: vectors, points, normals, rays, bounds, frames.
// All path-space arithmetic is double precision (gradient shifts are precision
// sensitive); Embree intersects in float and hits are refined in double.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <ostream>

namespace gradus {

using Float = double;
constexpr Float Pi = 3.14159265358979323846;
constexpr Float InvPi = 0.31830988618379067154;
constexpr Float Inv2Pi = 0.15915494309189533577;
constexpr Float Inv4Pi = 0.07957747154594766788;
constexpr Float Infinity = std::numeric_limits<Float>::infinity();

inline Float Radians(Float deg) { return deg * (Pi / 180); }
inline Float Degrees(Float rad) { return rad * (180 / Pi); }
template <typename T>
inline T Clamp(T v, T lo, T hi) { return v < lo ? lo : (v > hi ? hi : v); }
inline Float Lerp(Float t, Float a, Float b) { return (1 - t) * a + t * b; }
inline Float Sqr(Float x) { return x * x; }
inline Float SafeSqrt(Float x) { return std::sqrt(std::max<Float>(0, x)); }
inline Float SafeAcos(Float x) { return std::acos(Clamp<Float>(x, -1, 1)); }

struct Vec2 {
    Float x = 0, y = 0;
    Vec2() = default;
    Vec2(Float x_, Float y_) : x(x_), y(y_) {}
    Float operator[](int i) const { return i == 0 ? x : y; }
    Float &operator[](int i) { return i == 0 ? x : y; }
    Vec2 operator+(const Vec2 &o) const { return {x + o.x, y + o.y}; }
    Vec2 operator-(const Vec2 &o) const { return {x - o.x, y - o.y}; }
    Vec2 operator*(Float s) const { return {x * s, y * s}; }
    Vec2 operator/(Float s) const { return {x / s, y / s}; }
    bool operator==(const Vec2 &o) const { return x == o.x && y == o.y; }
};
using Point2 = Vec2;

struct Point2i {
    int x = 0, y = 0;
    bool operator==(const Point2i &o) const { return x == o.x && y == o.y; }
    bool operator!=(const Point2i &o) const { return !(*this == o); }
};

// One 3-vector type serves points, directions and normals; the Transform
// class has separate entry points for each (ApplyPoint/ApplyVector/ApplyNormal).
struct Vec3 {
    Float x = 0, y = 0, z = 0;
    Vec3() = default;
    constexpr Vec3(Float x_, Float y_, Float z_) : x(x_), y(y_), z(z_) {}
    Float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    Float &operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    Vec3 operator+(const Vec3 &o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3 &o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator*(Float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(Float s) const { Float inv = 1 / s; return {x * inv, y * inv, z * inv}; }
    Vec3 &operator+=(const Vec3 &o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3 &operator-=(const Vec3 &o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3 &operator*=(Float s) { x *= s; y *= s; z *= s; return *this; }
    bool operator==(const Vec3 &o) const { return x == o.x && y == o.y && z == o.z; }
    bool operator!=(const Vec3 &o) const { return !(*this == o); }
    Float lengthSquared() const { return x * x + y * y + z * z; }
    Float length() const { return std::sqrt(lengthSquared()); }
    bool hasNaN() const { return std::isnan(x) || std::isnan(y) || std::isnan(z); }
    bool isFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }
};
using Point3 = Vec3;
using Normal3 = Vec3;

inline Vec3 operator*(Float s, const Vec3 &v) { return v * s; }
inline Float Dot(const Vec3 &a, const Vec3 &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Float AbsDot(const Vec3 &a, const Vec3 &b) { return std::abs(Dot(a, b)); }
inline Vec3 Cross(const Vec3 &a, const Vec3 &b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Vec3 Normalize(const Vec3 &v) { return v / v.length(); }
inline Float Distance(const Vec3 &a, const Vec3 &b) { return (a - b).length(); }
inline Float DistanceSquared(const Vec3 &a, const Vec3 &b) { return (a - b).lengthSquared(); }
inline Vec3 Abs(const Vec3 &v) { return {std::abs(v.x), std::abs(v.y), std::abs(v.z)}; }
inline Vec3 Min(const Vec3 &a, const Vec3 &b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 Max(const Vec3 &a, const Vec3 &b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline Float MaxComponent(const Vec3 &v) { return std::max(v.x, std::max(v.y, v.z)); }
inline int MaxDimension(const Vec3 &v) { return (v.x > v.y) ? (v.x > v.z ? 0 : 2) : (v.y > v.z ? 1 : 2); }
// Flip v so that it lies in the hemisphere of n.
inline Vec3 FaceForward(const Vec3 &v, const Vec3 &n) { return Dot(v, n) < 0 ? -v : v; }
inline std::ostream &operator<<(std::ostream &os, const Vec3 &v) {
    return os << "[" << v.x << ", " << v.y << ", " << v.z << "]";
}

// Orthonormal basis around a unit vector n (Duff et al. 2017, branchless).
inline void CoordinateSystem(const Vec3 &n, Vec3 *s, Vec3 *t) {
    Float sign = std::copysign(Float(1), n.z);
    Float a = -1 / (sign + n.z);
    Float b = n.x * n.y * a;
    *s = Vec3(1 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *t = Vec3(b, sign + n.y * n.y * a, -n.y);
}

// Local shading frame: z is the normal.
struct Frame {
    Vec3 s, t, n;
    Frame() : s(1, 0, 0), t(0, 1, 0), n(0, 0, 1) {}
    explicit Frame(const Vec3 &normal) : n(normal) { CoordinateSystem(n, &s, &t); }
    Frame(const Vec3 &s_, const Vec3 &t_, const Vec3 &n_) : s(s_), t(t_), n(n_) {}
    Vec3 toLocal(const Vec3 &v) const { return {Dot(v, s), Dot(v, t), Dot(v, n)}; }
    Vec3 toWorld(const Vec3 &v) const { return s * v.x + t * v.y + n * v.z; }
};

struct Ray {
    Point3 o;
    Vec3 d;
    Float tMax = Infinity;
    Ray() = default;
    Ray(const Point3 &o_, const Vec3 &d_, Float tMax_ = Infinity) : o(o_), d(d_), tMax(tMax_) {}
    Point3 operator()(Float t) const { return o + d * t; }
};

struct Bounds3 {
    Point3 pMin{Infinity, Infinity, Infinity};
    Point3 pMax{-Infinity, -Infinity, -Infinity};
    void expand(const Point3 &p) { pMin = Min(pMin, p); pMax = Max(pMax, p); }
    void expand(const Bounds3 &b) { pMin = Min(pMin, b.pMin); pMax = Max(pMax, b.pMax); }
    bool empty() const { return pMin.x > pMax.x || pMin.y > pMax.y || pMin.z > pMax.z; }
    Vec3 diagonal() const { return pMax - pMin; }
    Point3 center() const { return (pMin + pMax) * 0.5; }
    void boundingSphere(Point3 *c, Float *r) const {
        *c = center();
        *r = empty() ? 0 : Distance(*c, pMax);
    }
};

// Spherical direction helpers (z up).
inline Float CosTheta(const Vec3 &w) { return w.z; }
inline Float AbsCosTheta(const Vec3 &w) { return std::abs(w.z); }
inline bool SameHemisphere(const Vec3 &a, const Vec3 &b) { return a.z * b.z > 0; }
inline Vec3 SphericalDirection(Float sinTheta, Float cosTheta, Float phi) {
    return {Clamp<Float>(sinTheta, -1, 1) * std::cos(phi), Clamp<Float>(sinTheta, -1, 1) * std::sin(phi),
            Clamp<Float>(cosTheta, -1, 1)};
}
inline Float SphericalTheta(const Vec3 &v) { return SafeAcos(v.z); }
inline Float SphericalPhi(const Vec3 &v) {
    Float p = std::atan2(v.y, v.x);
    return p < 0 ? p + 2 * Pi : p;
}

}  // namespace gradus
