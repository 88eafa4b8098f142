#include "materials/microfacet.h"

#include "materials/bxdf_util.h"

namespace gradus {
using namespace bxdfutil;

Float MicrofacetDistribution::RoughnessToAlpha(Float roughness) {
    Float x = std::log(std::max<Float>(roughness, 1e-3));
    return 1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x;
}

Float ErfInv(Float x) {
    x = Clamp<Float>(x, -1 + 1e-15, 1 - 1e-15);
    // Winitzki 2008, "A handy approximation for the error function and its inverse", a = 0.147.
    const Float a = 0.147;
    Float ln = std::log((1 - x) * (1 + x));
    Float t = 2 / (Pi * a) + ln / 2;
    Float y = std::copysign(std::sqrt(std::sqrt(t * t - ln / a) - t), x);
    for (int i = 0; i < 3; ++i) {
        Float err = std::erf(y) - x;
        y -= err / (2 / std::sqrt(Pi) * std::exp(-y * y));
    }
    return y;
}

Float MicrofacetDistribution::D(const Vec3 &wh) const {
    Float cos2 = Cos2Theta(wh);
    if (cos2 <= 0) return 0;
    Float tan2 = Sin2Theta(wh) / cos2;
    if (!std::isfinite(tan2)) return 0;
    Float c = CosPhi(wh), s = SinPhi(wh);
    Float e = tan2 * (c * c / (ax_ * ax_) + s * s / (ay_ * ay_));
    if (type_ == Beckmann) return std::exp(-e) / (Pi * ax_ * ay_ * cos2 * cos2);
    return 1 / (Pi * ax_ * ay_ * cos2 * cos2 * (1 + e) * (1 + e));
}

Float MicrofacetDistribution::Lambda(const Vec3 &w) const {
    Float cos2 = Cos2Theta(w);
    if (cos2 <= 0) return Infinity;
    Float tan2 = Sin2Theta(w) / cos2;
    if (tan2 == 0) return 0;
    Float c = CosPhi(w), s = SinPhi(w);
    Float alpha2 = c * c * ax_ * ax_ + s * s * ay_ * ay_;
    if (type_ == TrowbridgeReitz) return (-1 + std::sqrt(1 + alpha2 * tan2)) / 2;
    // Beckmann: Lambda = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), a = 1 / (alpha tan).
    Float a = 1 / std::sqrt(alpha2 * tan2);
    return (std::erf(a) - 1) / 2 + std::exp(-a * a) / (2 * a * std::sqrt(Pi));
}

// Slopes of visible normals for an isotropic Beckmann surface of alpha = 1 seen from
// a direction at cosTheta with azimuth 0. The x-slope marginal has CDF (up to
// normalization) C(x) = cos (1 + erf x) / 2 + sin exp(-x^2) / (2 sqrt(pi)) for
// x <= cot(theta); the y-slope is independent and Gaussian.
Point2 MicrofacetDistribution::sampleBeckmannSlopes(Float cosTheta, Point2 u) const {
    if (cosTheta > 0.999999) {
        Float r = std::sqrt(-std::log(std::max<Float>(1 - u.x, 1e-300)));
        Float phi = 2 * Pi * u.y;
        return {r * std::cos(phi), r * std::sin(phi)};
    }
    Float sinTheta = SafeSqrt(1 - cosTheta * cosTheta);
    Float cot = cosTheta / sinTheta;
    const Float invSqrtPi = 1 / std::sqrt(Pi);
    auto C = [&](Float x) { return cosTheta * (1 + std::erf(x)) / 2 + sinTheta * std::exp(-x * x) * invSqrtPi / 2; };
    Float hi = std::min<Float>(cot, 7), lo = -7;
    Float target = u.x * C(hi);
    Float x = Clamp<Float>(0, lo, hi);
    for (int i = 0; i < 100; ++i) {
        Float v = C(x) - target;
        if (std::abs(v) < 1e-14) break;
        if (v > 0) hi = x; else lo = x;
        Float d = (cosTheta - x * sinTheta) * std::exp(-x * x) * invSqrtPi;
        Float xn = d > 0 ? x - v / d : lo - 1;
        x = (xn > lo && xn < hi) ? xn : (lo + hi) / 2;
        if (hi - lo < 1e-13) break;
    }
    return {x, ErfInv(2 * u.y - 1)};
}

Vec3 MicrofacetDistribution::sampleWh(const Vec3 &woIn, Point2 u) const {
    Vec3 wo = woIn.z < 0 ? -woIn : woIn;
    if (type_ == TrowbridgeReitz) {
        Vec3 vh = Normalize(Vec3(ax_ * wo.x, ay_ * wo.y, wo.z));
        Float len2 = vh.x * vh.x + vh.y * vh.y;
        Vec3 t1 = len2 > 0 ? Vec3(-vh.y, vh.x, 0) / std::sqrt(len2) : Vec3(1, 0, 0);
        Vec3 t2 = Cross(vh, t1);
        Float r = std::sqrt(u.x), phi = 2 * Pi * u.y;
        Float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
        Float sw = (1 + vh.z) / 2;
        p2 = (1 - sw) * std::sqrt(std::max<Float>(0, 1 - p1 * p1)) + sw * p2;
        Vec3 nh = t1 * p1 + t2 * p2 + vh * SafeSqrt(1 - p1 * p1 - p2 * p2);
        return Normalize(Vec3(ax_ * nh.x, ay_ * nh.y, std::max<Float>(1e-9, nh.z)));
    }
    // Beckmann: stretch to alpha = 1, sample slopes, rotate back and unstretch.
    Vec3 ws = Normalize(Vec3(ax_ * wo.x, ay_ * wo.y, wo.z));
    Point2 slope = sampleBeckmannSlopes(ws.z, u);
    Float cphi = CosPhi(ws), sphi = SinPhi(ws);
    Float sx = cphi * slope.x - sphi * slope.y;
    Float sy = sphi * slope.x + cphi * slope.y;
    sx *= ax_;
    sy *= ay_;
    if (!std::isfinite(sx) || !std::isfinite(sy)) return Vec3(0, 0, 1);
    return Normalize(Vec3(-sx, -sy, 1));
}

Float MicrofacetDistribution::pdf(const Vec3 &woIn, const Vec3 &wh) const {
    Vec3 wo = woIn.z < 0 ? -woIn : woIn;
    if (wo.z == 0 || wh.z <= 0) return 0;
    Float d = Dot(wo, wh);
    if (d <= 0) return 0;
    return G1(wo) * d * D(wh) / wo.z;
}

}  // namespace gradus
