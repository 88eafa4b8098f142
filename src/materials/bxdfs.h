// The BxDFs of Gradus. All work in the local shading frame (z = shading normal).
// Composite materials build a CompositeBxDF whose components are BxDFs too.
#pragma once
#include <array>

#include "materials/bsdf.h"
#include "materials/fresnel.h"
#include "materials/microfacet.h"

namespace gradus {

// Ideal diffuse reflection: f = R / pi.
class LambertianReflection : public BxDF {
  public:
    explicit LambertianReflection(const Spectrum &R) : BxDF(BSDF_REFLECTION | BSDF_DIFFUSE), R_(R) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return 1; }

  private:
    Spectrum R_;
};

// Ideal diffuse transmission: f = T / pi into the opposite hemisphere.
class LambertianTransmission : public BxDF {
  public:
    explicit LambertianTransmission(const Spectrum &T) : BxDF(BSDF_TRANSMISSION | BSDF_DIFFUSE), T_(T) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return 1; }

  private:
    Spectrum T_;
};

// Oren & Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994
// (the qualitative model, Eq. 30); sigma in degrees.
class OrenNayar : public BxDF {
  public:
    OrenNayar(const Spectrum &R, Float sigmaDeg);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return 1; }

  private:
    Spectrum R_;
    Float A_, B_;
};

// Perfect mirror reflection scaled by R and a Fresnel term.
class SpecularReflection : public BxDF {
  public:
    SpecularReflection(const Spectrum &R, const Fresnel &fr) : BxDF(BSDF_REFLECTION | BSDF_SPECULAR), R_(R), fr_(fr) {}
    Spectrum f(const Vec3 &, const Vec3 &, TransportMode) const override { return Spectrum(0); }
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &, const Vec3 &, TransportMode) const override { return 0; }
    Float roughness() const override { return 0; }

  private:
    Spectrum R_;
    Fresnel fr_;
};

// Perfect specular refraction only (T * (1 - F)), eta = eta_inside / eta_outside.
class SpecularTransmission : public BxDF {
  public:
    SpecularTransmission(const Spectrum &T, Float eta) : BxDF(BSDF_TRANSMISSION | BSDF_SPECULAR), T_(T), eta_(eta) {}
    Spectrum f(const Vec3 &, const Vec3 &, TransportMode) const override { return Spectrum(0); }
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &, const Vec3 &, TransportMode) const override { return 0; }
    Float roughness() const override { return 0; }

  private:
    Spectrum T_;
    Float eta_;
};

// Smooth dielectric interface: reflection (R * F) or refraction (T * (1 - F)),
// chosen with probability F. eta = eta_inside / eta_outside (inside = -z).
class SpecularDielectric : public BxDF {
  public:
    SpecularDielectric(const Spectrum &R, const Spectrum &T, Float eta);
    Spectrum f(const Vec3 &, const Vec3 &, TransportMode) const override { return Spectrum(0); }
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &, const Vec3 &, TransportMode) const override { return 0; }
    Float roughness() const override { return 0; }
    Float eta() const override { return eta_; }

  private:
    Spectrum R_, T_;
    Float eta_;
};

// Torrance-Sparrow microfacet reflection: R D G F / (4 |cos o| |cos i|), sampled with
// visible normals. Works from both sides (two-sided surfaces).
class MicrofacetReflection : public BxDF {
  public:
    MicrofacetReflection(const Spectrum &R, const MicrofacetDistribution &d, const Fresnel &fr)
        : BxDF(BSDF_REFLECTION | BSDF_GLOSSY), R_(R), d_(d), fr_(fr) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return d_.alphaMin(); }

  private:
    Spectrum R_;
    MicrofacetDistribution d_;
    Fresnel fr_;
};

// Rough dielectric (Walter et al., "Microfacet models for refraction through rough
// surfaces", EGSR 2007): reflection R*F and transmission T*(1-F) through one
// visible-normal sample; eta = eta_inside / eta_outside. `reflect`/`transmit` select
// the lobes present (translucent uses both; a lobe with zero scale is dropped).
class MicrofacetDielectric : public BxDF {
  public:
    MicrofacetDielectric(const Spectrum &R, const Spectrum &T, Float eta, const MicrofacetDistribution &d);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return d_.alphaMin(); }
    Float eta() const override { return hasT_ ? eta_ : 1; }

  private:
    // Probability of choosing reflection given the microfacet normal.
    Float reflectProb(Float F) const;
    Spectrum R_, T_;
    Float eta_;
    MicrofacetDistribution d_;
    bool hasR_, hasT_;
};

// Ashikhmin & Shirley, "An anisotropic Phong BRDF model" (JGT 2000): diffuse
// substrate under a glossy coat, with the microfacet distribution d (pbrt-v3 "substrate").
class FresnelBlend : public BxDF {
  public:
    FresnelBlend(const Spectrum &Rd, const Spectrum &Rs, const MicrofacetDistribution &d)
        : BxDF(BSDF_REFLECTION | BSDF_GLOSSY), Rd_(Rd), Rs_(Rs), d_(d) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return d_.alphaMin(); }

  private:
    Spectrum Rd_, Rs_;
    MicrofacetDistribution d_;
};

// A BxDF whose value is multiplied by a constant (used by "mix").
class ScaledBxDF : public BxDF {
  public:
    ScaledBxDF(const BxDF *b, const Spectrum &scale) : BxDF(b->flags()), b_(b), scale_(scale) {}
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override {
        return scale_ * b_->f(wo, wi, mode);
    }
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override {
        if (!b_->sample(wo, uc, u, mode, s)) return false;
        s->f = scale_ * s->f;
        return true;
    }
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override { return b_->pdf(wo, wi, mode); }
    Float roughness() const override { return b_->roughness(); }

  private:
    const BxDF *b_;
    Spectrum scale_;
};

// Sum of up to MaxComponents BxDFs. sample() picks one component with probability
// proportional to its weight (uniform by default), re-uses the rest of uc for the
// component's own choice, and returns the full sum of f and the mixture pdf for
// non-specular samples.
class CompositeBxDF : public BxDF {
  public:
    static constexpr int MaxComponents = 8;
    CompositeBxDF() : BxDF(BSDF_NONE) {}
    // Adds a component (ignored when null or weight <= 0).
    void add(const BxDF *b, Float weight = 1);
    int count() const { return n_; }
    const BxDF *component(int i) const { return c_[i]; }
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override;

  private:
    std::array<const BxDF *, MaxComponents> c_{};
    std::array<Float, MaxComponents> w_{};
    int n_ = 0;
    Float wSum_ = 0;
};

}  // namespace gradus
