// pbrt-v3's "disney" material: the Disney BRDF of Burley 2012 ("Physically-Based
// Shading at Disney", SIGGRAPH course notes) extended to a BSDF as in Burley 2015
// ("Extending the Disney BRDF to a BSDF with Integrated Subsurface Scattering"), with the
// lobes, weights and parameters pbrt-v3 uses. Every lobe is a BxDF of its own (tests
// query them one by one); DisneyBxDF sums them.
#pragma once
#include <memory>

#include "materials/bxdfs.h"
#include "materials/material.h"

namespace gradus {

// pbrt-v3's Schlick weight (1 - cos)^5 with 1 - cos clamped to [0, 1].
Float SchlickWeight(Float cosTheta);

// Reflection lobes sampled from the cosine-weighted hemisphere on wo's side; the
// subclass supplies the value for a same-hemisphere pair from the lobe's scale R and
// (for the lobes that depend on theta_d) the roughness.
class DisneyCosineLobe : public BxDF {
  public:
    DisneyCosineLobe(const Spectrum &R, Float rough) : BxDF(BSDF_REFLECTION | BSDF_DIFFUSE), R_(R), rough_(rough) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return 1; }

  protected:
    virtual Spectrum eval(const Vec3 &wo, const Vec3 &wi) const = 0;
    Spectrum R_;
    Float rough_;
};

// Burley 2015, Eq. 4 without its retro-reflection term: R/pi (1 - Fo/2)(1 - Fi/2).
class DisneyDiffuse : public DisneyCosineLobe {
  public:
    explicit DisneyDiffuse(const Spectrum &R) : DisneyCosineLobe(R, 0) {}

  protected:
    Spectrum eval(const Vec3 &wo, const Vec3 &wi) const override;
};

// Burley 2015, Eq. 4's retro-reflection term: R/pi RR (Fo + Fi + Fo Fi (RR - 1)),
// RR = 2 roughness cos^2(theta_d). With DisneyDiffuse it sums to Burley 2012's diffuse
// (Sec. 5.3): R/pi (1 + (FD90 - 1) Fo)(1 + (FD90 - 1) Fi), FD90 = 0.5 + RR.
class DisneyRetro : public DisneyCosineLobe {
  public:
    using DisneyCosineLobe::DisneyCosineLobe;

  protected:
    Spectrum eval(const Vec3 &wo, const Vec3 &wi) const override;
};

// The thin-surface "fake subsurface" lobe (Burley 2012, Sec. 5.3: the Hanrahan-Krueger
// inspired flattening): 1.25 R/pi (Fss (1/(cos o + cos i) - 0.5) + 0.5), with
// Fss = (1 + (Fss90 - 1) Fo)(1 + (Fss90 - 1) Fi), Fss90 = roughness cos^2(theta_d).
class DisneyFakeSS : public DisneyCosineLobe {
  public:
    using DisneyCosineLobe::DisneyCosineLobe;

  protected:
    Spectrum eval(const Vec3 &wo, const Vec3 &wi) const override;
};

// Burley 2012, Sec. 5.3 sheen: R (1 - cos theta_d)^5.
class DisneySheen : public DisneyCosineLobe {
  public:
    explicit DisneySheen(const Spectrum &R) : DisneyCosineLobe(R, 0) {}

  protected:
    Spectrum eval(const Vec3 &wo, const Vec3 &wi) const override;
};

// Burley 2012, Sec. 5.4 and Appendix B clear coat: GTR1 distribution (Eq. 4 with
// gamma = 1), Schlick Fresnel with F0 = 0.04, separable Smith GGX masking with fixed
// alpha 0.25, f = weight/4 * D F G1(o) G1(i) / (4 cos o cos i) (the 1/4 is the
// BRDF explorer's scale). Sampled from D cos theta_h exactly (Appendix B, Eq. 2).
class DisneyClearcoat : public BxDF {
  public:
    DisneyClearcoat(Float weight, Float alpha)
        : BxDF(BSDF_REFLECTION | BSDF_GLOSSY), weight_(weight), alpha_(alpha) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return alpha_; }
    // GTR1 normal distribution (normalised: integral of D cos over the hemisphere is 1).
    static Float GTR1(Float cosTheta, Float alpha);

  private:
    Float weight_, alpha_;
};

// Specular reflection: Trowbridge-Reitz (GTR2, anisotropic; Burley 2012, Appendix B,
// Eq. 13) with height-correlated Smith masking, scaled by R and the Disney Fresnel
// lerp(metallic, F_dielectric(eta), Schlick(R0)). (pbrt-v3 declares Burley's separable
// G1(o) G1(i) in its Disney distribution, but G is not virtual in its base class, so the
// lobes it renders use the height-correlated G: so do these.)
// The Fresnel cosine is taken against the half vector turned to +z, so that reflection
// inside a refracting surface totally reflects (pbrt-v3 since its issue #254).
class DisneySpecular : public BxDF {
  public:
    DisneySpecular(const Spectrum &R, const MicrofacetDistribution &d, const Spectrum &R0, Float metallic, Float eta)
        : BxDF(BSDF_REFLECTION | BSDF_GLOSSY), R_(R), d_(d), R0_(R0), metallic_(metallic), eta_(eta) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return d_.alphaMin(); }
    Spectrum fresnel(Float cosI) const;

  private:
    Spectrum R_;
    MicrofacetDistribution d_;
    Spectrum R0_;
    Float metallic_, eta_;
};

// Rough transmission only (Walter et al. 2007, Eq. 21, T (1 - F)), eta = eta_inside /
// eta_outside, height-correlated Smith masking (see DisneySpecular).
class DisneyTransmission : public BxDF {
  public:
    DisneyTransmission(const Spectrum &T, const MicrofacetDistribution &d, Float eta)
        : BxDF(BSDF_TRANSMISSION | BSDF_GLOSSY), T_(T), d_(d), eta_(eta) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return d_.alphaMin(); }
    Float eta() const override { return eta_; }

  private:
    Spectrum T_;
    MicrofacetDistribution d_;
    Float eta_;
};

// The material's inputs at one point (pbrt-v3 names; textures already evaluated).
struct DisneyParams {
    Spectrum color{0.5};
    Float metallic = 0, eta = 1.5, roughness = 0.5, specularTint = 0, anisotropic = 0;
    Float sheen = 0, sheenTint = 0.5, clearcoat = 0, clearcoatGloss = 1, specTrans = 0;
    Float flatness = 0, diffTrans = 1;
    bool thin = false;
};

// The summed lobes as pbrt-v3's DisneyMaterial adds them. sample() picks a lobe (the
// cosine-sampled reflection lobes share one unit of weight, every other lobe has weight 1)
// and returns the sum of all lobes and the mixture pdf.
class DisneyBxDF : public BxDF {
  public:
    // Inputs are clamped to their valid ranges (textures may leave them).
    explicit DisneyBxDF(const DisneyParams &p);
    DisneyBxDF(const DisneyBxDF &) = delete;  // the composite points at the members
    DisneyBxDF &operator=(const DisneyBxDF &) = delete;
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override { return c_.f(wo, wi, mode); }
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override {
        return c_.sample(wo, uc, u, mode, s);
    }
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override { return c_.pdf(wo, wi, mode); }
    Float roughness() const override { return c_.roughness(); }
    Float eta() const override { return hasT_ ? eta_ : 1; }
    int lobeCount() const { return c_.count(); }

    // Below this |eta - 1| the transmission lobe is the smooth pass-through limit (a
    // delta; Walter's model degenerates at eta = 1).
    static constexpr Float SmoothEtaDelta = 1e-3;
    // Microfacet alphas as pbrt-v3 derives them from roughness and anisotropic.
    static void Alphas(Float rough, Float anisotropic, Float *ax, Float *ay);

  private:
    DisneyDiffuse diffuse_{Spectrum(0)};
    DisneyFakeSS fakeSS_{Spectrum(0), 0};
    DisneyRetro retro_{Spectrum(0), 0};
    DisneySheen sheen_{Spectrum(0)};
    DisneySpecular spec_{Spectrum(0), MicrofacetDistribution(MicrofacetDistribution::TrowbridgeReitz, 1, 1),
                         Spectrum(0), 0, 1};
    DisneyClearcoat clearcoat_{0, 0.1};
    DisneyTransmission trans_{Spectrum(0), MicrofacetDistribution(MicrofacetDistribution::TrowbridgeReitz, 1, 1), 1};
    SpecularTransmission smoothTrans_{Spectrum(0), 1};
    LambertianTransmission diffTrans_{Spectrum(0)};
    CompositeBxDF c_;
    Float eta_ = 1;
    bool hasT_ = false;
};

// The "disney" material (called by CreateMaterial; `bump` is "bumpmap" or null).
// scatterdistance > 0 (pbrt-v3's DisneyBSSRDF) is refused with a located error.
std::shared_ptr<Material> CreateDisneyMaterial(const ParamSet &params, const NamedTextures &textures,
                                              const FileLoc &loc, std::shared_ptr<FloatTexture> bump);

}  // namespace gradus
