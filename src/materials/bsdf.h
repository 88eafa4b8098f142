// BSDF interface. A BxDF works in the local shading frame (z = shading
// normal); a BSDF wraps one BxDF (composite lobes are BxDFs of their own) and
// converts directions. Radiance/importance transport is distinguished for
// non-symmetric scattering (refraction); the shading-normal adjoint correction
// is applied by the integrators (it depends on the geometric normal).
#pragma once
#include <cstdint>

#include "core/geometry.h"
#include "core/spectrum.h"
#include "core/interaction.h"

namespace gradus {

// Default near-specular threshold of every integrator that shifts or walks
// paths: a glossy vertex whose roughness is below it is treated as specular
// (G-MLT Sec. 5, Fig. 5a; G-BDPT Sec. 3.1); the scene's feature scan uses it too.
constexpr Float kDefaultShiftThreshold = 0.001;

enum BxDFFlags : unsigned {
    BSDF_NONE = 0,
    BSDF_REFLECTION = 1,
    BSDF_TRANSMISSION = 2,
    BSDF_DIFFUSE = 4,
    BSDF_GLOSSY = 8,
    BSDF_SPECULAR = 16,
    BSDF_ALL = 31,
};

enum class TransportMode { Radiance, Importance };

// Roughness classes used by shift mappings (G-PT/G-BDPT/G-VCM/G-MLT).
enum class RoughnessClass { Smooth, NearSpecular, Rough };

struct BSDFSample {
    Spectrum f;         // BSDF value (not multiplied by the cosine)
    Vec3 wi;            // sampled direction (world space from BSDF::sample, local from BxDF::sample)
    Float pdf = 0;      // solid-angle pdf of wi (for specular lobes: the discrete lobe probability)
    Float pdfRev = 0;   // pdf of sampling wo given wi, from the same query (0 if not computed)
    unsigned flags = 0; // the sampled lobe's flags
    Float eta = 1;      // relative IOR along the sampled direction (1 for reflection)
    bool valid() const { return pdf > 0 && !f.isBlack(); }
    bool isSpecular() const { return flags & BSDF_SPECULAR; }
    bool isTransmission() const { return flags & BSDF_TRANSMISSION; }
};

class BxDF {
  public:
    explicit BxDF(unsigned flags) : flags_(flags) {}
    virtual ~BxDF() = default;
    unsigned flags() const { return flags_; }
    // f(wo, wi); zero for specular lobes.
    virtual Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const = 0;
    // Samples wi (local). uc picks a lobe, u is 2D. Returns false when no sample.
    virtual bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const = 0;
    // Solid-angle pdf of sampling wi given wo (zero for specular lobes).
    virtual Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const = 0;
    // Lowest roughness (microfacet alpha) among the lobes: 0 for perfectly specular,
    // 1 (or more) for diffuse. Shift mappings classify vertices with it.
    virtual Float roughness() const = 0;
    // eta_inside / eta_outside of a refracting interface (inside = -z); 1 when
    // nothing refracts. Shifts that copy a refraction's half vector need it.
    virtual Float eta() const { return 1; }

  protected:
    // For composite BxDFs whose lobes are known only after construction.
    void addFlags(unsigned f) { flags_ |= f; }

  private:
    unsigned flags_;
};

class BSDF {
  public:
    BSDF() = default;
    // Frame from the interaction's shading normal and shading dpdu.
    BSDF(const SurfaceInteraction &si, const BxDF *bxdf);
    explicit operator bool() const { return bxdf_ != nullptr; }
    const BxDF *bxdf() const { return bxdf_; }
    unsigned flags() const { return bxdf_ ? bxdf_->flags() : 0; }
    bool isSpecular() const { return (flags() & (BSDF_DIFFUSE | BSDF_GLOSSY)) == 0; }
    bool hasNonSpecular() const { return flags() & (BSDF_DIFFUSE | BSDF_GLOSSY); }
    Float roughness() const { return bxdf_ ? bxdf_->roughness() : 0; }
    Float eta() const { return bxdf_ ? bxdf_->eta() : 1; }  // BxDF::eta
    RoughnessClass roughnessClass(Float shiftThreshold) const;

    Vec3 toLocal(const Vec3 &v) const { return frame_.toLocal(v); }
    Vec3 toWorld(const Vec3 &v) const { return frame_.toWorld(v); }
    const Normal3 &ng() const { return ng_; }
    const Normal3 &ns() const { return frame_.n; }

    Spectrum f(const Vec3 &woW, const Vec3 &wiW, TransportMode mode = TransportMode::Radiance) const;
    // Sample in world space; s.wi is world space. Returns false on failure.
    bool sample(const Vec3 &woW, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const;
    Float pdf(const Vec3 &woW, const Vec3 &wiW, TransportMode mode = TransportMode::Radiance) const;
    // Forward pdf (wo -> wi) and reverse pdf (wi -> wo) in one call.
    void pdfs(const Vec3 &woW, const Vec3 &wiW, TransportMode mode, Float *fwd, Float *rev) const;

  private:
    Frame frame_;
    Normal3 ng_;
    const BxDF *bxdf_ = nullptr;
};

}  // namespace gradus
