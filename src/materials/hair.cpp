#include "materials/hair.h"

#include <cmath>

#include "core/error.h"
#include "materials/fresnel.h"
#include "materials/material_util.h"

namespace gradus {

namespace {

constexpr int pMax = HairBxDF::pMax;

// Modified Bessel function I0 and its logarithm. pbrt-v3 sums 10 terms of the
// series, which undershoots by up to ~10% for arguments near 12 and breaks M_p's
// normalisation; here the series runs to convergence (x <= 15) and the
// asymptotic expansion takes four terms beyond (relative error < 1e-6).
Float BesselI0(Float x) {
    if (x > 15) return std::exp(x) / std::sqrt(2 * Pi * x) * (1 + 1 / (8 * x) + 9 / (128 * x * x) +
                                                              225 / (3072 * x * x * x) + 11025 / (98304 * Sqr(x * x)));
    const Float q = x * x / 4;
    Float sum = 1, term = 1;  // term_i = q^i / (i!)^2
    for (int i = 1; i < 60; ++i) {
        term *= q / Float(i * i);
        sum += term;
        if (term < 1e-17 * sum) break;
    }
    return sum;
}
Float LogBesselI0(Float x) {
    if (x > 15)
        return x - 0.5 * std::log(2 * Pi * x) +
               std::log1p(1 / (8 * x) + 9 / (128 * x * x) + 225 / (3072 * x * x * x) + 11025 / (98304 * Sqr(x * x)));
    return std::log(BesselI0(x));
}

// d'Eon et al. 2011's longitudinal scattering lobe (Chiang Eq. 6 with the
// numerically stable log form for small variance v).
Float Mp(Float cosThetaI, Float cosThetaO, Float sinThetaI, Float sinThetaO, Float v) {
    const Float a = cosThetaI * cosThetaO / v, b = sinThetaI * sinThetaO / v;
    if (v <= 0.1) return std::exp(LogBesselI0(a) - b - 1 / v + 0.6931 + std::log(1 / (2 * v)));
    return std::exp(-b) * BesselI0(a) / (std::sinh(1 / v) * 2 * v);
}

// Azimuthal centre of lobe p (Chiang Eq. 10's Phi, d'Eon's geometry).
Float PhiP(int p, Float gammaO, Float gammaT) { return 2 * p * gammaT - 2 * gammaO + p * Pi; }

Float LogisticCdf(Float x, Float s) { return 1 / (1 + std::exp(-x / s)); }
Float Logistic(Float x, Float s) {
    const Float e = std::exp(-std::abs(x) / s);
    return e / (s * (1 + e) * (1 + e));
}
// The logistic restricted to [-pi, pi] and renormalised (Chiang Eq. 11).
Float TrimmedLogistic(Float x, Float s) { return Logistic(x, s) / (LogisticCdf(Pi, s) - LogisticCdf(-Pi, s)); }
Float SampleTrimmedLogistic(Float u, Float s) {
    const Float lo = LogisticCdf(-Pi, s), k = LogisticCdf(Pi, s) - lo;
    const Float x = -s * std::log(1 / (u * k + lo) - 1);
    return Clamp<Float>(std::isnan(x) ? 0 : x, -Pi, Pi);
}

Float Np(Float phi, int p, Float s, Float gammaO, Float gammaT) {
    Float d = phi - PhiP(p, gammaO, gammaT);
    d = std::remainder(d, 2 * Pi);  // into [-pi, pi]
    return TrimmedLogistic(d, s);
}

// sin, cos of (theta + delta) from those of theta and delta.
void Rotate(Float sinT, Float cosT, Float sinD, Float cosD, Float *s, Float *c) {
    *s = sinT * cosD + cosT * sinD;
    *c = cosT * cosD - sinT * sinD;
}

Spectrum ExpNeg(const Spectrum &x) { return Spectrum(std::exp(-x.r), std::exp(-x.g), std::exp(-x.b)); }

}  // namespace

HairBxDF::HairBxDF(Float h, Float eta, const Spectrum &sigmaA, Float betaM, Float betaN, Float alphaDegrees)
    : BxDF(BSDF_GLOSSY | BSDF_REFLECTION | BSDF_TRANSMISSION),
      h_(Clamp<Float>(h, -1, 1)),
      eta_(std::max<Float>(eta, 1)),
      betaM_(Clamp<Float>(betaM, 0, 1)),
      betaN_(Clamp<Float>(betaN, 0, 1)) {
    auto clampSigma = [](Float x) { return Clamp<Float>(std::isnan(x) ? 0 : x, 0, 1e6); };
    sigmaA_ = Spectrum(clampSigma(sigmaA.r), clampSigma(sigmaA.g), clampSigma(sigmaA.b));
    // Chiang Eq. 7: beta_m -> longitudinal variance; R, TT, TRT as Marschner et al.
    const Float bm = betaM_;
    v_[0] = Sqr(0.726 * bm + 0.812 * bm * bm + 3.7 * std::pow(bm, 20));
    v_[0] = std::max<Float>(v_[0], 1e-6);  // beta_m = 0: keep Mp finite
    v_[1] = 0.25 * v_[0];
    v_[2] = 4 * v_[0];
    for (int p = 3; p <= pMax; ++p) v_[p] = v_[2];
    // Chiang Eq. 8: beta_n -> logistic scale s.
    const Float bn = betaN_;
    s_ = std::sqrt(Pi / 8) * (0.265 * bn + 1.194 * bn * bn + 5.372 * std::pow(bn, 22));
    s_ = std::max<Float>(s_, 1e-6);
    // Scale tilt: sin/cos of alpha, 2 alpha, 4 alpha.
    sin2kAlpha_[0] = std::sin(Radians(alphaDegrees));
    cos2kAlpha_[0] = SafeSqrt(1 - Sqr(sin2kAlpha_[0]));
    for (int i = 1; i < 3; ++i) {
        sin2kAlpha_[i] = 2 * cos2kAlpha_[i - 1] * sin2kAlpha_[i - 1];
        cos2kAlpha_[i] = Sqr(cos2kAlpha_[i - 1]) - Sqr(sin2kAlpha_[i - 1]);
    }
}

void HairBxDF::tiltO(int p, Float sinThetaO, Float cosThetaO, Float *s, Float *c) const {
    // Scale tilt of lobe p (Chiang Sec. 4.1, pbrt-v3's signs): theta_o - 2 alpha
    // for R, + alpha for TT, + 4 alpha for TRT. Tilting theta_o (not theta_i)
    // keeps every M_p a normalised density in theta_i.
    const int k = p == 0 ? 1 : p == 1 ? 0 : 2;
    Rotate(sinThetaO, cosThetaO, p == 0 ? -sin2kAlpha_[k] : sin2kAlpha_[k], cos2kAlpha_[k], s, c);
    *c = std::abs(*c);
}

Float HairBxDF::roughness() const { return std::max(std::min(betaM_, betaN_), kDefaultShiftThreshold); }

std::array<Spectrum, HairBxDF::pMax + 1> HairBxDF::attenuation(Float cosThetaO, Float h) const {
    const Float sinThetaO = SafeSqrt(1 - cosThetaO * cosThetaO);
    // Refracted direction: longitudinal (Snell) and azimuthal (Bravais' modified index).
    const Float cosThetaT = SafeSqrt(1 - Sqr(sinThetaO / eta_));
    const Float etap = std::sqrt(eta_ * eta_ - sinThetaO * sinThetaO) / std::max<Float>(cosThetaO, 1e-12);
    const Float cosGammaT = SafeSqrt(1 - Sqr(h / etap));
    // Chiang Eq. 4: transmittance of one internal chord.
    const Spectrum T = ExpNeg(sigmaA_ * (2 * cosGammaT / std::max<Float>(cosThetaT, 1e-12)));
    std::array<Spectrum, pMax + 1> ap;
    // Chiang Eq. 3: Fresnel at the angle between the ray and the fibre normal.
    const Float f = FrDielectric(cosThetaO * SafeSqrt(1 - h * h), eta_);
    ap[0] = Spectrum(f);
    ap[1] = T * Sqr(1 - f);
    for (int p = 2; p < pMax; ++p) ap[p] = ap[p - 1] * T * f;
    // Remaining orders: geometric series of (T f).
    const Spectrum tf = T * f;
    auto tail = [](Float a, Float x) { return x < 1 ? a * x / (1 - x) : 0; };  // x = 1 only where a = 0
    ap[pMax] = Spectrum(tail(ap[pMax - 1].r, tf.r), tail(ap[pMax - 1].g, tf.g), tail(ap[pMax - 1].b, tf.b));
    return ap;
}

std::array<Float, HairBxDF::pMax + 1> HairBxDF::lobePdf(Float cosThetaO, Float h) const {
    const auto ap = attenuation(cosThetaO, h);
    std::array<Float, pMax + 1> pdf;
    Float sum = 0;
    for (int p = 0; p <= pMax; ++p) sum += ap[p].y();
    for (int p = 0; p <= pMax; ++p) pdf[p] = sum > 0 ? ap[p].y() / sum : (p == 0 ? 1 : 0);
    return pdf;
}

Spectrum HairBxDF::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    // The integrators multiply by |cos| of wi to the shading normal; the hair lobes
    // are densities over the sphere already, so f is S / |cos wi| in both modes
    // (pbrt-v3 divides it out likewise): the normal drops out, as it must on
    // curves, whose normal is only pbrt-v3's convention. S is not reciprocal: the
    // adjoint swaps its directions.
    const Spectrum s = mode == TransportMode::Importance ? scattering(wi, wo) : scattering(wo, wi);
    const Float c = std::abs(wi.z);
    const Spectrum v = c > 0 ? s / c : s;
    return v.isFinite() ? v : Spectrum(0);
}

Spectrum HairBxDF::scattering(const Vec3 &wo, const Vec3 &wi) const {
    const Float h = h_, gammaO = std::asin(h);
    const Float sinThetaO = Clamp<Float>(wo.x, -1, 1), cosThetaO = SafeSqrt(1 - sinThetaO * sinThetaO);
    const Float sinThetaI = Clamp<Float>(wi.x, -1, 1), cosThetaI = SafeSqrt(1 - sinThetaI * sinThetaI);
    if (cosThetaO < 1e-9) return Spectrum(0);  // along the fibre: no azimuth
    const Float phi = std::atan2(wi.z, wi.y) - std::atan2(wo.z, wo.y);
    const Float etap = std::sqrt(eta_ * eta_ - sinThetaO * sinThetaO) / cosThetaO;
    const Float gammaT = std::asin(Clamp<Float>(h / etap, -1, 1));
    const auto ap = attenuation(cosThetaO, h);
    Spectrum sum(0);
    for (int p = 0; p < pMax; ++p) {
        Float sp, cp;
        tiltO(p, sinThetaO, cosThetaO, &sp, &cp);
        sum += ap[p] * (Mp(cosThetaI, cp, sinThetaI, sp, v_[p]) * Np(phi, p, s_, gammaO, gammaT));
    }
    sum += ap[pMax] * (Mp(cosThetaI, cosThetaO, sinThetaI, sinThetaO, v_[pMax]) / (2 * Pi));
    return sum;
}

Float HairBxDF::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    const Float h = h_, gammaO = std::asin(h);
    const Float sinThetaO = Clamp<Float>(wo.x, -1, 1), cosThetaO = SafeSqrt(1 - sinThetaO * sinThetaO);
    const Float sinThetaI = Clamp<Float>(wi.x, -1, 1), cosThetaI = SafeSqrt(1 - sinThetaI * sinThetaI);
    if (cosThetaO < 1e-9) return 0;
    const Float phi = std::atan2(wi.z, wi.y) - std::atan2(wo.z, wo.y);
    const Float etap = std::sqrt(eta_ * eta_ - sinThetaO * sinThetaO) / cosThetaO;
    const Float gammaT = std::asin(Clamp<Float>(h / etap, -1, 1));
    const auto w = lobePdf(cosThetaO, h);
    Float pdf = 0;
    for (int p = 0; p < pMax; ++p) {
        Float sp, cp;
        tiltO(p, sinThetaO, cosThetaO, &sp, &cp);
        pdf += w[p] * Mp(cosThetaI, cp, sinThetaI, sp, v_[p]) * Np(phi, p, s_, gammaO, gammaT);
    }
    pdf += w[pMax] * Mp(cosThetaI, cosThetaO, sinThetaI, sinThetaO, v_[pMax]) / (2 * Pi);
    return std::isfinite(pdf) ? pdf : 0;
}

bool HairBxDF::sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    const Float sinThetaO = Clamp<Float>(wo.x, -1, 1), cosThetaO = SafeSqrt(1 - sinThetaO * sinThetaO);
    if (cosThetaO < 1e-9) return false;
    const Float h = h_, gammaO = std::asin(h);
    // Lobe p by A_p's luminance; uc is reused within the chosen interval for N_p.
    const auto w = lobePdf(cosThetaO, h);
    int p = 0;
    while (p < pMax && uc >= w[p]) uc -= w[p++];
    if (w[p] <= 0) return false;
    const Float uPhi = Clamp<Float>(uc / w[p], 0, 1 - 1e-12);
    // M_p around the lobe's tilted theta_o: the cosine to its mirror direction
    // (d'Eon et al. 2011's sampling) and a uniform angle around it.
    Float sinOp = sinThetaO, cosOp = cosThetaO;
    if (p < pMax) tiltO(p, sinThetaO, cosThetaO, &sinOp, &cosOp);
    const Float u0 = std::max<Float>(u.x, 1e-5);
    const Float cosT = 1 + v_[p] * std::log(u0 + (1 - u0) * std::exp(-2 / v_[p]));
    const Float sinT = SafeSqrt(1 - cosT * cosT);
    const Float sinThetaI = Clamp<Float>(-cosT * sinOp + sinT * std::cos(2 * Pi * u.y) * cosOp, -1, 1);
    const Float cosThetaI = SafeSqrt(1 - sinThetaI * sinThetaI);
    // N_p: trimmed logistic around Phi(p); uniform for the tail.
    const Float etap = std::sqrt(eta_ * eta_ - sinThetaO * sinThetaO) / cosThetaO;
    const Float gammaT = std::asin(Clamp<Float>(h / etap, -1, 1));
    const Float dphi = p < pMax ? PhiP(p, gammaO, gammaT) + SampleTrimmedLogistic(uPhi, s_) : 2 * Pi * uPhi;
    const Float phiI = std::atan2(wo.z, wo.y) + dphi;
    s->wi = Vec3(sinThetaI, cosThetaI * std::cos(phiI), cosThetaI * std::sin(phiI));
    s->pdf = pdf(wo, s->wi, mode);
    s->pdfRev = pdf(s->wi, wo, mode);
    s->f = f(wo, s->wi, mode);
    s->eta = 1;
    s->flags = BSDF_GLOSSY | (s->wi.z * wo.z > 0 ? BSDF_REFLECTION : BSDF_TRANSMISSION);
    return s->pdf > 0 && s->wi.isFinite();
}

Spectrum HairBxDF::SigmaAFromConcentration(Float ce, Float cp) {
    const Spectrum eu(0.419, 0.697, 1.37), pheo(0.187, 0.4, 1.05);
    return eu * ce + pheo * cp;
}

Spectrum HairBxDF::SigmaAFromReflectance(const Spectrum &c, Float bn) {
    // Chiang Eq. 9, inverted for sigma_a.
    const Float d = 5.969 - 0.215 * bn + 2.532 * bn * bn - 10.73 * std::pow(bn, 3) + 5.574 * std::pow(bn, 4) +
                    0.245 * std::pow(bn, 5);
    auto one = [&](Float x) { return Sqr(std::log(Clamp<Float>(x, 1e-10, 1)) / d); };
    return Spectrum(one(c.r), one(c.g), one(c.b));
}

namespace {

class HairMaterial : public Material {
  public:
    std::shared_ptr<SpectrumTexture> sigmaA, color;
    std::shared_ptr<FloatTexture> eumelanin, pheomelanin, eta, betaM, betaN, alpha;
    BSDF getBSDF(SurfaceInteraction &si, Arena &arena, TransportMode) const override {
        const Float bn = betaN->evaluate(si);
        Spectrum sa;
        if (sigmaA) sa = matutil::ClampNeg(sigmaA->evaluate(si));
        else if (color) sa = HairBxDF::SigmaAFromReflectance(matutil::ClampNeg(color->evaluate(si)), bn);
        else
            sa = HairBxDF::SigmaAFromConcentration(std::max<Float>(0, eumelanin ? eumelanin->evaluate(si) : 0),
                                                   std::max<Float>(0, pheomelanin ? pheomelanin->evaluate(si) : 0));
        // pbrt-v3's offset across the width from the hit's v (shapes/curve.h).
        const Float h = -1 + 2 * si.uv.y;
        return BSDF(si, arena.make<HairBxDF>(h, eta->evaluate(si), sa, betaM->evaluate(si), bn, alpha->evaluate(si)));
    }
    Float minRoughness() const override {
        const Float m = matutil::ConstantOr(betaM, -1), n = matutil::ConstantOr(betaN, -1);
        if (m < 0 || n < 0) return kDefaultShiftThreshold;  // textured: at least what roughness() reports
        return std::max(std::min(m, n), kDefaultShiftThreshold);
    }
    bool hasTextures() const override {
        using matutil::NonConstant;
        return NonConstant(sigmaA) || NonConstant(color) || NonConstant(eumelanin) || NonConstant(pheomelanin) ||
               NonConstant(eta) || NonConstant(betaM) || NonConstant(betaN) || NonConstant(alpha);
    }
};

}  // namespace

std::shared_ptr<Material> CreateHairMaterial(const ParamSet &p, const NamedTextures &tex, const FileLoc &loc,
                                             std::vector<std::string> *notes) {
    auto m = std::make_shared<HairMaterial>();
    // pbrt-v3's precedence: sigma_a, then color, then the melanins (the others are
    // ignored with a note, as pbrt-v3 warns); none: eumelanin 1.3.
    const bool hasSigma = p.has("sigma_a"), hasColor = p.has("color");
    const bool hasMel = p.has("eumelanin") || p.has("pheomelanin");
    if (notes && (hasSigma || hasColor)) {
        const char *winner = hasSigma ? "sigma_a" : "color";
        for (const char *name : {"color", "eumelanin", "pheomelanin"})
            if (p.has(name) && std::string(name) != winner)
                notes->push_back(p.locOf(name, loc).str() + ": material \"hair\": \"" + name +
                                 "\" is ignored since \"" + winner + "\" is given (precedence: sigma_a, color, "
                                 "eumelanin/pheomelanin)");
    }
    if (hasSigma) m->sigmaA = GetSpectrumTexture(p, "sigma_a", Spectrum(0), tex, loc);
    if (hasColor) m->color = GetSpectrumTexture(p, "color", Spectrum(0), tex, loc);
    if (p.has("eumelanin")) m->eumelanin = GetFloatTexture(p, "eumelanin", 0, tex, loc);
    if (p.has("pheomelanin")) m->pheomelanin = GetFloatTexture(p, "pheomelanin", 0, tex, loc);
    if (hasSigma) m->color = nullptr, m->eumelanin = m->pheomelanin = nullptr;
    else if (hasColor) m->eumelanin = m->pheomelanin = nullptr;
    else if (!hasMel) m->sigmaA = std::make_shared<ConstantTexture<Spectrum>>(HairBxDF::SigmaAFromConcentration(1.3, 0));
    m->eta = GetFloatTexture(p, "eta", 1.55, tex, loc);
    m->betaM = GetFloatTexture(p, "beta_m", 0.3, tex, loc);
    m->betaN = GetFloatTexture(p, "beta_n", 0.3, tex, loc);
    m->alpha = GetFloatTexture(p, "alpha", 2, tex, loc);
    auto range = [&](const std::shared_ptr<FloatTexture> &t, const char *name, Float lo, Float hi) {
        const Float v = matutil::ConstantOr(t, lo);
        if (!(v >= lo && v <= hi))
            throw Error(p.locOf(name, loc), std::string("material \"hair\": \"") + name + "\" must be in [" +
                                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
    };
    range(m->betaM, "beta_m", 0, 1);
    range(m->betaN, "beta_n", 0, 1);
    range(m->eta, "eta", 1, 1e3);
    range(m->alpha, "alpha", -90, 90);
    if (m->eumelanin) range(m->eumelanin, "eumelanin", 0, 1e6);
    if (m->pheomelanin) range(m->pheomelanin, "pheomelanin", 0, 1e6);
    return m;
}

}  // namespace gradus
