// pbrt-v3's "subsurface" and "kdsubsurface" materials: a dielectric interface (as
// "glass": specular when both roughnesses are 0, else rough reflection + transmission)
// over a tabulated photon-beam-diffusion BSSRDF (bssrdf.h). Parameter names and
// defaults follow pbrt-v3; coefficients are per mm times "scale", per world unit.
#include <cmath>

#include "core/error.h"
#include "materials/bssrdf.h"
#include "materials/bxdfs.h"
#include "materials/material_util.h"
#include "media/medium.h"

namespace gradus {
using namespace matutil;
namespace {

// The interface and the table shared by the two materials.
class SubsurfaceBase : public BumpMaterial {
  public:
    struct Interface {
        std::shared_ptr<SpectrumTexture> kr, kt;
        std::shared_ptr<FloatTexture> uRough, vRough;
        bool remap = true;
        Float eta = 1.33;
    };
    SubsurfaceBase(Interface in, Float g, std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), in_(std::move(in)), table_(ComputeBeamDiffusionTable(g, in_.eta)) {}

    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum R = ClampNeg(in_.kr->evaluate(si)), T = ClampNeg(in_.kt->evaluate(si));
        if (R.isBlack() && T.isBlack()) return nullptr;
        Float ru = in_.uRough->evaluate(si), rv = in_.vRough->evaluate(si);
        // pbrt-v3: zero roughness (before remapping) is a smooth interface.
        if (ru == 0 && rv == 0) return arena.make<SpecularDielectric>(R, T, in_.eta);
        if (in_.remap) {
            ru = MicrofacetDistribution::RoughnessToAlpha(ru);
            rv = MicrofacetDistribution::RoughnessToAlpha(rv);
        }
        MicrofacetDistribution d(MicrofacetDistribution::TrowbridgeReitz, std::max<Float>(ru, 0),
                                 std::max<Float>(rv, 0));
        if (d.alphaMin() == 0) return arena.make<SpecularDielectric>(R, T, in_.eta);
        return arena.make<MicrofacetDielectric>(R, T, in_.eta, d);
    }
    const BSSRDF *getBSSRDF(const SurfaceInteraction &si, Arena &arena) const override {
        // pbrt-v3 builds no BSSRDF when the interface has no lobe.
        if (ClampNeg(in_.kr->evaluate(si)).isBlack() && ClampNeg(in_.kt->evaluate(si)).isBlack()) return nullptr;
        Spectrum sa, ss;
        coefficients(si, &sa, &ss);
        return arena.make<BSSRDF>(si, this, in_.eta, sa, ss, table_);
    }
    bool hasSubsurface() const override { return true; }
    Float minRoughness() const override {
        Float a = ConstantOr(in_.uRough, -1), b = ConstantOr(in_.vRough, -1);
        if (a < 0 || b < 0 || (a == 0 && b == 0)) return 0;
        if (in_.remap) {
            a = MicrofacetDistribution::RoughnessToAlpha(a);
            b = MicrofacetDistribution::RoughnessToAlpha(b);
        }
        return std::max<Float>(0, std::min(a, b));
    }
    bool texturesVary() const override {
        return NonConstant(in_.kr) || NonConstant(in_.kt) || NonConstant(in_.uRough) || NonConstant(in_.vRough) ||
               coefficientsVary();
    }
    const BSSRDFTable &table() const { return table_; }

  protected:
    // Absorption and scattering coefficients per world unit at si.
    virtual void coefficients(const SurfaceInteraction &si, Spectrum *sigmaA, Spectrum *sigmaS) const = 0;
    virtual bool coefficientsVary() const = 0;

  private:
    Interface in_;
    BSSRDFTable table_;
};

class SubsurfaceMaterial : public SubsurfaceBase {
  public:
    SubsurfaceMaterial(Interface in, Float g, Float scale, std::shared_ptr<SpectrumTexture> sigmaA,
                       std::shared_ptr<SpectrumTexture> sigmaS, std::shared_ptr<FloatTexture> bump)
        : SubsurfaceBase(std::move(in), g, std::move(bump)), scale_(scale), sigmaA_(std::move(sigmaA)),
          sigmaS_(std::move(sigmaS)) {}

  protected:
    void coefficients(const SurfaceInteraction &si, Spectrum *sa, Spectrum *ss) const override {
        *sa = ClampNeg(sigmaA_->evaluate(si)) * scale_;
        *ss = ClampNeg(sigmaS_->evaluate(si)) * scale_;
    }
    bool coefficientsVary() const override { return NonConstant(sigmaA_) || NonConstant(sigmaS_); }

  private:
    Float scale_;
    std::shared_ptr<SpectrumTexture> sigmaA_, sigmaS_;
};

class KdSubsurfaceMaterial : public SubsurfaceBase {
  public:
    KdSubsurfaceMaterial(Interface in, Float g, Float scale, std::shared_ptr<SpectrumTexture> kd,
                         std::shared_ptr<SpectrumTexture> mfp, std::shared_ptr<FloatTexture> bump)
        : SubsurfaceBase(std::move(in), g, std::move(bump)), scale_(scale), kd_(std::move(kd)),
          mfp_(std::move(mfp)) {}

  protected:
    void coefficients(const SurfaceInteraction &si, Spectrum *sa, Spectrum *ss) const override {
        Spectrum mfp = ClampNeg(mfp_->evaluate(si)) * scale_;
        SubsurfaceFromDiffuse(table(), ClampNeg(kd_->evaluate(si)), mfp, sa, ss);
        // A zero mean free path (textured) would give infinite coefficients: no subsurface light.
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite((*sa)[c]) || !std::isfinite((*ss)[c])) (*sa)[c] = (*ss)[c] = 0;
    }
    bool coefficientsVary() const override { return NonConstant(kd_) || NonConstant(mfp_); }

  private:
    Float scale_;
    std::shared_ptr<SpectrumTexture> kd_, mfp_;
};

bool BadComponent(const Spectrum &s, bool zeroIsBad) {
    for (int c = 0; c < 3; ++c)
        if (!(s[c] >= 0) || !std::isfinite(s[c]) || (zeroIsBad && s[c] == 0)) return true;
    return false;
}

// A constant spectrum parameter with a negative, NaN or infinite (or, with
// zeroIsBad, zero) component is a located error; textures are clamped when evaluated.
void CheckSpectrum(const ParamSet &p, const std::string &name, const std::shared_ptr<SpectrumTexture> &t,
                   const FileLoc &loc, bool zeroIsBad, const std::string &what) {
    auto c = dynamic_cast<const ConstantTexture<Spectrum> *>(t.get());
    if (c && BadComponent(c->value(), zeroIsBad)) {
        const Spectrum &v = c->value();
        throw Error(p.locOf(name, loc), "\"" + name + "\" must be " + what + " (got " + std::to_string(v.r) + " " +
                                            std::to_string(v.g) + " " + std::to_string(v.b) + ")");
    }
}

Float PositiveFloat(const ParamSet &p, const std::string &name, Float def, const FileLoc &loc, bool zeroOk) {
    Float v = p.getFloat(name, def);
    if (!std::isfinite(v) || v < 0 || (!zeroOk && v == 0))
        throw Error(p.locOf(name, loc),
                    "\"" + name + "\" must be " + (zeroOk ? "non-negative" : "positive") + " (got " + std::to_string(v) + ")");
    return v;
}

}  // namespace

std::shared_ptr<Material> CreateSubsurfaceMaterial(const std::string &type, const ParamSet &p,
                                                   const NamedTextures &tex, const FileLoc &loc,
                                                   std::shared_ptr<FloatTexture> bump) {
    SubsurfaceBase::Interface in;
    in.kr = GetSpectrumTexture(p, "Kr", Spectrum(1), tex, loc);
    in.kt = GetSpectrumTexture(p, "Kt", Spectrum(1), tex, loc);
    in.uRough = GetFloatTexture(p, "uroughness", 0, tex, loc);
    in.vRough = GetFloatTexture(p, "vroughness", 0, tex, loc);
    in.remap = p.getBool("remaproughness", true);
    in.eta = PositiveFloat(p, "eta", 1.33, loc, false);
    Float scale = PositiveFloat(p, "scale", 1, loc, true);
    Float g = p.getFloat("g", 0);
    if (!(std::abs(g) < 1)) throw Error(p.locOf("g", loc), "\"g\" must lie in (-1, 1) (got " + std::to_string(g) + ")");

    if (type == "kdsubsurface") {
        auto kd = GetSpectrumTexture(p, "Kd", Spectrum(0.5), tex, loc);
        // pbrt-v3's default mean free path is 0.5 (its Kd default reused).
        auto mfp = GetSpectrumTexture(p, "mfp", Spectrum(0.5), tex, loc);
        CheckSpectrum(p, "Kd", kd, loc, false, "non-negative");
        CheckSpectrum(p, "mfp", mfp, loc, true, "positive");
        return std::make_shared<KdSubsurfaceMaterial>(std::move(in), g, scale, kd, mfp, std::move(bump));
    }
    // "subsurface": pbrt-v3's defaults are whole milk's coefficients (mm^-1).
    Spectrum sa(0.0011, 0.0024, 0.014), ss(2.55, 3.21, 3.77);
    std::string name = p.getString("name", "");
    if (!name.empty()) {
        if (!MediumPreset(name, &sa, &ss)) {
            std::string known;
            for (const std::string &n : MediumPresetNames()) known += (known.empty() ? "" : ", ") + n;
            throw Error(p.locOf("name", loc), "unknown measured subsurface preset \"" + name + "\" (known: " + known + ")");
        }
        // The measured data are reduced scattering coefficients: pbrt-v3 forces g = 0.
        g = 0;
    }
    auto sigmaA = GetSpectrumTexture(p, "sigma_a", sa, tex, loc);
    auto sigmaS = GetSpectrumTexture(p, "sigma_s", ss, tex, loc);
    CheckSpectrum(p, "sigma_a", sigmaA, loc, false, "non-negative");
    CheckSpectrum(p, "sigma_s", sigmaS, loc, false, "non-negative");
    return std::make_shared<SubsurfaceMaterial>(std::move(in), g, scale, sigmaA, sigmaS, std::move(bump));
}

}  // namespace gradus
