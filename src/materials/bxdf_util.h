// Small sampling and trigonometry helpers used by the BxDFs (local frame, z = normal).
#pragma once
#include "core/geometry.h"
#include "samplers/sampling.h"

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

// Cosine-weighted hemisphere sampling comes from samplers/sampling.h.
inline Vec3 CosineHemisphere(Point2 u) { return SampleCosineHemisphere(u); }

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
