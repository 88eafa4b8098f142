#include "integrators/gradient/shift.h"

#include <cstdio>

#include "materials/bxdf_util.h"

namespace gradus {

ShiftVertexClass ClassifyBSDF(const BSDF *bsdf, Float shiftThreshold) {
    if (!bsdf || !*bsdf) return ShiftVertexClass::Invalid;
    return bsdf->roughnessClass(shiftThreshold) == RoughnessClass::Rough ? ShiftVertexClass::Rough
                                                                          : ShiftVertexClass::NonRough;
}

bool ShiftReconnect(const Point3 &xPrev, const Point3 &yPrev, const ShiftVertex &target, ReconnectionShift *out) {
    if (target.atInfinity) {  // environment-map shift: same direction
        out->wi = target.p;
        out->dist2 = 0;
        out->jacobian = 1;
        return true;
    }
    Vec3 dy = target.p - yPrev, dx = target.p - xPrev;
    Float d2y = dy.lengthSquared(), d2x = dx.lengthSquared();
    if (!(d2y > kShiftEps) || !(d2x > kShiftEps)) return false;
    Vec3 wy = dy / std::sqrt(d2y), wx = dx / std::sqrt(d2x);
    out->wi = wy;
    out->dist2 = d2y;
    if (target.n == Normal3(0, 0, 0)) {  // point vertex: positions only, no cosines
        out->jacobian = d2x / d2y;
        return true;
    }
    Float cy = AbsDot(wy, target.n), cx = AbsDot(wx, target.n);
    Float den = cx * d2y;
    if (!(den > kShiftEps)) return false;
    out->jacobian = cy * d2x / den;
    return out->jacobian > 0 && std::isfinite(out->jacobian);
}

bool ShiftHalfVector(const Vec3 &woX, const Vec3 &wiX, const Vec3 &woY, Float eta, HalfVectorShift *out) {
    bool reflect = woX.z * wiX.z > 0;
    out->refraction = !reflect;
    if (reflect) {
        Vec3 h = woX + wiX;
        Float len2 = h.lengthSquared();
        if (!(len2 > kShiftEps)) return false;
        h = h / std::sqrt(len2);
        Vec3 wi = bxdfutil::Reflect(woY, h);
        if (wi.z * woY.z <= 0) return false;  // below the surface: no (invertible) reflection
        Float den = AbsDot(wiX, h);
        if (!(den > kShiftEps)) return false;
        out->wi = Normalize(wi);
        out->jacobian = AbsDot(out->wi, h) / den;
        return out->jacobian > 0;
    }
    // Refraction: a half vector needs an index change and the same incident side.
    if (eta == 1 || woX.z * woY.z <= 0) return false;
    Vec3 hu = woX + wiX * eta;
    Float len2 = hu.lengthSquared();
    if (!(len2 > kShiftEps)) return false;
    Vec3 h = hu / std::sqrt(len2);
    if (h.z < 0) h = -h;
    Vec3 n = woY.z > 0 ? h : -h;
    if (Dot(woY, n) <= 0) return false;
    Vec3 wi;
    if (!bxdfutil::Refract(woY, n, eta, &wi)) return false;  // total internal reflection
    if (wi.z * woY.z >= 0) return false;
    wi = Normalize(wi);
    Float numY = Sqr(Dot(woY, h) + eta * Dot(wi, h));   // |h_u(y)|^2
    Float denX = Sqr(Dot(woX, h) + eta * Dot(wiX, h));  // |h_u(x)|^2
    Float den = AbsDot(wi, h) * denX;
    if (!(den > kShiftEps)) return false;
    out->wi = wi;
    out->jacobian = AbsDot(wiX, h) * numY / den;
    return out->jacobian > 0 && std::isfinite(out->jacobian);
}

bool ShiftHalfVectorWorld(const BSDF &bx, const Vec3 &woX, const Vec3 &wiX, const BSDF &by, const Vec3 &woY,
                          HalfVectorShift *out) {
    const Vec3 woL = bx.toLocal(woX), wiL = bx.toLocal(wiX);
    Float eta = 1;
    if (woL.z * wiL.z < 0) {
        // Walter et al. 2007: eta = index on wi's side over wo's side.
        const Float e = bx.eta();
        if (e == 1) return false;
        eta = woL.z > 0 ? e : 1 / e;
    }
    if (!ShiftHalfVector(woL, wiL, by.toLocal(woY), eta, out)) return false;
    out->wi = Normalize(by.toWorld(out->wi));
    return true;
}

bool ShiftReplay(const BSDF &offsetBsdf, const Vec3 &woY, Float uc, Point2 u, Float basePdf, TransportMode mode,
                 ReplayShift *out) {
    if (!offsetBsdf.sample(woY, uc, u, mode, &out->sample) || !out->sample.valid()) return false;
    if (!(out->sample.pdf > 0) || !(basePdf > 0)) return false;
    out->jacobian = basePdf / out->sample.pdf;
    return std::isfinite(out->jacobian);
}

const char *ShiftTypeName(ShiftType t) {
    switch (t) {
    case ShiftType::Reconnection: return "reconnection";
    case ShiftType::Environment: return "environment";
    case ShiftType::HalfVector: return "half-vector copy";
    case ShiftType::Replay: return "random replay";
    default: return "?";
    }
}
const char *ShiftFailureName(ShiftFailure f) {
    switch (f) {
    case ShiftFailure::Occluded: return "occluded";
    case ShiftFailure::ClassMismatch: return "class mismatch (not invertible)";
    case ShiftFailure::Geometry: return "geometry (TIR, zero pdf/BSDF, degenerate)";
    case ShiftFailure::Escaped: return "escaped/hit mismatch";
    default: return "?";
    }
}

void ShiftStats::add(const LocalShiftStats &l) {
    for (int i = 0; i < int(ShiftType::Count); ++i) {
        if (l.attempts[i]) attempts_[i] += l.attempts[i];
        if (l.successes[i]) successes_[i] += l.successes[i];
    }
    for (int i = 0; i < int(ShiftFailure::Count); ++i)
        if (l.failures[i]) failures_[i] += l.failures[i];
    if (l.offsetPaths) offsetPaths_ += l.offsetPaths;
}

void ShiftStats::reset() {
    for (auto &a : attempts_) a = 0;
    for (auto &a : successes_) a = 0;
    for (auto &a : failures_) a = 0;
    offsetPaths_ = 0;
}

std::string ShiftStats::format(const std::string &title) const {
    std::string s;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s: offset paths %llu\n", title.c_str(), (unsigned long long)offsetPaths_.load());
    s += buf;
    for (int i = 0; i < int(ShiftType::Count); ++i) {
        uint64_t a = attempts_[i], ok = successes_[i];
        std::snprintf(buf, sizeof buf, "  %-18s attempts %12llu  successes %12llu  failures %12llu (%.2f%% success)\n",
                      ShiftTypeName(ShiftType(i)), (unsigned long long)a, (unsigned long long)ok,
                      (unsigned long long)(a - ok), a ? 100.0 * ok / a : 0.0);
        s += buf;
    }
    for (int i = 0; i < int(ShiftFailure::Count); ++i) {
        std::snprintf(buf, sizeof buf, "  failed: %-40s %12llu\n", ShiftFailureName(ShiftFailure(i)),
                      (unsigned long long)failures_[i].load());
        s += buf;
    }
    return s;
}

}  // namespace gradus
