#include "materials/bsdf.h"

namespace gradus {

BSDF::BSDF(const SurfaceInteraction &si, const BxDF *bxdf) : ng_(si.n), bxdf_(bxdf) {
    Vec3 n = si.shading.n;
    // Gram-Schmidt: the tangent follows shading dpdu so anisotropic lobes line up with uv.
    Vec3 s = si.shading.dpdu - n * Dot(n, si.shading.dpdu);
    Float len2 = s.lengthSquared();
    if (len2 > 1e-20 && std::isfinite(len2)) {
        s = s / std::sqrt(len2);
        frame_ = Frame(s, Cross(n, s), n);
    } else {
        frame_ = Frame(n);
    }
}

RoughnessClass BSDF::roughnessClass(Float shiftThreshold) const {
    Float r = roughness();
    if (isSpecular() || r == 0) return RoughnessClass::Smooth;
    if (r < shiftThreshold) return RoughnessClass::NearSpecular;
    return RoughnessClass::Rough;
}

Spectrum BSDF::f(const Vec3 &woW, const Vec3 &wiW, TransportMode mode) const {
    if (!bxdf_) return Spectrum(0);
    Vec3 wo = toLocal(woW), wi = toLocal(wiW);
    if (wo.z == 0) return Spectrum(0);
    return bxdf_->f(wo, wi, mode);
}

bool BSDF::sample(const Vec3 &woW, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const {
    if (!bxdf_) return false;
    Vec3 wo = toLocal(woW);
    if (wo.z == 0) return false;
    if (!bxdf_->sample(wo, uc, u, mode, s)) return false;
    if (!(s->pdf > 0) || s->f.isBlack() || s->wi.z == 0 || !s->f.isFinite()) return false;
    s->wi = toWorld(s->wi);
    return true;
}

Float BSDF::pdf(const Vec3 &woW, const Vec3 &wiW, TransportMode mode) const {
    if (!bxdf_) return 0;
    Vec3 wo = toLocal(woW), wi = toLocal(wiW);
    if (wo.z == 0) return 0;
    return bxdf_->pdf(wo, wi, mode);
}

void BSDF::pdfs(const Vec3 &woW, const Vec3 &wiW, TransportMode mode, Float *fwd, Float *rev) const {
    if (!bxdf_) {
        *fwd = *rev = 0;
        return;
    }
    Vec3 wo = toLocal(woW), wi = toLocal(wiW);
    *fwd = wo.z == 0 ? 0 : bxdf_->pdf(wo, wi, mode);
    // The reverse query swaps roles; the transport mode flips with the direction of flow.
    TransportMode revMode = mode == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
    *rev = wi.z == 0 ? 0 : bxdf_->pdf(wi, wo, revMode);
}

}  // namespace gradus
