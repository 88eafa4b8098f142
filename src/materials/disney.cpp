#include "materials/disney.h"

#include "materials/bxdf_util.h"
#include "materials/fresnel.h"
#include "materials/material_util.h"

namespace gradus {
using namespace bxdfutil;
using namespace matutil;

namespace {
Float Clamp01(Float x) { return std::isnan(x) ? 0 : Clamp<Float>(x, 0, 1); }
Float NonNeg(Float x) { return std::isnan(x) ? 0 : std::max<Float>(x, 0); }
Spectrum LerpS(Float t, const Spectrum &a, const Spectrum &b) { return a * (1 - t) + b * t; }

// cos(theta_d) = wi . h with h the normalised half vector of the pair; false when wi = -wo.
bool CosThetaD(const Vec3 &wo, const Vec3 &wi, Float *cosD) {
    Vec3 h = wo + wi;
    Float l2 = h.lengthSquared();
    if (!(l2 > 0)) return false;
    *cosD = Dot(wi, h) / std::sqrt(l2);
    return true;
}

// Smith G1 of the GGX distribution divided by 2 cos: 1 / (cos + sqrt(a^2 + cos^2 - a^2 cos^2))
// (Burley 2012, Appendix B's smithG_GGX).
Float SmithGOverTwoCos(Float c, Float a) {
    Float a2 = a * a, c2 = c * c;
    return 1 / (c + std::sqrt(a2 + c2 - a2 * c2));
}
}  // namespace

Float SchlickWeight(Float c) {
    Float m = Clamp<Float>(1 - c, 0, 1);
    return (m * m) * (m * m) * m;
}

// ---------------------------------------------------------------- cosine-sampled lobes
Spectrum DisneyCosineLobe::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return SameHemisphere(wo, wi) ? eval(wo, wi) : Spectrum(0);
}
bool DisneyCosineLobe::sample(const Vec3 &wo, Float, Point2 u, TransportMode, BSDFSample *s) const {
    Vec3 wi = CosineHemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    if (wi.z == 0 || wo.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    s->f = eval(wo, wi);
    s->pdf = AbsCosTheta(wi) * InvPi;
    s->pdfRev = AbsCosTheta(wo) * InvPi;
    s->flags = flags();
    return true;
}
Float DisneyCosineLobe::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return SameHemisphere(wo, wi) ? AbsCosTheta(wi) * InvPi : 0;
}

Spectrum DisneyDiffuse::eval(const Vec3 &wo, const Vec3 &wi) const {
    Float Fo = SchlickWeight(AbsCosTheta(wo)), Fi = SchlickWeight(AbsCosTheta(wi));
    return R_ * (InvPi * (1 - Fo / 2) * (1 - Fi / 2));
}

Spectrum DisneyRetro::eval(const Vec3 &wo, const Vec3 &wi) const {
    Float cosD;
    if (!CosThetaD(wo, wi, &cosD)) return Spectrum(0);
    Float Fo = SchlickWeight(AbsCosTheta(wo)), Fi = SchlickWeight(AbsCosTheta(wi));
    Float RR = 2 * rough_ * cosD * cosD;
    return R_ * (InvPi * RR * (Fo + Fi + Fo * Fi * (RR - 1)));
}

Spectrum DisneyFakeSS::eval(const Vec3 &wo, const Vec3 &wi) const {
    Float cosD;
    if (!CosThetaD(wo, wi, &cosD)) return Spectrum(0);
    Float Fss90 = cosD * cosD * rough_;
    Float Fo = SchlickWeight(AbsCosTheta(wo)), Fi = SchlickWeight(AbsCosTheta(wi));
    Float Fss = (1 + (Fss90 - 1) * Fo) * (1 + (Fss90 - 1) * Fi);
    Float ss = 1.25 * (Fss * (1 / (AbsCosTheta(wo) + AbsCosTheta(wi)) - 0.5) + 0.5);
    return R_ * (InvPi * ss);
}

Spectrum DisneySheen::eval(const Vec3 &wo, const Vec3 &wi) const {
    Float cosD;
    if (!CosThetaD(wo, wi, &cosD)) return Spectrum(0);
    return R_ * SchlickWeight(cosD);
}

// ---------------------------------------------------------------- clear coat
// Burley 2012, Appendix B, Eq. 4 (GTR with gamma = 1): D = (a^2 - 1) / (pi ln(a^2) (1 + (a^2 - 1) cos^2)).
Float DisneyClearcoat::GTR1(Float c, Float a) {
    if (a >= 1) return InvPi;
    Float a2 = a * a;
    return (a2 - 1) / (Pi * std::log(a2) * (1 + (a2 - 1) * c * c));
}

Spectrum DisneyClearcoat::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    if (!SameHemisphere(wo, wi) || !ReflectionHalf(wo, wi, &wh)) return Spectrum(0);
    Float D = GTR1(wh.z, alpha_);
    Float F = 0.04 + 0.96 * SchlickWeight(AbsDot(wo, wh));
    Float G = SmithGOverTwoCos(AbsCosTheta(wo), 0.25) * SmithGOverTwoCos(AbsCosTheta(wi), 0.25);
    return Spectrum(weight_ * G * F * D / 4);
}

bool DisneyClearcoat::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    // Appendix B, Eq. 2: cos^2 theta_h = (1 - a^(2 (1 - u))) / (1 - a^2).
    Float a2 = alpha_ * alpha_;
    Float cos2 = a2 < 1 ? (1 - std::pow(a2, 1 - u.x)) / (1 - a2) : 1 - u.x;
    Float cosT = std::sqrt(Clamp<Float>(cos2, 0, 1)), sinT = SafeSqrt(1 - cosT * cosT);
    Vec3 wh = SphericalDirection(sinT, cosT, 2 * Pi * u.y);
    Vec3 wi = Reflect(wo, wh);
    if (!SameHemisphere(wo, wi)) return false;
    return SampleFromEval(*this, wo, wi, mode, flags(), 1, s);
}

Float DisneyClearcoat::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    if (!SameHemisphere(wo, wi) || !ReflectionHalf(wo, wi, &wh)) return 0;
    // D(h) cos(theta_h) over the reflection Jacobian 4 |wo . h|.
    return GTR1(wh.z, alpha_) * wh.z / (4 * AbsDot(wo, wh));
}

// ---------------------------------------------------------------- specular reflection
Spectrum DisneySpecular::fresnel(Float cosI) const {
    Float fd = eta_ == 1 ? 0 : FrDielectric(cosI, eta_), w = SchlickWeight(cosI);
    Spectrum schlick = R0_ + (Spectrum(1) - R0_) * w;
    return Spectrum(fd * (1 - metallic_)) + schlick * metallic_;
}

Spectrum DisneySpecular::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Float cosO = AbsCosTheta(wo), cosI = AbsCosTheta(wi);
    Vec3 wh;
    if (cosO == 0 || cosI == 0 || !SameHemisphere(wo, wi) || !ReflectionHalf(wo, wi, &wh)) return Spectrum(0);
    Float DG = d_.D(wh) * d_.G(wo, wi);
    return R_ * fresnel(Dot(wi, wh)) * (DG / (4 * cosO * cosI));
}

bool DisneySpecular::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    Vec3 wi = Reflect(wo, d_.sampleWh(wo, u));
    if (!SameHemisphere(wo, wi)) return false;
    return SampleFromEval(*this, wo, wi, mode, flags(), 1, s);
}

Float DisneySpecular::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    if (!SameHemisphere(wo, wi) || !ReflectionHalf(wo, wi, &wh)) return 0;
    return d_.pdf(wo, wh) / (4 * AbsDot(wo, wh));
}

// ---------------------------------------------------------------- rough transmission
Spectrum DisneyTransmission::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    Vec3 wh;
    Float etap;
    if (!RefractionHalf(wo, wi, eta_, &wh, &etap)) return Spectrum(0);
    Float oh = Dot(wo, wh), ih = Dot(wi, wh);
    Float denom = Sqr(ih + oh / etap);
    if (!(denom > 0)) return Spectrum(0);
    Float F = FrDielectric(oh, eta_);
    Float G = d_.G(wo, wi);
    // Walter et al. 2007, Eq. 21 divided through by eta_o^2; radiance is compressed by
    // 1/etap^2 across the interface, importance is not (Veach 1997, Sec. 5.2).
    Float ft = d_.D(wh) * G * (1 - F) * std::abs(ih * oh) / (AbsCosTheta(wi) * AbsCosTheta(wo) * denom);
    if (mode == TransportMode::Radiance) ft /= etap * etap;
    return T_ * ft;
}

bool DisneyTransmission::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    Vec3 wh = d_.sampleWh(wo, u);
    Float etap = wo.z > 0 ? eta_ : 1 / eta_;
    Vec3 wi;
    if (!Refract(wo, wo.z > 0 ? wh : -wh, etap, &wi) || wi.z * wo.z >= 0) return false;
    return SampleFromEval(*this, wo, wi, mode, flags(), etap, s);
}

Float DisneyTransmission::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    Float etap;
    if (!RefractionHalf(wo, wi, eta_, &wh, &etap)) return 0;
    Float denom = Sqr(Dot(wi, wh) + Dot(wo, wh) / etap);
    if (!(denom > 0)) return 0;
    // Walter et al. 2007, Eq. 17: dwh/dwi = |wi . h| / (wi . h + wo . h / etap)^2.
    return d_.pdf(wo, wh) * AbsDot(wi, wh) / denom;
}

// ---------------------------------------------------------------- the summed BSDF
void DisneyBxDF::Alphas(Float rough, Float anisotropic, Float *ax, Float *ay) {
    Float aspect = std::sqrt(1 - 0.9 * Clamp01(anisotropic));
    Float r2 = rough * rough;
    *ax = std::max<Float>(0.001, r2 / aspect);
    *ay = std::max<Float>(0.001, r2 * aspect);
}

DisneyBxDF::DisneyBxDF(const DisneyParams &p) : BxDF(BSDF_NONE) {
    const Spectrum c = ClampNeg(p.color);
    const Float metallic = Clamp01(p.metallic), strans = Clamp01(p.specTrans), rough = NonNeg(p.roughness);
    const Float eta = std::isnan(p.eta) ? 1.5 : Clamp<Float>(p.eta, 1e-3, 1e3);
    const Float diffuseWeight = (1 - metallic) * (1 - strans);
    const Float dt = Clamp01(p.diffTrans) / 2;  // 0: diffuse all reflected, 1: half transmitted
    // The hue and saturation of the base color (luminance normalised away).
    const Float lum = c.y();
    const Spectrum tint = lum > 0 ? c / lum : Spectrum(1);
    const Float sheen = NonNeg(p.sheen);
    const Spectrum Csheen = LerpS(Clamp01(p.sheenTint), Spectrum(1), tint);

    const BxDF *cosLobes[4];
    int nCos = 0;
    if (diffuseWeight > 0) {
        if (p.thin) {
            Float flat = Clamp01(p.flatness);
            diffuse_ = DisneyDiffuse(c * (diffuseWeight * (1 - flat) * (1 - dt)));
            fakeSS_ = DisneyFakeSS(c * (diffuseWeight * flat * (1 - dt)), rough);
            if (flat < 1) cosLobes[nCos++] = &diffuse_;
            if (flat > 0) cosLobes[nCos++] = &fakeSS_;
        } else {
            diffuse_ = DisneyDiffuse(c * diffuseWeight);
            cosLobes[nCos++] = &diffuse_;
        }
        retro_ = DisneyRetro(c * diffuseWeight, rough);
        if (rough > 0) cosLobes[nCos++] = &retro_;
        if (sheen > 0) {
            sheen_ = DisneySheen(Csheen * (diffuseWeight * sheen));
            cosLobes[nCos++] = &sheen_;
        }
    }
    // The cosine-sampled lobes share one unit of sampling weight.
    if (!c.isBlack())
        for (int i = 0; i < nCos; ++i) c_.add(cosLobes[i], 1.0 / nCos);

    Float ax, ay;
    Alphas(rough, p.anisotropic, &ax, &ay);
    const MicrofacetDistribution distrib(MicrofacetDistribution::TrowbridgeReitz, ax, ay);
    const Float r0 = Sqr((eta - 1) / (eta + 1));  // Schlick's F0 of a dielectric seen from air
    const Spectrum Cspec0 = LerpS(metallic, LerpS(Clamp01(p.specularTint), Spectrum(1), tint) * r0, c);
    // Unit scale, as pbrt-v3 since its issue #224 (earlier revisions multiplied the lobe by
    // the color again); the shared references show it (the zoo's metal sphere is c, not c^2).
    spec_ = DisneySpecular(Spectrum(1), distrib, Cspec0, metallic, eta);
    c_.add(&spec_);

    const Float cc = NonNeg(p.clearcoat);
    if (cc > 0) {
        clearcoat_ = DisneyClearcoat(cc, Lerp(Clamp01(p.clearcoatGloss), 0.1, 0.001));
        c_.add(&clearcoat_);
    }

    if (strans > 0 && !c.isBlack()) {
        // T = strans sqrt(color): two refractions give back the color (pbrt-v3).
        Spectrum T = Sqrt(c) * strans;
        eta_ = eta;
        hasT_ = true;
        if (std::abs(eta - 1) < SmoothEtaDelta) {
            smoothTrans_ = SpecularTransmission(T, eta);
            c_.add(&smoothTrans_);
        } else if (p.thin) {
            // Thin: roughness scaled with the IOR (Burley 2015, Fig. 15).
            Float tx, ty;
            Alphas((0.65 * eta - 0.35) * rough, p.anisotropic, &tx, &ty);
            trans_ = DisneyTransmission(T, MicrofacetDistribution(MicrofacetDistribution::TrowbridgeReitz, tx, ty),
                                        eta);
            c_.add(&trans_);
        } else {
            trans_ = DisneyTransmission(T, distrib, eta);
            c_.add(&trans_);
        }
    }
    if (p.thin && dt > 0 && !c.isBlack()) {
        diffTrans_ = LambertianTransmission(c * dt);
        c_.add(&diffTrans_);
    }
    addFlags(c_.flags());
}

// ---------------------------------------------------------------- material
namespace {
class DisneyMaterial : public BumpMaterial {
  public:
    std::shared_ptr<SpectrumTexture> color;
    std::shared_ptr<FloatTexture> metallic, eta, roughness, specularTint, anisotropic, sheen, sheenTint, clearcoat,
        clearcoatGloss, specTrans, flatness, diffTrans;
    bool thin = false;
    explicit DisneyMaterial(std::shared_ptr<FloatTexture> bump) : BumpMaterial(std::move(bump)) {}

    const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        DisneyParams p;
        p.color = color->evaluate(si);
        p.metallic = metallic->evaluate(si);
        p.eta = eta->evaluate(si);
        p.roughness = roughness->evaluate(si);
        p.specularTint = specularTint->evaluate(si);
        p.anisotropic = anisotropic->evaluate(si);
        p.sheen = sheen->evaluate(si);
        p.sheenTint = sheenTint->evaluate(si);
        p.clearcoat = clearcoat->evaluate(si);
        p.clearcoatGloss = clearcoatGloss->evaluate(si);
        p.specTrans = specTrans->evaluate(si);
        p.flatness = flatness->evaluate(si);
        p.diffTrans = diffTrans->evaluate(si);
        p.thin = thin;
        return arena.make<DisneyBxDF>(p);
    }

    // The lowest alpha of any lobe anywhere: a lower bound where a texture varies.
    Float minRoughness() const override {
        Float r = ConstantOr(roughness, -1), an = ConstantOr(anisotropic, -1);
        Float rLow = std::max<Float>(r, 0), anHigh = an < 0 ? 1 : an;
        Float ax, ay;
        DisneyBxDF::Alphas(rLow, anHigh, &ax, &ay);
        Float m = std::min(ax, ay);
        if (ConstantOr(clearcoat, -1) != 0) {
            Float g = ConstantOr(clearcoatGloss, -1);
            m = std::min(m, g < 0 ? 0.001 : Lerp(Clamp01(g), 0.1, 0.001));
        }
        if (ConstantOr(specTrans, -1) != 0) {
            Float e = ConstantOr(eta, -1);
            if (e < 0 || std::abs(e - 1) < DisneyBxDF::SmoothEtaDelta) return 0;  // may pass straight through
            if (thin) {
                DisneyBxDF::Alphas(r < 0 ? 0 : (0.65 * e - 0.35) * r, anHigh, &ax, &ay);
                m = std::min(m, std::min(ax, ay));
            }
        }
        return m;
    }
    bool texturesVary() const override {
        return NonConstant(color) || NonConstant(metallic) || NonConstant(eta) || NonConstant(roughness) ||
               NonConstant(specularTint) || NonConstant(anisotropic) || NonConstant(sheen) ||
               NonConstant(sheenTint) || NonConstant(clearcoat) || NonConstant(clearcoatGloss) ||
               NonConstant(specTrans) || NonConstant(flatness) || NonConstant(diffTrans);
    }
};

// A constant value outside [lo, hi] is a located error (textures are clamped per point).
void CheckRange(const ParamSet &p, const std::shared_ptr<FloatTexture> &t, const char *name, Float lo, Float hi,
                const FileLoc &loc) {
    auto c = dynamic_cast<const ConstantTexture<Float> *>(t.get());
    if (!c) return;
    Float v = c->value();
    if (!(v >= lo && v <= hi)) {
        std::string range = hi == Infinity ? ">= " + std::to_string(lo) : "in [" + std::to_string(lo) + ", " +
                                                                             std::to_string(hi) + "]";
        throw Error(p.locOf(name, loc), "\"disney\" material: \"" + std::string(name) + "\" is " +
                                            std::to_string(v) + ", must be " + range);
    }
}
}  // namespace

std::shared_ptr<Material> CreateDisneyMaterial(const ParamSet &p, const NamedTextures &tex, const FileLoc &loc,
                                              std::shared_ptr<FloatTexture> bump) {
    auto m = std::make_shared<DisneyMaterial>(std::move(bump));
    m->color = GetSpectrumTexture(p, "color", Spectrum(0.5), tex, loc);
    m->metallic = GetFloatTexture(p, "metallic", 0, tex, loc);
    m->eta = GetFloatTexture(p, "eta", 1.5, tex, loc);
    m->roughness = GetFloatTexture(p, "roughness", 0.5, tex, loc);
    m->specularTint = GetFloatTexture(p, "speculartint", 0, tex, loc);
    m->anisotropic = GetFloatTexture(p, "anisotropic", 0, tex, loc);
    m->sheen = GetFloatTexture(p, "sheen", 0, tex, loc);
    m->sheenTint = GetFloatTexture(p, "sheentint", 0.5, tex, loc);
    m->clearcoat = GetFloatTexture(p, "clearcoat", 0, tex, loc);
    m->clearcoatGloss = GetFloatTexture(p, "clearcoatgloss", 1, tex, loc);
    m->specTrans = GetFloatTexture(p, "spectrans", 0, tex, loc);
    m->thin = p.getBool("thin", false);
    m->flatness = GetFloatTexture(p, "flatness", 0, tex, loc);
    m->diffTrans = GetFloatTexture(p, "difftrans", 1, tex, loc);
    auto sd = GetSpectrumTexture(p, "scatterdistance", Spectrum(0), tex, loc);
    if (!m->thin) {  // pbrt-v3 reads scatterdistance only for solid (non-thin) surfaces
        auto c = dynamic_cast<const ConstantTexture<Spectrum> *>(sd.get());
        if (!c || !c->value().isBlack())
            throw UnsupportedError(p.locOf("scatterdistance", loc),
                                   "\"disney\" material with \"scatterdistance\" > 0 (pbrt-v3's DisneyBSSRDF)");
    }
    CheckRange(p, m->roughness, "roughness", 0, Infinity, loc);
    if (auto c = dynamic_cast<const ConstantTexture<Float> *>(m->eta.get()); c && !(c->value() > 0))
        throw Error(p.locOf("eta", loc), "\"disney\" material: \"eta\" is " + std::to_string(c->value()) +
                                             ", must be > 0");
    CheckRange(p, m->eta, "eta", 1e-3, 1e3, loc);
    for (auto [t, name] : {std::pair{m->metallic, "metallic"}, {m->specularTint, "speculartint"},
                           {m->anisotropic, "anisotropic"}, {m->sheenTint, "sheentint"},
                           {m->clearcoatGloss, "clearcoatgloss"}, {m->specTrans, "spectrans"},
                           {m->flatness, "flatness"}, {m->diffTrans, "difftrans"}})
        CheckRange(p, t, name, 0, 1, loc);
    CheckRange(p, m->sheen, "sheen", 0, Infinity, loc);
    CheckRange(p, m->clearcoat, "clearcoat", 0, Infinity, loc);
    return m;
}

}  // namespace gradus
