// Small sampling and trigonometry helpers used by the BxDFs (local frame, z = normal).
#pragma once
#include "core/geometry.h"
#include "materials/bsdf.h"
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

// Half vector of a reflection pair, turned to z > 0; false when degenerate (wi = -wo)
// or when it lies in the tangent plane.
inline bool ReflectionHalf(const Vec3 &wo, const Vec3 &wi, Vec3 *wh) {
    Vec3 h = wo + wi;
    Float l2 = h.lengthSquared();
    if (!(l2 > 0)) return false;
    h = h / std::sqrt(l2);
    if (h.z < 0) h = -h;
    *wh = h;
    return h.z > 0;
}

// Generalized half vector of a refraction pair (Walter et al. 2007, Eq. 16) turned to
// z > 0, and etap = eta on wi's side / eta on wo's side (eta = eta_inside /
// eta_outside). False unless wo and wi lie on opposite sides, when degenerate, or when
// either direction would see the microfacet from behind.
inline bool RefractionHalf(const Vec3 &wo, const Vec3 &wi, Float eta, Vec3 *wh, Float *etap) {
    if (wo.z * wi.z >= 0) return false;
    *etap = wo.z > 0 ? eta : 1 / eta;
    Vec3 h = wo + wi * *etap;
    Float l2 = h.lengthSquared();
    if (!(l2 > 0)) return false;
    h = h / std::sqrt(l2);
    if (h.z < 0) h = -h;
    if (!(h.z > 0) || Dot(h, wo) * wo.z <= 0 || Dot(h, wi) * wi.z <= 0) return false;
    *wh = h;
    return true;
}

// The mode of the reverse query (the pdf of sampling wo from wi).
inline TransportMode Reverse(TransportMode m) {
    return m == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
}

// Fills *s for a direction wi that b sampled from wo, from b's own f and pdf: value,
// pdf, reverse pdf, the sampled lobe's flags and eta. True when the pdf is positive.
// (For non-specular lobes whose sample() draws wi and leaves the weights to f and pdf.)
inline bool SampleFromEval(const BxDF &b, const Vec3 &wo, const Vec3 &wi, TransportMode mode, unsigned flags,
                           Float eta, BSDFSample *s) {
    *s = BSDFSample();
    s->wi = wi;
    s->f = b.f(wo, wi, mode);
    s->pdf = b.pdf(wo, wi, mode);
    s->pdfRev = b.pdf(wi, wo, Reverse(mode));
    s->flags = flags;
    s->eta = eta;
    return s->pdf > 0;
}

}  // namespace bxdfutil
}  // namespace gradus
