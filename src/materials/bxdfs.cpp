#include "materials/bxdfs.h"

#include "core/error.h"
#include "materials/bxdf_util.h"

namespace gradus {
using namespace bxdfutil;

// ---------------------------------------------------------------- Lambertian
Spectrum LambertianReflection::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return SameHemisphere(wo, wi) ? R_ * InvPi : Spectrum(0);
}
bool LambertianReflection::sample(const Vec3 &wo, Float, Point2 u, TransportMode, BSDFSample *s) const {
    Vec3 wi = CosineHemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    if (wi.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    s->f = R_ * InvPi;
    s->pdf = AbsCosTheta(wi) * InvPi;
    s->pdfRev = AbsCosTheta(wo) * InvPi;
    s->flags = flags();
    return true;
}
Float LambertianReflection::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return SameHemisphere(wo, wi) ? AbsCosTheta(wi) * InvPi : 0;
}

Spectrum LambertianTransmission::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return wo.z * wi.z < 0 ? T_ * InvPi : Spectrum(0);
}
bool LambertianTransmission::sample(const Vec3 &wo, Float, Point2 u, TransportMode, BSDFSample *s) const {
    Vec3 wi = CosineHemisphere(u);
    if (wo.z > 0) wi.z = -wi.z;
    if (wi.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    s->f = T_ * InvPi;
    s->pdf = AbsCosTheta(wi) * InvPi;
    s->pdfRev = AbsCosTheta(wo) * InvPi;
    s->flags = flags();
    return true;
}
Float LambertianTransmission::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return wo.z * wi.z < 0 ? AbsCosTheta(wi) * InvPi : 0;
}

// ---------------------------------------------------------------- Oren-Nayar
OrenNayar::OrenNayar(const Spectrum &R, Float sigmaDeg) : BxDF(BSDF_REFLECTION | BSDF_DIFFUSE), R_(R) {
    Float s = Radians(sigmaDeg), s2 = s * s;
    A_ = 1 - s2 / (2 * (s2 + 0.33));
    B_ = 0.45 * s2 / (s2 + 0.09);
}
Spectrum OrenNayar::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (!SameHemisphere(wo, wi)) return Spectrum(0);
    Float sinI = SinTheta(wi), sinO = SinTheta(wo);
    Float maxCos = 0;
    if (sinI > 1e-4 && sinO > 1e-4)
        maxCos = std::max<Float>(0, CosPhi(wi) * CosPhi(wo) + SinPhi(wi) * SinPhi(wo));
    // alpha = max(theta_i, theta_o), beta = min(theta_i, theta_o).
    Float sinAlpha, tanBeta;
    if (AbsCosTheta(wi) > AbsCosTheta(wo)) {
        sinAlpha = sinO;
        tanBeta = sinI / AbsCosTheta(wi);
    } else {
        sinAlpha = sinI;
        tanBeta = sinO / AbsCosTheta(wo);
    }
    return R_ * (InvPi * (A_ + B_ * maxCos * sinAlpha * tanBeta));
}
bool OrenNayar::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    Vec3 wi = CosineHemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    if (wi.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    s->f = f(wo, wi, mode);
    s->pdf = AbsCosTheta(wi) * InvPi;
    s->pdfRev = AbsCosTheta(wo) * InvPi;
    s->flags = flags();
    return true;
}
Float OrenNayar::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    return SameHemisphere(wo, wi) ? AbsCosTheta(wi) * InvPi : 0;
}

// ---------------------------------------------------------------- specular
bool SpecularReflection::sample(const Vec3 &wo, Float, Point2, TransportMode, BSDFSample *s) const {
    Vec3 wi(-wo.x, -wo.y, wo.z);
    if (wi.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    s->f = R_ * fr_.evaluate(wi.z) / AbsCosTheta(wi);
    s->pdf = s->pdfRev = 1;
    s->flags = flags();
    return true;
}

bool SpecularTransmission::sample(const Vec3 &wo, Float, Point2, TransportMode mode, BSDFSample *s) const {
    Float etap = wo.z > 0 ? eta_ : 1 / eta_;  // eta_t / eta_i
    Vec3 wi;
    if (!Refract(wo, Vec3(0, 0, wo.z > 0 ? 1 : -1), etap, &wi) || wi.z == 0) return false;
    *s = BSDFSample();
    s->wi = wi;
    Spectrum ft = T_ * (1 - FrDielectric(wo.z, eta_)) / AbsCosTheta(wi);
    if (mode == TransportMode::Radiance) ft *= 1 / (etap * etap);  // Veach 1997, Sec. 5.2
    s->f = ft;
    s->pdf = s->pdfRev = 1;
    s->flags = flags();
    s->eta = etap;
    return true;
}

SpecularDielectric::SpecularDielectric(const Spectrum &R, const Spectrum &T, Float eta)
    : BxDF((R.isBlack() ? 0u : unsigned(BSDF_REFLECTION)) | (T.isBlack() ? 0u : unsigned(BSDF_TRANSMISSION)) |
           BSDF_SPECULAR),
      R_(R), T_(T), eta_(eta) {}

bool SpecularDielectric::sample(const Vec3 &wo, Float uc, Point2, TransportMode mode, BSDFSample *s) const {
    Float F = FrDielectric(wo.z, eta_);
    Float pr = R_.maxComponent() * F, pt = T_.maxComponent() * (1 - F);
    if (!(pr + pt > 0)) return false;
    *s = BSDFSample();
    if (uc < pr / (pr + pt)) {
        Vec3 wi(-wo.x, -wo.y, wo.z);
        s->wi = wi;
        s->f = R_ * F / AbsCosTheta(wi);
        s->pdf = s->pdfRev = pr / (pr + pt);
        s->flags = BSDF_REFLECTION | BSDF_SPECULAR;
        return true;
    }
    Float etap = wo.z > 0 ? eta_ : 1 / eta_;
    Vec3 wi;
    if (!Refract(wo, Vec3(0, 0, wo.z > 0 ? 1 : -1), etap, &wi) || wi.z == 0) return false;
    Spectrum ft = T_ * (1 - F) / AbsCosTheta(wi);
    if (mode == TransportMode::Radiance) ft *= 1 / (etap * etap);
    s->wi = wi;
    s->f = ft;
    // Fresnel reflectance is the same from both sides of a refraction pair.
    s->pdf = s->pdfRev = pt / (pr + pt);
    s->flags = BSDF_TRANSMISSION | BSDF_SPECULAR;
    s->eta = etap;
    return true;
}

// ---------------------------------------------------------------- microfacet reflection
namespace {
// Half vector of a reflection pair, in the upper hemisphere; false if degenerate.
bool HalfVector(const Vec3 &wo, const Vec3 &wi, Vec3 *wh) {
    Vec3 h = wo + wi;
    if (h.lengthSquared() == 0) return false;
    h = Normalize(h);
    *wh = h.z < 0 ? -h : h;
    return h.z != 0;
}
}  // namespace

Spectrum MicrofacetReflection::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (!SameHemisphere(wo, wi)) return Spectrum(0);
    Float cosO = AbsCosTheta(wo), cosI = AbsCosTheta(wi);
    Vec3 wh;
    if (cosO == 0 || cosI == 0 || !HalfVector(wo, wi, &wh)) return Spectrum(0);
    Spectrum F = fr_.evaluate(Dot(wi, wh));
    return R_ * F * (d_.D(wh) * d_.G(wo, wi) / (4 * cosI * cosO));
}
bool MicrofacetReflection::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    Vec3 wh = d_.sampleWh(wo, u);
    Vec3 wi = Reflect(wo, wh);
    if (!SameHemisphere(wo, wi)) return false;
    return SampleFromEval(*this, wo, wi, mode, flags(), 1, s);
}
Float MicrofacetReflection::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    if (!SameHemisphere(wo, wi) || !HalfVector(wo, wi, &wh)) return 0;
    return d_.pdf(wo, wh) / (4 * AbsDot(wo, wh));
}

// ---------------------------------------------------------------- rough dielectric
MicrofacetDielectric::MicrofacetDielectric(const Spectrum &R, const Spectrum &T, Float eta,
                                           const MicrofacetDistribution &d)
    : BxDF((R.isBlack() ? 0u : unsigned(BSDF_REFLECTION)) | (T.isBlack() ? 0u : unsigned(BSDF_TRANSMISSION)) |
           BSDF_GLOSSY),
      R_(R), T_(T), eta_(eta), d_(d), hasR_(!R.isBlack()), hasT_(!T.isBlack()) {}

Float MicrofacetDielectric::reflectProb(Float F) const {
    Float pr = hasR_ ? R_.maxComponent() * F : 0, pt = hasT_ ? T_.maxComponent() * (1 - F) : 0;
    return pr + pt > 0 ? pr / (pr + pt) : -1;
}

namespace {
// Generalized half vector (Walter et al. 2007, Eq. 16) in the upper hemisphere, and
// etap = eta on wi's side / eta on wo's side (1 for reflection). False if degenerate
// or if a microfacet would be back-facing for either direction.
bool DielectricHalf(const Vec3 &wo, const Vec3 &wi, Float eta, Vec3 *wh, Float *etap) {
    if (wo.z == 0 || wi.z == 0) return false;
    bool reflect = wo.z * wi.z > 0;
    *etap = reflect ? 1 : (wo.z > 0 ? eta : 1 / eta);
    Vec3 h = wi * *etap + wo;
    if (h.lengthSquared() == 0) return false;
    h = Normalize(h);
    if (h.z < 0) h = -h;
    if (h.z == 0) return false;
    if (Dot(h, wi) * wi.z < 0 || Dot(h, wo) * wo.z < 0) return false;
    *wh = h;
    return true;
}
}  // namespace

Spectrum MicrofacetDielectric::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    Vec3 wh;
    Float etap;
    if (!DielectricHalf(wo, wi, eta_, &wh, &etap)) return Spectrum(0);
    Float F = FrDielectric(Dot(wo, wh), eta_);
    Float cosO = AbsCosTheta(wo), cosI = AbsCosTheta(wi);
    if (etap == 1 && wo.z * wi.z > 0) {
        if (!hasR_) return Spectrum(0);
        return R_ * (d_.D(wh) * d_.G(wo, wi) * F / (4 * cosI * cosO));
    }
    if (!hasT_) return Spectrum(0);
    Float denom = Sqr(Dot(wi, wh) + Dot(wo, wh) / etap);
    if (denom == 0) return Spectrum(0);
    // Walter et al. 2007, Eq. 21, divided through by eta_i^2.
    Float ft = d_.D(wh) * d_.G(wo, wi) * (1 - F) * std::abs(Dot(wi, wh) * Dot(wo, wh)) / (cosI * cosO * denom);
    if (mode == TransportMode::Radiance) ft *= 1 / (etap * etap);
    return T_ * ft;
}

Float MicrofacetDielectric::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    Vec3 wh;
    Float etap;
    if (!DielectricHalf(wo, wi, eta_, &wh, &etap)) return 0;
    Float pR = reflectProb(FrDielectric(Dot(wo, wh), eta_));
    if (pR < 0) return 0;
    if (wo.z * wi.z > 0) return d_.pdf(wo, wh) / (4 * AbsDot(wo, wh)) * pR;
    Float denom = Sqr(Dot(wi, wh) + Dot(wo, wh) / etap);
    if (denom == 0) return 0;
    return d_.pdf(wo, wh) * AbsDot(wi, wh) / denom * (1 - pR);
}

bool MicrofacetDielectric::sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    Vec3 wh = d_.sampleWh(wo, u);
    Float pR = reflectProb(FrDielectric(Dot(wo, wh), eta_));
    if (pR < 0) return false;
    Vec3 wi;
    if (uc < pR) {
        wi = Reflect(wo, wh);
        if (!SameHemisphere(wo, wi)) return false;
    } else {
        Float etap = wo.z > 0 ? eta_ : 1 / eta_;
        if (!Refract(wo, wo.z > 0 ? wh : -wh, etap, &wi) || wi.z * wo.z >= 0) return false;
    }
    bool refl = wo.z * wi.z > 0;
    return SampleFromEval(*this, wo, wi, mode, (refl ? BSDF_REFLECTION : BSDF_TRANSMISSION) | BSDF_GLOSSY,
                          refl ? 1 : (wo.z > 0 ? eta_ : 1 / eta_), s);
}

// ---------------------------------------------------------------- Ashikhmin-Shirley
namespace {
inline Float Pow5(Float x) { return (x * x) * (x * x) * x; }
}  // namespace

Spectrum FresnelBlend::f(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (!SameHemisphere(wo, wi)) return Spectrum(0);
    Float cosI = AbsCosTheta(wi), cosO = AbsCosTheta(wo);
    // Ashikhmin & Shirley 2000, Eq. 5 (diffuse) and Eq. 4 (specular, with Schlick's Fresnel).
    Spectrum diffuse = Rd_ * (Spectrum(1) - Rs_) *
                       (28 / (23 * Pi) * (1 - Pow5(1 - cosI / 2)) * (1 - Pow5(1 - cosO / 2)));
    Vec3 wh;
    if (!HalfVector(wo, wi, &wh)) return diffuse;
    Float cosH = AbsDot(wi, wh);
    Spectrum schlick = Rs_ + (Spectrum(1) - Rs_) * Pow5(1 - cosH);
    Spectrum spec = schlick * (d_.D(wh) / (4 * cosH * std::max(cosI, cosO)));
    return diffuse + spec;
}
bool FresnelBlend::sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (wo.z == 0) return false;
    Vec3 wi;
    if (uc < 0.5) {
        wi = CosineHemisphere(u);
        if (wo.z < 0) wi.z = -wi.z;
    } else {
        wi = Reflect(wo, d_.sampleWh(wo, u));
        if (!SameHemisphere(wo, wi)) return false;
    }
    return SampleFromEval(*this, wo, wi, mode, flags(), 1, s);
}
Float FresnelBlend::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (!SameHemisphere(wo, wi)) return 0;
    Float p = AbsCosTheta(wi) * InvPi;
    Vec3 wh;
    if (HalfVector(wo, wi, &wh)) p += d_.pdf(wo, wh) / (4 * AbsDot(wo, wh));
    return p / 2;
}

// ---------------------------------------------------------------- composite
void CompositeBxDF::add(const BxDF *b, Float weight) {
    if (!b || !(weight > 0)) return;
    GRADUS_CHECK(n_ < MaxComponents);
    c_[n_] = b;
    w_[n_] = weight;
    wSum_ += weight;
    addFlags(b->flags());
    ++n_;
}

Spectrum CompositeBxDF::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    Spectrum r(0);
    for (int i = 0; i < n_; ++i) r += c_[i]->f(wo, wi, mode);
    return r;
}

Float CompositeBxDF::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    if (n_ == 0) return 0;
    Float p = 0;
    for (int i = 0; i < n_; ++i) p += w_[i] * c_[i]->pdf(wo, wi, mode);
    return p / wSum_;
}

bool CompositeBxDF::sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (n_ == 0) return false;
    // Pick a component and rescale uc to [0,1) for its own use.
    Float target = uc * wSum_, acc = 0;
    int k = n_ - 1;
    for (int i = 0; i < n_; ++i) {
        if (target < acc + w_[i]) {
            k = i;
            break;
        }
        acc += w_[i];
    }
    Float prob = w_[k] / wSum_;
    Float ucR = Clamp<Float>((target - acc) / w_[k], 0, 0.99999999999999989);
    if (!c_[k]->sample(wo, ucR, u, mode, s)) return false;
    if (s->isSpecular()) {
        s->pdf *= prob;
        s->pdfRev *= prob;
        return true;
    }
    s->f = f(wo, s->wi, mode);
    s->pdf = pdf(wo, s->wi, mode);
    s->pdfRev = pdf(s->wi, wo, Reverse(mode));
    return s->pdf > 0;
}

Float CompositeBxDF::roughness() const {
    Float r = Infinity;
    for (int i = 0; i < n_; ++i) r = std::min(r, c_[i]->roughness());
    return n_ ? r : 1;
}

}  // namespace gradus
