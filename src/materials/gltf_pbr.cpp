#include "materials/gltf_pbr.h"

#include "materials/bxdf_util.h"
#include "materials/material_util.h"

namespace gradus {
using namespace bxdfutil;
using namespace matutil;

namespace {
inline Float Pow5(Float x) { return (x * x) * (x * x) * x; }
inline Spectrum Clamp01(const Spectrum &s) {
    return {Clamp<Float>(s.r, 0, 1), Clamp<Float>(s.g, 0, 1), Clamp<Float>(s.b, 0, 1)};
}
inline Float Clamp01(Float x) { return std::isnan(x) ? 0 : Clamp<Float>(x, 0, 1); }
}  // namespace

// ---------------------------------------------------------------- BxDF
GltfPbrBxDF::GltfPbrBxDF(const Spectrum &baseColor, Float metallic, Float alpha, Float ior, Float transmission)
    : BxDF(BSDF_NONE), base_(Clamp01(baseColor)), metallic_(Clamp01(metallic)), alpha_(Clamp01(alpha)),
      ior_(std::isnan(ior) ? 1.5 : Clamp<Float>(ior, 1, 1e4)), t_(Clamp01(transmission)),
      d_(MicrofacetDistribution::TrowbridgeReitz, alpha_, alpha_) {
    f0_ = Sqr((ior_ - 1) / (ior_ + 1));  // KHR_materials_ior
    kd_ = (1 - metallic_) * (1 - t_);
    kt_ = (1 - metallic_) * t_;
    bool colored = base_.maxComponent() > 0;
    hasDiffuse_ = kd_ > 0 && colored;
    hasTrans_ = kt_ > 0 && colored;
    smoothR_ = alpha_ < SmoothAlpha;
    // The refracted lobe's width scales with alpha (1 - 1/eta): at ior = 1 it is a
    // delta (straight through) whatever alpha.
    smoothT_ = smoothR_ || alpha_ * (1 - 1 / ior_) < SmoothAlpha;
    unsigned fl = BSDF_REFLECTION | (smoothR_ ? BSDF_SPECULAR : BSDF_GLOSSY);
    if (hasDiffuse_) fl |= BSDF_DIFFUSE;
    if (hasTrans_) fl |= BSDF_TRANSMISSION | (smoothT_ ? BSDF_SPECULAR : BSDF_GLOSSY);
    addFlags(fl);
}

Float GltfPbrBxDF::roughness() const { return smoothR_ || (hasTrans_ && smoothT_) ? 0 : alpha_; }

// Appendix B, fresnel_mix: F = f0 + (1 - f0)(1 - |V.H|)^5.
Float GltfPbrBxDF::fresnelD(Float c) const { return f0_ + (1 - f0_) * Pow5(1 - Clamp01(c)); }

Spectrum GltfPbrBxDF::fresnelMix(Float c) const {
    Float w = Pow5(1 - Clamp01(c));
    Spectrum metal = base_ + (Spectrum(1) - base_) * w;  // Appendix B, metal_brdf
    return Spectrum(fresnelD(c) * (1 - metallic_)) + metal * metallic_;
}

GltfPbrBxDF::LobeProbs GltfPbrBxDF::lobeProbs(const Vec3 &wo) const {
    // Approximate lobe albedos with the Fresnel terms at the normal-incidence half
    // vector; the specular weight has a floor so that it covers all reflections.
    Float c = AbsCosTheta(wo), Fd = fresnelD(c), avg = base_.average();
    Float ws = std::max<Float>(0.05, (1 - metallic_) * Fd + metallic_ * fresnelMix(c).average());
    Float wd = hasDiffuse_ ? kd_ * avg * (1 - f0_) : 0;
    Float wt = hasTrans_ ? std::max<Float>(kt_ * avg * (1 - Fd), 1e-3 * kt_) : 0;
    Float sum = ws + wd + wt;
    LobeProbs p;
    p.diffuse = wd / sum;
    p.transmission = wt / sum;
    p.specular = 1 - p.diffuse - p.transmission;
    return p;
}

Spectrum GltfPbrBxDF::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    Float cosO = AbsCosTheta(wo), cosI = AbsCosTheta(wi);
    if (cosO == 0 || cosI == 0) return Spectrum(0);
    if (SameHemisphere(wo, wi)) {
        Vec3 wh;
        if (!ReflectionHalf(wo, wi, &wh)) return Spectrum(0);
        Float vh = AbsDot(wo, wh);
        Spectrum r(0);
        if (hasDiffuse_) r = base_ * (kd_ * (1 - fresnelD(vh)) * InvPi);
        if (!smoothR_) {
            // D V with V = G / (4 |N.L| |N.V|), G height-correlated Smith (Appendix B).
            Float dv = d_.D(wh) * d_.G(wo, wi) / (4 * cosO * cosI);
            r += fresnelMix(vh) * dv;
        }
        return r;
    }
    if (!hasTrans_ || smoothT_) return Spectrum(0);
    Vec3 wh;
    Float etap;
    if (!RefractionHalf(wo, wi, ior_, &wh, &etap)) return Spectrum(0);
    Float oh = Dot(wo, wh), ih = Dot(wi, wh);
    Float denom = Sqr(ih + oh / etap);
    if (!(denom > 0)) return Spectrum(0);
    // KHR_materials_transmission's specular_btdf as Walter et al. 2007, Eq. 21 (divided
    // by eta_o^2, Fresnel left out: fresnel_mix applies 1 - F_d). F_d at the
    // cosine on the outside (z > 0) keeps f(wo, wi) = f*(wi, wo) (adjoint).
    Float btdf = d_.D(wh) * d_.G(wo, wi) * std::abs(oh * ih) / (cosO * cosI * denom);
    if (mode == TransportMode::Radiance) btdf /= etap * etap;
    Float cOut = wo.z > 0 ? std::abs(oh) : std::abs(ih);
    return base_ * (kt_ * (1 - fresnelD(cOut)) * btdf);
}

Float GltfPbrBxDF::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (wo.z == 0 || wi.z == 0) return 0;
    LobeProbs p = lobeProbs(wo);
    if (SameHemisphere(wo, wi)) {
        Float r = hasDiffuse_ ? p.diffuse * AbsCosTheta(wi) * InvPi : 0;
        Vec3 wh;
        if (!smoothR_ && ReflectionHalf(wo, wi, &wh)) r += p.specular * d_.pdf(wo, wh) / (4 * AbsDot(wo, wh));
        return r;
    }
    if (!hasTrans_ || smoothT_) return 0;
    Vec3 wh;
    Float etap;
    if (!RefractionHalf(wo, wi, ior_, &wh, &etap)) return 0;
    Float denom = Sqr(Dot(wi, wh) + Dot(wo, wh) / etap);
    if (!(denom > 0)) return 0;
    return p.transmission * d_.pdf(wo, wh) * AbsDot(wi, wh) / denom;
}

bool GltfPbrBxDF::sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    LobeProbs p = lobeProbs(wo);
    Vec3 wi;
    unsigned lobe;
    Float eta = 1;
    *s = BSDFSample();
    if (uc < p.diffuse) {
        wi = CosineHemisphere(u);
        if (wo.z < 0) wi.z = -wi.z;
        lobe = BSDF_REFLECTION | BSDF_DIFFUSE;
    } else if (uc < p.diffuse + p.specular) {
        if (smoothR_) {
            wi = Vec3(-wo.x, -wo.y, wo.z);
            s->wi = wi;
            s->f = fresnelMix(AbsCosTheta(wo)) / AbsCosTheta(wi);
            s->pdf = s->pdfRev = p.specular;  // |wi.z| = |wo.z|: same probabilities
            s->flags = BSDF_REFLECTION | BSDF_SPECULAR;
            return true;
        }
        wi = Reflect(wo, d_.sampleWh(wo, u));
        if (!SameHemisphere(wo, wi)) return false;
        lobe = BSDF_REFLECTION | BSDF_GLOSSY;
    } else {
        if (!hasTrans_) return false;
        Float etap = wo.z > 0 ? ior_ : 1 / ior_;
        if (smoothT_) {
            if (!Refract(wo, Vec3(0, 0, wo.z > 0 ? 1 : -1), etap, &wi) || wi.z == 0) return false;
            Float cOut = wo.z > 0 ? AbsCosTheta(wo) : AbsCosTheta(wi);
            Spectrum ft = base_ * (kt_ * (1 - fresnelD(cOut)) / AbsCosTheta(wi));
            if (mode == TransportMode::Radiance) ft *= 1 / (etap * etap);
            s->wi = wi;
            s->f = ft;
            s->pdf = p.transmission;
            s->pdfRev = lobeProbs(wi).transmission;
            s->flags = BSDF_TRANSMISSION | BSDF_SPECULAR;
            s->eta = etap;
            return true;
        }
        Vec3 wh = d_.sampleWh(wo, u);
        if (!Refract(wo, wo.z > 0 ? wh : -wh, etap, &wi) || wi.z * wo.z >= 0) return false;
        lobe = BSDF_TRANSMISSION | BSDF_GLOSSY;
        eta = etap;
    }
    if (wi.z == 0) return false;
    return SampleFromEval(*this, wo, wi, mode, lobe, eta, s);
}

// ---------------------------------------------------------------- normal map
void ApplyNormalMap(const Spectrum &rgb, Float scale, SurfaceInteraction &si) {
    const Vec3 N = si.shading.n;
    Vec3 T = si.shading.dpdu - N * Dot(N, si.shading.dpdu);
    Vec3 B = si.shading.dpdv - N * Dot(N, si.shading.dpdv);
    const Float tiny = 1e-20;
    if (T.lengthSquared() > tiny) {
        T = Normalize(T);
        B = B - T * Dot(T, B);
        B = B.lengthSquared() > tiny ? Normalize(B) : Cross(N, T);
    } else if (B.lengthSquared() > tiny) {
        B = Normalize(B);
        T = Cross(B, N);
    } else {
        return;  // no tangent frame
    }
    // glTF 2.0 normalTexture: (2 rgb - 1) * (scale, scale, 1). A texel pointing below
    // the surface is mirrored to the upper side (z kept slightly positive).
    Float x = (2 * rgb.r - 1) * scale, y = (2 * rgb.g - 1) * scale;
    Float z = std::max<Float>(std::abs(2 * rgb.b - 1), 1e-6);
    Vec3 n = T * x + B * y + N * z;
    Float l2 = n.lengthSquared();
    if (!(l2 > 0) || !std::isfinite(l2)) return;
    n = n / std::sqrt(l2);
    // New tangents: T projected onto the perturbed tangent plane, and the bitangent
    // with dpdv's handedness, with the old lengths.
    Float lu = si.shading.dpdu.length(), lv = si.shading.dpdv.length();
    Vec3 u = Normalize(T - n * Dot(n, T));
    Vec3 v = Cross(n, u);
    if (Dot(v, B) < 0) v = -v;
    si.shading.n = n;
    si.shading.dpdu = u * (lu > 0 ? lu : 1);
    si.shading.dpdv = v * (lv > 0 ? lv : 1);
}

// ---------------------------------------------------------------- material
namespace {
class GltfPbrMaterial : public BumpMaterial {
  public:
    std::shared_ptr<SpectrumTexture> baseColor, normalMap;
    std::shared_ptr<FloatTexture> metallic, roughness, ior, transmission, normalScale;
    explicit GltfPbrMaterial(std::shared_ptr<FloatTexture> bump) : BumpMaterial(std::move(bump)) {}

    BSDF getBSDF(SurfaceInteraction &si, Arena &arena, TransportMode mode) const override {
        if (normalMap) ApplyNormalMap(normalMap->evaluate(si), normalScale->evaluate(si), si);
        return BumpMaterial::getBSDF(si, arena, mode);
    }
    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        Float r = Clamp01(roughness->evaluate(si));
        Float eta = ior->evaluate(si);
        return arena.make<GltfPbrBxDF>(Clamp01(baseColor->evaluate(si)), Clamp01(metallic->evaluate(si)), r * r,
                                       std::isnan(eta) ? 1.5 : std::max<Float>(eta, 1),
                                       Clamp01(transmission->evaluate(si)));
    }
    Float minRoughness() const override {
        Float r = ConstantOr(roughness, -1);
        if (r < 0) return 0;
        Float a = Sqr(Clamp01(r));
        if (a < GltfPbrBxDF::SmoothAlpha) return 0;
        // A transmission lobe may be smooth (ior near 1): see GltfPbrBxDF.
        if (ConstantOr(transmission, -1) != 0) {
            Float eta = ConstantOr(ior, -1);
            if (eta < 0 || a * (1 - 1 / std::max<Float>(eta, 1)) < GltfPbrBxDF::SmoothAlpha) return 0;
        }
        return a;
    }
    bool texturesVary() const override {
        return NonConstant(baseColor) || NonConstant(metallic) || NonConstant(roughness) || NonConstant(ior) ||
               NonConstant(transmission) || NonConstant(normalMap) || NonConstant(normalScale);
    }
};
}  // namespace

std::shared_ptr<Material> CreateGltfPbrMaterial(const ParamSet &p, const NamedTextures &tex, const FileLoc &loc,
                                               std::shared_ptr<FloatTexture> bump) {
    auto m = std::make_shared<GltfPbrMaterial>(std::move(bump));
    m->baseColor = GetSpectrumTexture(p, "basecolor", Spectrum(1), tex, loc);
    m->metallic = GetFloatTexture(p, "metallic", 1, tex, loc);
    m->roughness = GetFloatTexture(p, "roughness", 1, tex, loc);
    m->ior = GetFloatTexture(p, "ior", 1.5, tex, loc);
    m->transmission = GetFloatTexture(p, "transmission", 0, tex, loc);
    if (p.find("normalmap")) m->normalMap = GetSpectrumTexture(p, "normalmap", Spectrum(0.5, 0.5, 1), tex, loc);
    m->normalScale = GetFloatTexture(p, "normalscale", 1, tex, loc);
    return m;
}

}  // namespace gradus
