// pbrt-v3's "hair" material: the fibre scattering model of Chiang, Bitterli,
// Tappan and Burley 2016 ("A Practical and Controllable Hair and Fur Model for
// Production Path Tracing"), with the lobe and sampling structure pbrt-v3 uses.
//
// Local frame: x along the fibre (shading dpdu), z the shading normal; theta is
// the longitudinal angle (sin theta = w.x), phi the azimuth in the y-z plane.
//   S(wo, wi) = sum_{p<pMax} M_p(theta_i, theta_o) A_p N_p(phi) + M_pMax A_pMax / (2 pi),
// f = S / |cos wi| to the shading normal (the integrators multiply it back).
//   M_p: d'Eon et al. 2011's longitudinal lobe (Chiang Eq. 7 maps beta_m to its
//        variance v; v_R = v, v_TT = v/4, v_TRT = 4v), with the low-variance
//        log form for v <= 0.1 and scale tilts -2a, a, 4a of theta_o for R, TT,
//        TRT (pbrt-v3's final form: each M_p stays normalised in theta_i);
//   A_p: Fresnel and absorption along p internal segments (Chiang Eq. 3-4), the
//        p >= pMax tail summed as a geometric series;
//   N_p: trimmed logistic in phi around Phi(p) = 2 p gamma_t - 2 gamma_o + p pi
//        (Chiang Eq. 8 maps beta_n to the logistic scale s).
// Sampling picks p by the luminance of A_p, samples M_p exactly and N_p by its
// inverse CDF; pdf() is the full mixture density. h in [-1, 1] is the offset
// across the fibre, -1 + 2 v of the hit (shapes/curve.h: pbrt-v3's v), fixed
// by the hit for both directions as in pbrt-v3.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "materials/bsdf.h"
#include "materials/material.h"

namespace gradus {

class HairBxDF : public BxDF {
  public:
    static constexpr int pMax = 3;
    // alpha in degrees; beta_m, beta_n clamped to [0, 1], h to [-1, 1], eta to >= 1.
    // f = S(wo, wi) / |cos wi| (S: the lobe sum below). S is not reciprocal:
    // Importance mode evaluates S(wi, wo) / |cos wi|, so light and camera subpaths
    // agree on each vertex's value whatever the normal.
    HairBxDF(Float h, Float eta, const Spectrum &sigmaA, Float betaM, Float betaN, Float alphaDegrees);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    // min(beta_m, beta_n), at least kDefaultShiftThreshold: a fibre scatters over
    // its whole cross-section, never a specular chain member (Rough class).
    Float roughness() const override;

    // A_p for a direction with cos(theta_o) at offset h (Chiang Eq. 3-4, pbrt-v3's tail term).
    std::array<Spectrum, pMax + 1> attenuation(Float cosThetaO, Float h) const;
    std::array<Spectrum, pMax + 1> attenuation(Float cosThetaO) const { return attenuation(cosThetaO, h_); }
    // Lobe selection probabilities (luminance of A_p, normalised).
    std::array<Float, pMax + 1> lobePdf(Float cosThetaO, Float h) const;

    // sigma_a from melanin concentrations (pbrt-v3's RGB absorption of eumelanin
    // and pheomelanin) and from a colour through Chiang Eq. 9's inverse.
    static Spectrum SigmaAFromConcentration(Float eumelanin, Float pheomelanin);
    static Spectrum SigmaAFromReflectance(const Spectrum &color, Float betaN);

  private:
    Spectrum scattering(const Vec3 &wo, const Vec3 &wi) const;  // S: the lobe sum, no cosine
    void tiltO(int p, Float sinThetaO, Float cosThetaO, Float *s, Float *c) const;
    Float h_;
    Float eta_, betaM_, betaN_, s_;
    Spectrum sigmaA_;
    Float v_[pMax + 1];
    Float sin2kAlpha_[3], cos2kAlpha_[3];
};

// The "hair" material (called by CreateMaterial). Parameters as pbrt-v3:
// sigma_a, color, eumelanin, pheomelanin (precedence in that order; none given:
// eumelanin 1.3), eta 1.55, beta_m 0.3, beta_n 0.3, alpha 2 (degrees). A
// parameter the precedence ignores adds a located note to `notes` (when given),
// as pbrt-v3 warns.
std::shared_ptr<Material> CreateHairMaterial(const ParamSet &params, const NamedTextures &textures, const FileLoc &loc,
                                             std::vector<std::string> *notes = nullptr);

}  // namespace gradus
