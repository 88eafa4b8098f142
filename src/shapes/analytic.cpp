#include "shapes/analytic.h"

#include <cmath>

namespace gradus {

AnalyticShape::AnalyticShape(const Transform &w, bool ro)
    : worldFromObject_(w), objectFromWorld_(w.inverse()), reverseOrientation_(ro) {
    flip_ = ro ^ w.swapsHandedness();
    Vec3 a = w.applyVector(Vec3(1, 0, 0)), b = w.applyVector(Vec3(0, 1, 0)), c = w.applyVector(Vec3(0, 0, 1));
    detLinear_ = std::abs(Dot(a, Cross(b, c)));
    areaScale_ = std::pow(detLinear_, 2.0 / 3.0);
}

bool SolveQuadratic(Float a, Float b, Float c, Float *t0, Float *t1) {
    if (a == 0) {
        if (b == 0) return false;
        *t0 = *t1 = -c / b;
        return std::isfinite(*t0);
    }
    Float disc = b * b - 4 * a * c;
    if (disc < 0) return false;
    Float root = std::sqrt(disc);
    // Avoid cancellation: q has the sign of b.
    Float q = b < 0 ? -0.5 * (b - root) : -0.5 * (b + root);
    if (q == 0) {
        *t0 = *t1 = 0;  // b == 0 and c == 0
        return true;
    }
    *t0 = q / a;
    *t1 = c / q;
    if (*t0 > *t1) std::swap(*t0, *t1);
    return true;
}

Normal3 AnalyticShape::worldNormal(const Patch &pt) const {
    Vec3 nObj = Cross(pt.dpdu, pt.dpdv);
    if (!(nObj.lengthSquared() > 0)) return Normal3(0, 0, 0);
    Normal3 n = worldFromObject_.applyNormal(Normalize(nObj));
    n = Normalize(n);
    return flip_ ? -n : n;
}

Float AnalyticShape::areaRatio(const Patch &pt) const {
    Vec3 nObj = Cross(pt.dpdu, pt.dpdv);
    if (!(nObj.lengthSquared() > 0)) return areaScale_;
    return detLinear_ * worldFromObject_.applyNormal(Normalize(nObj)).length();
}

Interaction AnalyticShape::sampleArea(Point2 u, Float *pdf) const {
    Patch pt = patch(sampleObjectPoint(u));
    Interaction it;
    it.p = worldFromObject_.applyPoint(pt.p);
    it.n = worldNormal(pt);
    Float a = objectArea() * areaRatio(pt);
    *pdf = (a > 0 && it.onSurface()) ? 1 / a : 0;
    return it;
}

Float AnalyticShape::pdfArea(const Interaction &it) const {
    Patch pt = patch(objectFromWorld_.applyPoint(it.p));
    Float a = objectArea() * areaRatio(pt);
    return a > 0 ? 1 / a : 0;
}

bool AnalyticShape::intersectP(const Ray &r, Float *tHit, Interaction *hit) const {
    Ray ro = objectFromWorld_.applyRay(r);
    Float t;
    if (!intersectObject(ro, 0, &t)) return false;
    *tHit = t;
    Patch pt = patch(ro(t));
    hit->p = worldFromObject_.applyPoint(pt.p);
    hit->n = worldNormal(pt);
    hit->wo = -r.d;
    return true;
}

void AnalyticShape::interaction(const Ray &worldRay, Float tHit, SurfaceInteraction *si) const {
    Ray r = objectFromWorld_.applyRay(worldRay);
    Patch pt = patch(r(tHit));
    // Normal derivatives from the Weingarten equations.
    Float E = Dot(pt.dpdu, pt.dpdu), F = Dot(pt.dpdu, pt.dpdv), G = Dot(pt.dpdv, pt.dpdv);
    Vec3 nObj = Cross(pt.dpdu, pt.dpdv);
    Normal3 dndu(0, 0, 0), dndv(0, 0, 0);
    Float den = E * G - F * F;
    if (nObj.lengthSquared() > 0 && den > 0) {
        nObj = Normalize(nObj);
        Float e = Dot(nObj, pt.d2pduu), f = Dot(nObj, pt.d2pduv), g = Dot(nObj, pt.d2pdvv);
        Float inv = 1 / den;
        dndu = pt.dpdu * ((f * F - e * G) * inv) + pt.dpdv * ((e * F - f * E) * inv);
        dndv = pt.dpdu * ((g * F - f * G) * inv) + pt.dpdv * ((f * F - g * E) * inv);
    }
    Vec3 dpduW = worldFromObject_.applyVector(pt.dpdu), dpdvW = worldFromObject_.applyVector(pt.dpdv);
    Normal3 n = worldNormal(pt);
    if (!(n.lengthSquared() > 0)) n = Normal3(0, 0, 1);
    si->p = worldFromObject_.applyPoint(pt.p);
    si->uv = pt.uv;
    si->wo = -Normalize(worldRay.d);
    si->n = n;
    si->dpdu = dpduW;
    si->dpdv = dpdvW;
    si->dndu = worldFromObject_.applyNormal(dndu);
    si->dndv = worldFromObject_.applyNormal(dndv);
    si->shading.n = n;
    si->shading.dpdu = dpduW;
    si->shading.dpdv = dpdvW;
    si->shading.dndu = si->dndu;
    si->shading.dndv = si->dndv;
    // World unit normal n = +-m/|m| with m = M^-T n_obj: its derivative is
    // +-(I - n n^T) M^-T dn_obj/du / |m|. (si->dndu above, pbrt-v3's, lacks the
    // 1/|m| factor, e.g. 1/scale under a uniform scale, and the orientation flip.)
    Float mLen = worldFromObject_.applyNormal(nObj).length();
    if (nObj.lengthSquared() > 0 && mLen > 0) {
        const Float sign = flip_ ? -1 : 1;
        auto unit = [&](const Normal3 &dm) { return (dm - n * Dot(n, dm)) * (sign / mLen); };
        si->shading.dnhatdu = unit(si->dndu);
        si->shading.dnhatdv = unit(si->dndv);
    } else {
        si->shading.dnhatdu = si->shading.dnhatdv = Normal3(0, 0, 0);
    }
}

}  // namespace gradus
