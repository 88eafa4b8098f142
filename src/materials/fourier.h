// pbrt-v3's "fourier" material: the tabulated isotropic BSDF of Jakob et al. 2014,
// "A comprehensive framework for rendering layered materials" (Sec. 4 and 6), read
// from the binary ".bsdf" files that layerlab writes and pbrt-v3 renders.
//
// The table stores, for every pair of zenith-cosine nodes (mu_o, mu_i), the cosine
// series of f(mu_i, mu_o, phi) |mu_i| in the azimuth difference phi (paper Eq. 8):
//   f |mu_i| = sum_k a_k(mu_i, mu_o) cos(k phi),
// with the a_k interpolated between nodes by Catmull-Rom splines in both cosines.
// Conventions as pbrt-v3: mu_i = cos(-wi), mu_o = cos(wo), so mu_i mu_o < 0 is
// reflection; phi is the azimuth of -wi relative to wo. Three-channel files hold
// luminance, red and blue. Transmission in radiance transport is scaled by
// (eta_o / eta_i)^2. One deviation from pbrt-v3: the mu_o stencil stays within wo's
// hemisphere (see RowsFor in fourier.cpp), so that sample() and pdf() agree at
// grazing wo, where pbrt-v3 blends the reflection and transmission tables.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "materials/bsdf.h"
#include "materials/material.h"

namespace gradus {

struct FourierTable {
    Float eta = 1;              // relative index of the layer's interface (inside = -z)
    int nMu = 0, nChannels = 1;
    int mMax = 0;               // longest series present in the file
    std::vector<Float> mu;      // nMu non-decreasing nodes in [-1, 1] (+-0 may both appear)
    int posStart = 0;           // first node with a clear sign bit (the upper hemisphere)
    std::vector<Float> a0;      // nMu * nMu luminance a_0, row o (mu_o) column i (mu_i)
    std::vector<Float> cdf;     // per row: Catmull-Rom integral of a0 up to mu_i (recomputed)
    std::vector<int> offset, length;  // nMu * nMu: where each series starts, its order count
    std::vector<Float> coeffs;  // entry e, channel c, order k at offset[e] + c * length[e] + k
    bool reflects = false, transmits = false;  // any nonzero coefficient on that side

    // Reads and checks a .bsdf file. Every defect (unreadable, wrong identifier, short
    // or inconsistent file, unsupported variant, non-finite value) throws Error(loc, ...)
    // naming the path.
    static std::shared_ptr<const FourierTable> Read(const std::string &path, const FileLoc &loc);
};

class FourierBxDF : public BxDF {
  public:
    explicit FourierBxDF(const FourierTable *t);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    // A cosine series of order mMax cannot resolve azimuthal features narrower than
    // about pi / mMax radians: reported as the lobe's roughness (at most 1).
    Float roughness() const override;
    Float eta() const override { return t_->transmits ? t_->eta : 1; }

  private:
    const FourierTable *t_;
};

// "Material "fourier"": string bsdffile (resolved against the scene directory when
// `scene` is given), float bumpmap.
std::shared_ptr<Material> CreateFourierMaterial(const ParamSet &params, const SceneDesc *scene, const FileLoc &loc,
                                                std::shared_ptr<FloatTexture> bump);

}  // namespace gradus
