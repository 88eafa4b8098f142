// Microfacet distributions (Beckmann and Trowbridge-Reitz/GGX), anisotropic,
// with Smith masking and visible-normal sampling.
#pragma once
#include "core/geometry.h"

namespace gradus {

class MicrofacetDistribution {
  public:
    enum Type { Beckmann, TrowbridgeReitz };
    MicrofacetDistribution(Type type, Float alphaX, Float alphaY)
        : type_(type), ax_(std::max<Float>(alphaX, 1e-4)), ay_(std::max<Float>(alphaY, 1e-4)),
          axRaw_(alphaX), ayRaw_(alphaY) {}

    // pbrt-v3's "remaproughness" mapping from a perceptual roughness in [0,1] to alpha
    // (a polynomial fit in log(roughness), the same for both distributions in pbrt-v3).
    static Float RoughnessToAlpha(Float roughness);

    Type type() const { return type_; }
    Float alphaX() const { return ax_; }
    Float alphaY() const { return ay_; }
    // The lowest alpha as given (before clamping for numerical safety).
    Float alphaMin() const { return std::min(axRaw_, ayRaw_); }

    // Normal distribution D(wh) (projected area normalized: integral of D cos = 1).
    Float D(const Vec3 &wh) const;
    // Smith Lambda; G1 = 1 / (1 + Lambda); G is the height-correlated form.
    Float Lambda(const Vec3 &w) const;
    Float G1(const Vec3 &w) const { return 1 / (1 + Lambda(w)); }
    Float G(const Vec3 &wo, const Vec3 &wi) const { return 1 / (1 + Lambda(wo) + Lambda(wi)); }

    // Samples a microfacet normal (z > 0) from the distribution of normals visible
    // from wo (wo mirrored to the upper hemisphere when below). GGX: Heitz 2018,
    // "Sampling the GGX distribution of visible normals", JCGT 7(4); Beckmann:
    // Heitz & d'Eon 2014, "Importance sampling microfacet-based BSDFs using the
    // distribution of visible normals", EGSR (stretch / sample slopes / unstretch).
    Vec3 sampleWh(const Vec3 &wo, Point2 u) const;
    // Density of sampleWh: G1(wo) max(0, wo.wh) D(wh) / |cos wo| (wo mirrored as above).
    Float pdf(const Vec3 &wo, const Vec3 &wh) const;

  private:
    Point2 sampleBeckmannSlopes(Float cosTheta, Point2 u) const;
    Type type_;
    Float ax_, ay_, axRaw_, ayRaw_;
};

// Inverse error function (Winitzki's approximation refined by Newton steps).
Float ErfInv(Float x);

}  // namespace gradus
