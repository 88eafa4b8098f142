// pbrt-v3 materials: matte, plastic, metal, mirror, glass, uber, substrate,
// translucent, mix (+ "bumpmap" on each). Parameter names and defaults follow pbrt-v3.
// "gltfpbr" (glTF 2.0 metallic-roughness) lives in gltf_pbr.cpp, "subsurface" and
// "kdsubsurface" in subsurface.cpp.
#include <vector>

#include "materials/bssrdf.h"
#include "materials/bxdfs.h"
#include "materials/disney.h"
#include "materials/fourier.h"
#include "materials/gltf_pbr.h"
#include "materials/hair.h"
#include "materials/material.h"
#include "textures/textures.h"
#include "materials/material_util.h"

namespace gradus {
using namespace matutil;
namespace {

// Roughness parameters shared by the microfacet materials.
struct Roughness {
    std::shared_ptr<FloatTexture> u, v;
    bool remap = true;
    MicrofacetDistribution eval(const SurfaceInteraction &si) const {
        Float ru = u->evaluate(si), rv = v->evaluate(si);
        if (remap) {
            ru = MicrofacetDistribution::RoughnessToAlpha(ru);
            rv = MicrofacetDistribution::RoughnessToAlpha(rv);
        }
        return MicrofacetDistribution(MicrofacetDistribution::TrowbridgeReitz, std::max<Float>(ru, 0),
                                      std::max<Float>(rv, 0));
    }
    // Lowest alpha, 0 if unknown (textured).
    Float minAlpha() const {
        Float a = ConstantOr(u, -1), b = ConstantOr(v, -1);
        if (a < 0 || b < 0) return 0;
        if (remap) {
            a = MicrofacetDistribution::RoughnessToAlpha(a);
            b = MicrofacetDistribution::RoughnessToAlpha(b);
        }
        return std::max<Float>(0, std::min(a, b));
    }
    bool varies() const { return NonConstant(u) || NonConstant(v); }
};

// Copper, pbrt-v3's default "metal": the spectral complex index of refraction of
// copper (measured data as tabulated in Palik's handbook, the data pbrt-v3 ships)
// reduced to linear sRGB, as commonly quoted for RGB renderers. Normal-incidence
// reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2) ~ (0.96, 0.64, 0.54).
const Spectrum kCopperEta(0.200438, 0.924033, 1.10221);
const Spectrum kCopperK(3.91295, 2.45285, 2.14219);

class MatteMaterial : public BumpMaterial {
  public:
    MatteMaterial(std::shared_ptr<SpectrumTexture> kd, std::shared_ptr<FloatTexture> sigma,
                  std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), kd_(std::move(kd)), sigma_(std::move(sigma)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum r = ClampNeg(kd_->evaluate(si));
        Float sig = Clamp<Float>(sigma_->evaluate(si), 0, 90);
        if (sig == 0) return arena.make<LambertianReflection>(r);
        return arena.make<OrenNayar>(r, sig);
    }
    Float minRoughness() const override { return 1; }
    bool texturesVary() const override { return NonConstant(kd_) || NonConstant(sigma_); }

  private:
    std::shared_ptr<SpectrumTexture> kd_;
    std::shared_ptr<FloatTexture> sigma_;
};

class PlasticMaterial : public BumpMaterial {
  public:
    PlasticMaterial(std::shared_ptr<SpectrumTexture> kd, std::shared_ptr<SpectrumTexture> ks, Roughness r,
                    std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), kd_(std::move(kd)), ks_(std::move(ks)), rough_(std::move(r)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        auto *c = arena.make<CompositeBxDF>();
        Spectrum kd = ClampNeg(kd_->evaluate(si)), ks = ClampNeg(ks_->evaluate(si));
        if (!kd.isBlack()) c->add(arena.make<LambertianReflection>(kd));
        if (!ks.isBlack()) {
            // pbrt-v3 compatibility: its plastic evaluates FresnelDielectric(etaI = 1.5,
            // etaT = 1), i.e. the coating seen from inside the 1.5 medium (total internal
            // reflection at grazing half-angles). Scenes written for pbrt-v3 and its
            // references depend on it, so Gradus reproduces it (relative eta 1/1.5).
            MicrofacetDistribution d = rough_.eval(si);
            Fresnel fr = Fresnel::MakeDielectric(1 / 1.5);
            if (d.alphaMin() == 0)
                c->add(arena.make<SpecularReflection>(ks, fr));
            else
                c->add(arena.make<MicrofacetReflection>(ks, d, fr));
        }
        return c->count() ? c : nullptr;
    }
    Float minRoughness() const override { return rough_.minAlpha(); }
    bool texturesVary() const override { return NonConstant(kd_) || NonConstant(ks_) || rough_.varies(); }

  private:
    std::shared_ptr<SpectrumTexture> kd_, ks_;
    Roughness rough_;
};

class MetalMaterial : public BumpMaterial {
  public:
    MetalMaterial(std::shared_ptr<SpectrumTexture> eta, std::shared_ptr<SpectrumTexture> k, Roughness r,
                  std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), eta_(std::move(eta)), k_(std::move(k)), rough_(std::move(r)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Fresnel fr = Fresnel::MakeConductor(eta_->evaluate(si), k_->evaluate(si));
        MicrofacetDistribution d = rough_.eval(si);
        if (d.alphaMin() == 0) return arena.make<SpecularReflection>(Spectrum(1), fr);
        return arena.make<MicrofacetReflection>(Spectrum(1), d, fr);
    }
    Float minRoughness() const override { return rough_.minAlpha(); }
    bool texturesVary() const override { return NonConstant(eta_) || NonConstant(k_) || rough_.varies(); }

  private:
    std::shared_ptr<SpectrumTexture> eta_, k_;
    Roughness rough_;
};

class MirrorMaterial : public BumpMaterial {
  public:
    MirrorMaterial(std::shared_ptr<SpectrumTexture> kr, std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), kr_(std::move(kr)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum r = ClampNeg(kr_->evaluate(si));
        if (r.isBlack()) return nullptr;
        return arena.make<SpecularReflection>(r, Fresnel::One());
    }
    Float minRoughness() const override { return 0; }
    bool texturesVary() const override { return NonConstant(kr_); }

  private:
    std::shared_ptr<SpectrumTexture> kr_;
};

class GlassMaterial : public BumpMaterial {
  public:
    GlassMaterial(std::shared_ptr<SpectrumTexture> kr, std::shared_ptr<SpectrumTexture> kt,
                  std::shared_ptr<FloatTexture> eta, Roughness r, std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), kr_(std::move(kr)), kt_(std::move(kt)), eta_(std::move(eta)),
          rough_(std::move(r)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum R = ClampNeg(kr_->evaluate(si)), T = ClampNeg(kt_->evaluate(si));
        if (R.isBlack() && T.isBlack()) return nullptr;
        Float eta = eta_->evaluate(si);
        Float ru = rough_.u->evaluate(si), rv = rough_.v->evaluate(si);
        // pbrt-v3: zero roughness (before remapping) is a smooth interface.
        if (ru == 0 && rv == 0) return arena.make<SpecularDielectric>(R, T, eta);
        MicrofacetDistribution d = rough_.eval(si);
        if (d.alphaMin() == 0) return arena.make<SpecularDielectric>(R, T, eta);
        return arena.make<MicrofacetDielectric>(R, T, eta, d);
    }
    Float minRoughness() const override {
        Float a = ConstantOr(rough_.u, -1), b = ConstantOr(rough_.v, -1);
        if (a == 0 && b == 0) return 0;
        return rough_.minAlpha();
    }
    bool texturesVary() const override {
        return NonConstant(kr_) || NonConstant(kt_) || NonConstant(eta_) || rough_.varies();
    }

  private:
    std::shared_ptr<SpectrumTexture> kr_, kt_;
    std::shared_ptr<FloatTexture> eta_;
    Roughness rough_;
};

class UberMaterial : public BumpMaterial {
  public:
    std::shared_ptr<SpectrumTexture> kd, ks, kr, kt, opacity;
    std::shared_ptr<FloatTexture> eta;
    Roughness rough;
    explicit UberMaterial(std::shared_ptr<FloatTexture> bump) : BumpMaterial(std::move(bump)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        auto *c = arena.make<CompositeBxDF>();
        Spectrum op = opacity->evaluate(si);
        op = {Clamp<Float>(op.r, 0, 1), Clamp<Float>(op.g, 0, 1), Clamp<Float>(op.b, 0, 1)};
        Spectrum pass = Spectrum(1) - op;
        Float e = eta->evaluate(si);
        if (!pass.isBlack()) c->add(arena.make<SpecularTransmission>(pass, 1.0));
        Spectrum d = op * ClampNeg(kd->evaluate(si));
        if (!d.isBlack()) c->add(arena.make<LambertianReflection>(d));
        Spectrum s = op * ClampNeg(ks->evaluate(si));
        if (!s.isBlack()) {
            MicrofacetDistribution dist = rough.eval(si);
            if (dist.alphaMin() == 0)
                c->add(arena.make<SpecularReflection>(s, Fresnel::MakeDielectric(e)));
            else
                c->add(arena.make<MicrofacetReflection>(s, dist, Fresnel::MakeDielectric(e)));
        }
        Spectrum r = op * ClampNeg(kr->evaluate(si));
        if (!r.isBlack()) c->add(arena.make<SpecularReflection>(r, Fresnel::MakeDielectric(e)));
        Spectrum t = op * ClampNeg(kt->evaluate(si));
        if (!t.isBlack()) c->add(arena.make<SpecularTransmission>(t, e));
        return c->count() ? c : nullptr;
    }
    Float minRoughness() const override {
        // Specular lobes (Kr, Kt, opacity) may be textured on; be conservative.
        return 0;
    }
    bool texturesVary() const override {
        return NonConstant(kd) || NonConstant(ks) || NonConstant(kr) || NonConstant(kt) || NonConstant(opacity) ||
               NonConstant(eta) || rough.varies();
    }
};

class SubstrateMaterial : public BumpMaterial {
  public:
    SubstrateMaterial(std::shared_ptr<SpectrumTexture> kd, std::shared_ptr<SpectrumTexture> ks, Roughness r,
                      std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), kd_(std::move(kd)), ks_(std::move(ks)), rough_(std::move(r)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum d = ClampNeg(kd_->evaluate(si)), s = ClampNeg(ks_->evaluate(si));
        if (d.isBlack() && s.isBlack()) return nullptr;
        MicrofacetDistribution dist = rough_.eval(si);
        if (dist.alphaMin() == 0)  // keep the glossy lobe finite
            dist = MicrofacetDistribution(MicrofacetDistribution::TrowbridgeReitz, 1e-4, 1e-4);
        return arena.make<FresnelBlend>(d, s, dist);
    }
    Float minRoughness() const override { return rough_.minAlpha(); }
    bool texturesVary() const override { return NonConstant(kd_) || NonConstant(ks_) || rough_.varies(); }

  private:
    std::shared_ptr<SpectrumTexture> kd_, ks_;
    Roughness rough_;
};

class TranslucentMaterial : public BumpMaterial {
  public:
    std::shared_ptr<SpectrumTexture> kd, ks, reflect, transmit;
    Roughness rough;
    explicit TranslucentMaterial(std::shared_ptr<FloatTexture> bump) : BumpMaterial(std::move(bump)) {}
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Spectrum r = ClampNeg(reflect->evaluate(si)), t = ClampNeg(transmit->evaluate(si));
        if (r.isBlack() && t.isBlack()) return nullptr;
        auto *c = arena.make<CompositeBxDF>();
        Spectrum d = ClampNeg(kd->evaluate(si));
        if (!d.isBlack()) {
            if (!r.isBlack()) c->add(arena.make<LambertianReflection>(r * d));
            if (!t.isBlack()) c->add(arena.make<LambertianTransmission>(t * d));
        }
        Spectrum s = ClampNeg(ks->evaluate(si));
        if (!s.isBlack()) {
            MicrofacetDistribution dist = rough.eval(si);
            if (dist.alphaMin() == 0)
                c->add(arena.make<SpecularDielectric>(r * s, t * s, 1.5));
            else
                c->add(arena.make<MicrofacetDielectric>(r * s, t * s, 1.5, dist));
        }
        return c->count() ? c : nullptr;
    }
    Float minRoughness() const override { return rough.minAlpha(); }
    bool texturesVary() const override {
        return NonConstant(kd) || NonConstant(ks) || NonConstant(reflect) || NonConstant(transmit) || rough.varies();
    }
};

// pbrt-v3 "mix": materials[0] weighted by amount, materials[1] by (1 - amount).
class MixMaterial : public Material {
  public:
    MixMaterial(std::shared_ptr<Material> a, std::shared_ptr<Material> b, std::shared_ptr<SpectrumTexture> amount)
        : a_(std::move(a)), b_(std::move(b)), amount_(std::move(amount)) {}
    BSDF getBSDF(SurfaceInteraction &si, Arena &arena, TransportMode mode) const override {
        Spectrum s1 = amount_->evaluate(si);
        s1 = {Clamp<Float>(s1.r, 0, 1), Clamp<Float>(s1.g, 0, 1), Clamp<Float>(s1.b, 0, 1)};
        Spectrum s2 = Spectrum(1) - s1;
        SurfaceInteraction si2 = si;
        BSDF b1 = a_->getBSDF(si, arena, mode);
        BSDF b2 = b_->getBSDF(si2, arena, mode);
        auto *c = arena.make<CompositeBxDF>();
        if (b1 && !s1.isBlack()) c->add(arena.make<ScaledBxDF>(b1.bxdf(), s1), s1.average());
        if (b2 && !s2.isBlack()) c->add(arena.make<ScaledBxDF>(b2.bxdf(), s2), s2.average());
        if (!c->count()) return BSDF();
        return BSDF(si, c);
    }
    Float minRoughness() const override { return std::min(a_->minRoughness(), b_->minRoughness()); }
    bool hasTextures() const override {
        return NonConstant(amount_) || a_->hasTextures() || b_->hasTextures();
    }

  private:
    std::shared_ptr<Material> a_, b_;
    std::shared_ptr<SpectrumTexture> amount_;
};

// "interface" / "none": no surface scattering (medium boundaries).
class InterfaceMaterial : public Material {
  public:
    BSDF getBSDF(SurfaceInteraction &, Arena &, TransportMode) const override { return BSDF(); }
    Float minRoughness() const override { return 1; }
};

Roughness ReadRoughness(const ParamSet &p, const NamedTextures &tex, const FileLoc &loc, const char *uName,
                        const char *vName, const char *isoName, Float def) {
    Roughness r;
    std::shared_ptr<FloatTexture> iso = isoName ? GetFloatTextureOrNull(p, isoName, tex, loc) : nullptr;
    if (!iso) iso = std::make_shared<ConstantTexture<Float>>(def);
    r.u = uName ? GetFloatTextureOrNull(p, uName, tex, loc) : nullptr;
    r.v = vName ? GetFloatTextureOrNull(p, vName, tex, loc) : nullptr;
    if (!r.u) r.u = iso;
    if (!r.v) r.v = iso;
    r.remap = p.getBool("remaproughness", true);
    return r;
}

}  // namespace

std::shared_ptr<Material> CreateMaterial(const MaterialDesc &desc, const NamedTextures &tex,
                                         const std::map<std::string, std::shared_ptr<Material>> &named,
                                         const SceneDesc *scene, std::vector<std::string> *notes) {
    const ParamSet &p = desc.params;
    const FileLoc &loc = desc.loc;
    const std::string &t = desc.type;
    if (t == "hair") return CreateHairMaterial(p, tex, loc, notes);  // no bumpmap in pbrt-v3's hair
    if (t == "" || t == "none" || t == "interface") return std::make_shared<InterfaceMaterial>();
    if (t == "mix") {
        std::vector<std::string> names = p.getStrings("materials");
        if (names.size() != 2)
            throw Error(p.locOf("materials", loc), "\"mix\" material needs \"string materials\" with two names");
        std::shared_ptr<Material> m[2];
        for (int i = 0; i < 2; ++i) {
            auto it = named.find(names[i]);
            if (it == named.end() || !it->second)
                throw Error(p.locOf("materials", loc), "named material \"" + names[i] + "\" is not defined");
            m[i] = it->second;
        }
        auto amount = GetSpectrumTexture(p, "amount", Spectrum(0.5), tex, loc);
        return std::make_shared<MixMaterial>(m[0], m[1], amount);
    }
    auto bump = GetFloatTextureOrNull(p, "bumpmap", tex, loc);
    if (t == "matte") {
        return std::make_shared<MatteMaterial>(GetSpectrumTexture(p, "Kd", Spectrum(0.5), tex, loc),
                                               GetFloatTexture(p, "sigma", 0, tex, loc), bump);
    }
    if (t == "plastic") {
        auto kd = GetSpectrumTexture(p, "Kd", Spectrum(0.25), tex, loc);
        auto ks = GetSpectrumTexture(p, "Ks", Spectrum(0.25), tex, loc);
        return std::make_shared<PlasticMaterial>(kd, ks, ReadRoughness(p, tex, loc, nullptr, nullptr, "roughness", 0.1),
                                                 bump);
    }
    if (t == "metal") {
        auto eta = GetSpectrumTexture(p, "eta", kCopperEta, tex, loc);
        auto k = GetSpectrumTexture(p, "k", kCopperK, tex, loc);
        return std::make_shared<MetalMaterial>(
            eta, k, ReadRoughness(p, tex, loc, "uroughness", "vroughness", "roughness", 0.01), bump);
    }
    if (t == "mirror") return std::make_shared<MirrorMaterial>(GetSpectrumTexture(p, "Kr", Spectrum(0.9), tex, loc), bump);
    if (t == "glass") {
        auto kr = GetSpectrumTexture(p, "Kr", Spectrum(1), tex, loc);
        auto kt = GetSpectrumTexture(p, "Kt", Spectrum(1), tex, loc);
        auto eta = GetFloatTextureOrNull(p, "eta", tex, loc);
        if (!eta) eta = GetFloatTexture(p, "index", 1.5, tex, loc);
        return std::make_shared<GlassMaterial>(kr, kt, eta,
                                               ReadRoughness(p, tex, loc, "uroughness", "vroughness", nullptr, 0), bump);
    }
    if (t == "uber") {
        auto m = std::make_shared<UberMaterial>(bump);
        m->kd = GetSpectrumTexture(p, "Kd", Spectrum(0.25), tex, loc);
        m->ks = GetSpectrumTexture(p, "Ks", Spectrum(0.25), tex, loc);
        m->kr = GetSpectrumTexture(p, "Kr", Spectrum(0), tex, loc);
        m->kt = GetSpectrumTexture(p, "Kt", Spectrum(0), tex, loc);
        m->opacity = GetSpectrumTexture(p, "opacity", Spectrum(1), tex, loc);
        m->rough = ReadRoughness(p, tex, loc, "uroughness", "vroughness", "roughness", 0.1);
        m->eta = GetFloatTextureOrNull(p, "eta", tex, loc);
        if (!m->eta) m->eta = GetFloatTexture(p, "index", 1.5, tex, loc);
        return m;
    }
    if (t == "substrate") {
        auto kd = GetSpectrumTexture(p, "Kd", Spectrum(0.5), tex, loc);
        auto ks = GetSpectrumTexture(p, "Ks", Spectrum(0.5), tex, loc);
        return std::make_shared<SubstrateMaterial>(
            kd, ks, ReadRoughness(p, tex, loc, "uroughness", "vroughness", nullptr, 0.1), bump);
    }
    if (t == "translucent") {
        auto m = std::make_shared<TranslucentMaterial>(bump);
        m->kd = GetSpectrumTexture(p, "Kd", Spectrum(0.25), tex, loc);
        m->ks = GetSpectrumTexture(p, "Ks", Spectrum(0.25), tex, loc);
        m->reflect = GetSpectrumTexture(p, "reflect", Spectrum(0.5), tex, loc);
        m->transmit = GetSpectrumTexture(p, "transmit", Spectrum(0.5), tex, loc);
        m->rough = ReadRoughness(p, tex, loc, nullptr, nullptr, "roughness", 0.1);
        return m;
    }
    if (t == "gltfpbr") return CreateGltfPbrMaterial(p, tex, loc, bump);
    if (t == "disney") return CreateDisneyMaterial(p, tex, loc, bump);
    if (t == "subsurface" || t == "kdsubsurface") return CreateSubsurfaceMaterial(t, p, tex, loc, bump);
    if (t == "fourier") return CreateFourierMaterial(p, scene, loc, bump);
    throw Error(loc, "unknown material type \"" + t +
                         "\" (known: matte, plastic, metal, mirror, glass, uber, substrate, translucent, mix, gltfpbr, subsurface, kdsubsurface, disney, fourier, hair)");
}

}  // namespace gradus
