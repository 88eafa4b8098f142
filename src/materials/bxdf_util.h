// Small sampling and trigonometry helpers used by the BxDFs (local frame, z = normal).
#pragma once
#include "core/geometry.h"

namespace gradus {
namespace bxdfutil {

inline Float Cos2Theta(const Vec3 &w) { return w.z * w.z; }
inline Float Sin2Theta(const Vec3 &w) { return std::max<Float>(0, 1 - Cos2Theta(w)); }
inline Float SinTheta(const Vec3 &w) { return std::sqrt(Sin2Theta(w)); }
inline Float TanTheta(const Vec3 &w) { return SinTheta(w) / CosTheta(w); }
inline Float Tan2Theta(const Vec3 &w) { return Sin2Theta(w) / Cos2Theta(w); }
inline Float CosPhi(const Vec3 &w) {
    Float s = SinTheta(w);
    return s == 0 ? 1 : Clamp<Float>(w.x / s, -1, 1);
}
inline Float SinPhi(const Vec3 &w) {
    Float s = SinTheta(w);
    return s == 0 ? 0 : Clamp<Float>(w.y / s, -1, 1);
}

// Concentric disk mapping (Shirley & Chiu 1997).
inline Point2 ConcentricDisk(Point2 u) {
    Float ox = 2 * u.x - 1, oy = 2 * u.y - 1;
    if (ox == 0 && oy == 0) return {0, 0};
    Float r, theta;
    if (std::abs(ox) > std::abs(oy)) {
        r = ox;
        theta = (Pi / 4) * (oy / ox);
    } else {
        r = oy;
        theta = Pi / 2 - (Pi / 4) * (ox / oy);
    }
    return {r * std::cos(theta), r * std::sin(theta)};
}

// Cosine-weighted hemisphere (Malley's method); pdf = cos / pi.
inline Vec3 CosineHemisphere(Point2 u) {
    Point2 d = ConcentricDisk(u);
    Float z = SafeSqrt(1 - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}

inline Vec3 Reflect(const Vec3 &wo, const Vec3 &n) { return -wo + n * (2 * Dot(wo, n)); }

// Refraction of wi about n (same side as wi); eta = eta_t / eta_i. False on total internal reflection.
inline bool Refract(const Vec3 &wi, const Vec3 &n, Float eta, Vec3 *wt) {
    Float cosI = Dot(n, wi);
    Float sin2I = std::max<Float>(0, 1 - cosI * cosI);
    Float sin2T = sin2I / (eta * eta);
    if (sin2T >= 1) return false;
    Float cosT = std::sqrt(1 - sin2T);
    *wt = -wi / eta + n * (cosI / eta - cosT);
    return true;
}

}  // namespace bxdfutil
}  // namespace gradus
