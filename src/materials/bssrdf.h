// Subsurface scattering as pbrt-v3 defines it: a separable BSSRDF
//   S(po, wo, pi, wi) ~ (1 - Fr(cos theta_o)) * Sp(|po - pi|) * Sw(wi)
// (the factorisation of Jensen et al. 2001, "A practical model for subsurface light
// transport"), whose radial profile Sr is tabulated over the single-scattering albedo
// rho and the optical radius r * sigma_t by photon beam diffusion (Habel, Christensen &
// Jarosz 2013: the dipole integrated along the refracted beam, plus single scattering),
// with the diffusion coefficient, boundary condition and Fresnel moments of d'Eon &
// Irving 2011 ("A quantized-diffusion model for rendering translucent materials").
//
// The (1 - Fr) factor at po is the interface BSDF's transmission (the material's
// dielectric lobe); Sp is sampled by probe rays (integrators/path/subsurface.h, which
// needs the Scene); Sw is the exit BxDF SubsurfaceExitBxDF.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "materials/bsdf.h"
#include "materials/material.h"

namespace gradus {

// ---------------------------------------------------------------------------
// Catmull-Rom splines through (nodes[i], f[i]) on non-uniform nodes: cubic Hermite
// segments whose tangents are finite differences over the neighbouring nodes
// (one-sided at the ends).

// Weights w[k] of nodes offset + k (k = 0..3) such that the spline at x is
// sum_k w[k] f[offset + k]. Nodes outside [0, n) get weight exactly 0 (callers skip
// zero weights). False when x lies outside [nodes[0], nodes[n - 1]].
bool CatmullRomWeights(int n, const Float *nodes, Float x, int *offset, Float w[4]);
// Integral of the spline over [x[0], x[n-1]]; cdf[i] receives the integral up to x[i].
Float IntegrateCatmullRom(int n, const Float *x, const Float *f, Float *cdf);
// The x at which the spline through increasing values f equals u (clamped to the ends).
Float InvertCatmullRom(int n, const Float *x, const Float *f, Float u);
// Samples x proportionally to the spline f(alpha, x) of a 2-D table (rows over nodes1,
// each of n2 values on nodes2, with per-row cdfs from IntegrateCatmullRom), the rows
// interpolated at alpha. Returns x (or -1 when the interpolated row has no mass);
// *fval = f(alpha, x), *pdf = f(alpha, x) / integral.
Float SampleCatmullRom2D(int n1, int n2, const Float *nodes1, const Float *nodes2, const Float *values,
                         const Float *cdf, Float alpha, Float u, Float *fval = nullptr, Float *pdf = nullptr);

// ---------------------------------------------------------------------------
// Photon beam diffusion (all lengths in units of 1 / sigma_t when sigma_t = 1).

// Polynomial fits (d'Eon & Irving 2011) of the first and second angular moments of
// the dielectric Fresnel reflectance, eta the relative index of the interface.
Float FresnelMoment1(Float eta);
Float FresnelMoment2(Float eta);
// Multiple-scattering exitance at radius r of a beam entering at normal incidence:
// the classical dipole (Grosjean's D, extrapolated boundary z_e) integrated over the
// beam's real-source depths by exponential quadrature (Habel et al. 2013, Eq. 9-11).
Float BeamDiffusionMS(Float sigmaS, Float sigmaA, Float g, Float eta, Float r);
// Single-scattering exitance at radius r (Habel et al. 2013, Eq. 6): depths below the
// critical-angle depth t_crit, exponentially sampled, Henyey-Greenstein phase.
Float BeamDiffusionSS(Float sigmaS, Float sigmaA, Float g, Float eta, Float r);

// The profile table: 2 pi r Sr(rho, r) for sigma_t = 1, rows over rho.
struct BSSRDFTable {
    std::vector<Float> rho;         // albedo nodes in [0, 1]
    std::vector<Float> radius;      // optical radius nodes, radius[0] = 0
    std::vector<Float> profile;     // nRho x nRadius: 2 pi r (SS + MS)
    std::vector<Float> profileCDF;  // per row: integral of profile up to each radius node
    std::vector<Float> rhoEff;      // per row: the total (effective albedo)
    int nRho() const { return int(rho.size()); }
    int nRadius() const { return int(radius.size()); }
    Float profileAt(int iRho, int iRadius) const { return profile[size_t(iRho) * radius.size() + iRadius]; }
};
// pbrt-v3's discretisation: 100 albedos (denser near 1), 64 radii (0, 2.5e-3 * 1.2^k).
BSSRDFTable ComputeBeamDiffusionTable(Float g, Float eta, int nRho = 100, int nRadius = 64);
// Albedo and coefficients whose effective albedo is rhoEff with sigma_t = 1 / mfp,
// per channel (pbrt-v3's SubsurfaceFromDiffuse; rhoEff above the table's range gives rho = 1).
void SubsurfaceFromDiffuse(const BSSRDFTable &table, const Spectrum &rhoEff, const Spectrum &mfp,
                           Spectrum *sigmaA, Spectrum *sigmaS);

// ---------------------------------------------------------------------------
// pbrt-v3's TabulatedBSSRDF at an entry point po (arena-allocated by
// Material::getBSSRDF). Coefficients are per world unit.
class BSSRDF {
  public:
    static constexpr int kChannels = 3;
    BSSRDF(const SurfaceInteraction &po, const Material *material, Float eta, const Spectrum &sigmaA,
           const Spectrum &sigmaS, const BSSRDFTable &table);

    // Radial profile Sr(r) (per unit area), clamped at 0.
    Spectrum Sr(Float r) const;
    Spectrum Sp(const Point3 &pi) const { return Sr(Distance(po_, pi)); }
    // Samples a radius for channel ch proportionally to r Sr_ch(r); -1 when none.
    Float sampleSr(int ch, Float u) const;
    // Density of sampleSr over the plane: Sr_ch(r) / rho_eff (per unit area).
    Float pdfSr(int ch, Float r) const;
    // Area density of reaching pi (geometric normal ni) by the probe-ray strategy:
    // the three projection axes (probabilities .25, .25, .5 for ss, ts, ns) times the
    // channels, each weighted by |cos| between the axis and ni (pbrt-v3's Pdf_Sp).
    Float pdfSp(const Point3 &pi, const Normal3 &ni) const;

    const Point3 &po() const { return po_; }
    const Vec3 &ss() const { return ss_; }
    const Vec3 &ts() const { return ts_; }
    const Vec3 &ns() const { return ns_; }
    const Material *material() const { return material_; }
    Float eta() const { return eta_; }
    const Spectrum &sigmaT() const { return sigmaT_; }
    const Spectrum &rho() const { return rho_; }

  private:
    // Interpolated table value (2 pi r Sr for sigma_t = 1) at (rho, rOptical) and the
    // row's rho_eff; false outside the table.
    bool lookup(Float rho, Float rOptical, Float *value, Float *rhoEff) const;
    Point3 po_;
    Vec3 ss_, ts_, ns_;  // orthonormal frame at po (shading normal, shading dpdu)
    const Material *material_;
    Float eta_;
    Spectrum sigmaT_, rho_;
    const BSSRDFTable *table_;
};

// Sw: the exit lobe at pi, a normalised Fresnel-weighted diffuse reflection
//   f = (1 - Fr(cos theta_i)) / (c pi),  c = 1 - 2 FresnelMoment1(1 / eta),
// times eta^2 in radiance transport (pbrt-v3's SeparableBSSRDFAdapter). Cosine-sampled.
class SubsurfaceExitBxDF : public BxDF {
  public:
    explicit SubsurfaceExitBxDF(Float eta);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    Float roughness() const override { return 1; }

  private:
    Float eta_, invNorm_;  // 1 / (c pi)
};

// The pbrt-v3 materials "subsurface" and "kdsubsurface" (subsurface.cpp): reads
// their parameters (bad values throw located errors).
std::shared_ptr<Material> CreateSubsurfaceMaterial(const std::string &type, const ParamSet &params,
                                                   const NamedTextures &textures, const FileLoc &loc,
                                                   std::shared_ptr<FloatTexture> bump);

}  // namespace gradus
