#include "materials/bssrdf.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "materials/fresnel.h"
#include "samplers/sampling.h"

namespace gradus {
namespace {

// Largest i in [0, n - 2] with nodes[i] <= x (x assumed inside the range).
int SegmentOf(int n, const Float *nodes, Float x) {
    int lo = 0, hi = n - 1;  // invariant: nodes[lo] <= x, answer < hi
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (nodes[mid] <= x) lo = mid; else hi = mid;
    }
    return std::min(lo, n - 2);
}

// One Hermite segment of a Catmull-Rom spline: values f0, f1 at its ends and
// tangents d0, d1 already scaled to the segment parameter t in [0, 1].
struct HermiteSegment {
    Float f0, f1, d0, d1;
    Float value(Float t) const {
        Float t2 = t * t, t3 = t2 * t;
        return (2 * t3 - 3 * t2 + 1) * f0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * f1 + (t3 - t2) * d1;
    }
    Float derivative(Float t) const {
        Float t2 = t * t;
        return (6 * t2 - 6 * t) * f0 + (3 * t2 - 4 * t + 1) * d0 + (-6 * t2 + 6 * t) * f1 + (3 * t2 - 2 * t) * d1;
    }
    // Integral of value over [0, t].
    Float integral(Float t) const {
        Float t2 = t * t, t3 = t2 * t, t4 = t3 * t;
        return f0 * (t4 / 2 - t3 + t) + d0 * (t4 / 4 - 2 * t3 / 3 + t2 / 2) + f1 * (t3 - t4 / 2) +
               d1 * (t4 / 4 - t3 / 3);
    }
};

// Segment i of the spline through (x, f); get(k) returns f at node k.
template <typename Get>
HermiteSegment SegmentAt(int n, const Float *x, int i, Get get) {
    HermiteSegment s;
    s.f0 = get(i);
    s.f1 = get(i + 1);
    Float w = x[i + 1] - x[i];
    s.d0 = i > 0 ? w * (s.f1 - get(i - 1)) / (x[i + 1] - x[i - 1]) : s.f1 - s.f0;
    s.d1 = i + 2 < n ? w * (get(i + 2) - s.f0) / (x[i + 2] - x[i]) : s.f1 - s.f0;
    return s;
}

// Solves g(t) = target on [0, 1] for increasing g by Newton steps safeguarded by
// bisection; t0 is the first guess.
template <typename G, typename DG>
Float SolveMonotone(G g, DG dg, Float target, Float t0) {
    Float a = 0, b = 1, t = t0;
    for (int it = 0; it < 100; ++it) {
        if (!(t >= a && t <= b)) t = (a + b) / 2;
        Float err = g(t) - target;
        if (std::abs(err) < 1e-12 * (1 + std::abs(target)) || b - a < 1e-12) break;
        if (err < 0) a = t; else b = t;
        Float d = dg(t);
        t = d != 0 ? t - err / d : (a + b) / 2;
    }
    return Clamp<Float>(t, 0, 1);
}

// Henyey-Greenstein density in pbrt-v3's convention (cosTheta between the two
// directions pointing away from the scattering point).
Float PhaseHG(Float cosTheta, Float g) {
    Float denom = 1 + g * g + 2 * g * cosTheta;
    return Inv4Pi * (1 - g * g) / (denom * std::sqrt(denom));
}

}  // namespace

bool CatmullRomWeights(int n, const Float *nodes, Float x, int *offset, Float w[4]) {
    if (!(x >= nodes[0] && x <= nodes[n - 1])) return false;
    int i = SegmentOf(n, nodes, x);
    *offset = i - 1;
    Float x0 = nodes[i], x1 = nodes[i + 1], width = x1 - x0;
    Float t = (x - x0) / width, t2 = t * t, t3 = t2 * t;
    Float h00 = 2 * t3 - 3 * t2 + 1, h01 = -2 * t3 + 3 * t2, h10 = t3 - 2 * t2 + t, h11 = t3 - t2;
    w[0] = 0;
    w[1] = h00;
    w[2] = h01;
    w[3] = 0;
    // Tangent at x0: (f1 - f_{-1}) scaled, or f1 - f0 at the first segment.
    if (i > 0) {
        Float c = h10 * width / (x1 - nodes[i - 1]);
        w[0] -= c;
        w[2] += c;
    } else {
        w[1] -= h10;
        w[2] += h10;
    }
    // Tangent at x1: (f2 - f0) scaled, or f1 - f0 at the last segment.
    if (i + 2 < n) {
        Float c = h11 * width / (nodes[i + 2] - x0);
        w[1] -= c;
        w[3] += c;
    } else {
        w[1] -= h11;
        w[2] += h11;
    }
    return true;
}

Float IntegrateCatmullRom(int n, const Float *x, const Float *f, Float *cdf) {
    auto get = [&](int k) { return f[k]; };
    Float sum = 0;
    cdf[0] = 0;
    for (int i = 0; i + 1 < n; ++i) {
        sum += SegmentAt(n, x, i, get).integral(1) * (x[i + 1] - x[i]);
        cdf[i + 1] = sum;
    }
    return sum;
}

Float InvertCatmullRom(int n, const Float *x, const Float *f, Float u) {
    if (!(u > f[0])) return x[0];
    if (!(u < f[n - 1])) return x[n - 1];
    int i = SegmentOf(n, f, u);
    HermiteSegment s = SegmentAt(n, x, i, [&](int k) { return f[k]; });
    Float t0 = s.f1 != s.f0 ? (u - s.f0) / (s.f1 - s.f0) : 0.5;
    Float t = SolveMonotone([&](Float v) { return s.value(v); }, [&](Float v) { return s.derivative(v); }, u, t0);
    return x[i] + t * (x[i + 1] - x[i]);
}

Float SampleCatmullRom2D(int n1, int n2, const Float *nodes1, const Float *nodes2, const Float *values,
                         const Float *cdf, Float alpha, Float u, Float *fval, Float *pdf) {
    int off;
    Float w[4];
    if (!CatmullRomWeights(n1, nodes1, alpha, &off, w)) return -1;
    // The row at alpha, interpolated on demand.
    auto row = [&](const Float *table, int k) {
        Float v = 0;
        for (int j = 0; j < 4; ++j)
            if (w[j] != 0) v += w[j] * table[size_t(off + j) * n2 + k];
        return v;
    };
    Float total = row(cdf, n2 - 1);
    if (!(total > 0)) return -1;
    Float target = u * total;
    // Segment whose cdf interval holds the target (the interpolated cdf is increasing
    // where the profile is positive).
    int lo = 0, hi = n2 - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (row(cdf, mid) <= target) lo = mid; else hi = mid;
    }
    int i = std::min(lo, n2 - 2);
    HermiteSegment s = SegmentAt(n2, nodes2, i, [&](int k) { return row(values, k); });
    Float width = nodes2[i + 1] - nodes2[i];
    Float rest = (target - row(cdf, i)) / width;  // integral still needed, in units of t
    // First guess: invert the integral of the linear interpolant f0 + (f1 - f0) t.
    Float t0;
    if (s.f0 != s.f1)
        t0 = (s.f0 - SafeSqrt(s.f0 * s.f0 + 2 * rest * (s.f1 - s.f0))) / (s.f0 - s.f1);
    else
        t0 = s.f0 != 0 ? rest / s.f0 : 0.5;
    Float t = SolveMonotone([&](Float v) { return s.integral(v); }, [&](Float v) { return s.value(v); }, rest, t0);
    Float f = s.value(t);
    if (fval) *fval = f;
    if (pdf) *pdf = f / total;
    return nodes2[i] + t * width;
}

// ---------------------------------------------------------------------------

Float FresnelMoment1(Float eta) {
    Float e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1) return 0.45966 - 1.73965 * eta + 3.37668 * e2 - 3.904945 * e3 + 2.49277 * e4 - 0.68441 * e5;
    return -4.61686 + 11.1136 * eta - 10.4646 * e2 + 5.11455 * e3 - 1.27198 * e4 + 0.12746 * e5;
}

Float FresnelMoment2(Float eta) {
    Float e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1) return 0.27614 - 0.87350 * eta + 1.12077 * e2 - 0.65095 * e3 + 0.07883 * e4 + 0.04860 * e5;
    Float r = 1 / eta, r2 = r * r, r3 = r2 * r;
    return -547.033 + 45.3087 * r3 - 218.725 * r2 + 458.843 * r + 404.557 * eta - 189.519 * e2 + 54.9327 * e3 -
           9.00603 * e4 + 0.63942 * e5;
}

Float BeamDiffusionMS(Float sigmaS, Float sigmaA, Float g, Float eta, Float r) {
    const int n = 100;
    // Reduced coefficients (similarity relation) and albedo.
    Float sps = sigmaS * (1 - g), spt = sigmaA + sps, rhop = sps / spt;
    // Grosjean's diffusion coefficient (d'Eon & Irving 2011, Eq. 5) and the transport coefficient.
    Float D = (2 * sigmaA + sps) / (3 * spt * spt);
    Float sigmaTr = SafeSqrt(sigmaA / D);
    // Extrapolated boundary below the surface and the exitance weights of fluence and
    // flux (d'Eon & Irving 2011, Eq. 19-21).
    Float fm1 = FresnelMoment1(eta), fm2 = FresnelMoment2(eta);
    Float ze = -2 * D * (1 + 3 * fm2) / (1 - 2 * fm1);
    Float cPhi = 0.25 * (1 - 2 * fm1), cE = 0.5 * (1 - 3 * fm2);
    Float sum = 0;
    for (int i = 0; i < n; ++i) {
        // Real source depth: the i-th quantile of the beam's exponential falloff.
        Float zr = -std::log(1 - (i + 0.5) / n) / spt;
        Float zv = -zr + 2 * ze;  // mirrored (virtual) source
        Float dr = std::sqrt(r * r + zr * zr), dv = std::sqrt(r * r + zv * zv);
        Float er = std::exp(-sigmaTr * dr), ev = std::exp(-sigmaTr * dv);
        Float phi = Inv4Pi / D * (er / dr - ev / dv);
        Float flux = Inv4Pi * (zr * (1 + sigmaTr * dr) * er / (dr * dr * dr) - zv * (1 + sigmaTr * dv) * ev / (dv * dv * dv));
        Float E = cPhi * phi + cE * flux;
        // Habel et al. 2013's correction for sources close to the exit point.
        Float kappa = 1 - std::exp(-2 * spt * (dr + zr));
        sum += kappa * rhop * rhop * E;
    }
    return sum / n;
}

Float BeamDiffusionSS(Float sigmaS, Float sigmaA, Float g, Float eta, Float r) {
    const int n = 100;
    Float sigmaT = sigmaA + sigmaS, rho = sigmaS / sigmaT;
    // Depth below which the path to the exit lies inside the critical angle.
    Float tCrit = r * SafeSqrt(eta * eta - 1);
    Float sum = 0;
    for (int i = 0; i < n; ++i) {
        Float t = tCrit - std::log(1 - (i + 0.5) / n) / sigmaT;
        Float d = std::sqrt(r * r + t * t);
        Float cosO = t / d;
        sum += rho * std::exp(-sigmaT * (d + tCrit)) / (d * d) * PhaseHG(cosO, g) * (1 - FrDielectric(-cosO, eta)) *
               std::abs(cosO);
    }
    return sum / n;
}

BSSRDFTable ComputeBeamDiffusionTable(Float g, Float eta, int nRho, int nRadius) {
    BSSRDFTable t;
    t.radius.resize(nRadius);
    t.radius[0] = 0;
    if (nRadius > 1) t.radius[1] = 2.5e-3;
    for (int i = 2; i < nRadius; ++i) t.radius[i] = t.radius[i - 1] * 1.2;
    t.rho.resize(nRho);
    for (int i = 0; i < nRho; ++i) t.rho[i] = (1 - std::exp(-8.0 * i / (nRho - 1))) / (1 - std::exp(-8.0));
    t.profile.resize(size_t(nRho) * nRadius);
    t.profileCDF.resize(size_t(nRho) * nRadius);
    t.rhoEff.resize(nRho);
    for (int i = 0; i < nRho; ++i) {
        Float rho = t.rho[i];
        Float *row = &t.profile[size_t(i) * nRadius];
        for (int j = 0; j < nRadius; ++j) {
            Float r = t.radius[j];
            row[j] = 2 * Pi * r * (BeamDiffusionSS(rho, 1 - rho, g, eta, r) + BeamDiffusionMS(rho, 1 - rho, g, eta, r));
        }
        t.rhoEff[i] = IntegrateCatmullRom(nRadius, t.radius.data(), row, &t.profileCDF[size_t(i) * nRadius]);
    }
    return t;
}

void SubsurfaceFromDiffuse(const BSSRDFTable &t, const Spectrum &rhoEff, const Spectrum &mfp, Spectrum *sigmaA,
                           Spectrum *sigmaS) {
    for (int c = 0; c < 3; ++c) {
        Float rho = InvertCatmullRom(t.nRho(), t.rho.data(), t.rhoEff.data(), rhoEff[c]);
        (*sigmaS)[c] = rho / mfp[c];
        (*sigmaA)[c] = (1 - rho) / mfp[c];
    }
}

// ---------------------------------------------------------------------------

BSSRDF::BSSRDF(const SurfaceInteraction &po, const Material *material, Float eta, const Spectrum &sigmaA,
               const Spectrum &sigmaS, const BSSRDFTable &table)
    : po_(po.p), material_(material), eta_(eta), sigmaT_(sigmaA + sigmaS), table_(&table) {
    for (int c = 0; c < kChannels; ++c) rho_[c] = sigmaT_[c] != 0 ? sigmaS[c] / sigmaT_[c] : 0;
    // Frame of the probe axes: shading normal and shading dpdu made orthogonal to it.
    ns_ = po.shading.n;
    Vec3 s = po.shading.dpdu - ns_ * Dot(ns_, po.shading.dpdu);
    Float len2 = s.lengthSquared();
    if (len2 > 1e-20 && std::isfinite(len2)) {
        ss_ = s / std::sqrt(len2);
        ts_ = Cross(ns_, ss_);
    } else {
        CoordinateSystem(ns_, &ss_, &ts_);
    }
}

bool BSSRDF::lookup(Float rho, Float rOptical, Float *value, Float *rhoEff) const {
    const BSSRDFTable &t = *table_;
    int ro, xo;
    Float rw[4], xw[4];
    if (!CatmullRomWeights(t.nRho(), t.rho.data(), rho, &ro, rw) ||
        !CatmullRomWeights(t.nRadius(), t.radius.data(), rOptical, &xo, xw))
        return false;
    Float v = 0, e = 0;
    for (int i = 0; i < 4; ++i) {
        if (rw[i] == 0) continue;
        e += rw[i] * t.rhoEff[ro + i];
        for (int j = 0; j < 4; ++j)
            if (xw[j] != 0) v += rw[i] * xw[j] * t.profileAt(ro + i, xo + j);
    }
    *value = v;
    *rhoEff = e;
    return true;
}

Spectrum BSSRDF::Sr(Float r) const {
    Spectrum out(0);
    for (int c = 0; c < kChannels; ++c) {
        Float rOpt = r * sigmaT_[c], v, e;
        if (!lookup(rho_[c], rOpt, &v, &e)) continue;
        // The table holds 2 pi r Sr in optical units: undo the marginal factor, then
        // scale the per-area density from optical to world units (sigma_t^2).
        if (rOpt != 0) v /= 2 * Pi * rOpt;
        out[c] = std::max<Float>(0, v * sigmaT_[c] * sigmaT_[c]);
    }
    return out;
}

Float BSSRDF::sampleSr(int ch, Float u) const {
    if (sigmaT_[ch] == 0) return -1;
    const BSSRDFTable &t = *table_;
    Float r = SampleCatmullRom2D(t.nRho(), t.nRadius(), t.rho.data(), t.radius.data(), t.profile.data(),
                                 t.profileCDF.data(), rho_[ch], u);
    return r < 0 ? -1 : r / sigmaT_[ch];
}

Float BSSRDF::pdfSr(int ch, Float r) const {
    Float rOpt = r * sigmaT_[ch], v, e;
    if (!lookup(rho_[ch], rOpt, &v, &e) || !(e > 0)) return 0;
    if (rOpt != 0) v /= 2 * Pi * rOpt;
    return std::max<Float>(0, v * sigmaT_[ch] * sigmaT_[ch] / e);
}

Float BSSRDF::pdfSp(const Point3 &pi, const Normal3 &ni) const {
    Vec3 d = po_ - pi;
    Vec3 dl(Dot(ss_, d), Dot(ts_, d), Dot(ns_, d));
    Vec3 nl(Dot(ss_, ni), Dot(ts_, ni), Dot(ns_, ni));
    // Radius seen when projecting along each axis (ss, ts, ns).
    const Float rProj[3] = {std::sqrt(dl.y * dl.y + dl.z * dl.z), std::sqrt(dl.z * dl.z + dl.x * dl.x),
                            std::sqrt(dl.x * dl.x + dl.y * dl.y)};
    const Float axisProb[3] = {0.25, 0.25, 0.5};
    const Float nlc[3] = {nl.x, nl.y, nl.z};
    Float pdf = 0;
    for (int a = 0; a < 3; ++a)
        for (int c = 0; c < kChannels; ++c)
            pdf += pdfSr(c, rProj[a]) * std::abs(nlc[a]) * axisProb[a] / kChannels;
    return pdf;
}

// ---------------------------------------------------------------------------

SubsurfaceExitBxDF::SubsurfaceExitBxDF(Float eta) : BxDF(BSDF_REFLECTION | BSDF_DIFFUSE), eta_(eta) {
    Float c = 1 - 2 * FresnelMoment1(1 / eta);
    invNorm_ = 1 / (c * Pi);
}

Spectrum SubsurfaceExitBxDF::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    if (wo.z * wi.z <= 0) return Spectrum(0);
    Float v = (1 - FrDielectric(std::abs(wi.z), eta_)) * invNorm_;
    // Radiance crossing the interface outwards is scaled by eta^2 (Veach 1997, Sec. 5.2),
    // the counterpart of the 1 / eta^2 of the transmission at the entry point.
    if (mode == TransportMode::Radiance) v *= eta_ * eta_;
    return Spectrum(v);
}

bool SubsurfaceExitBxDF::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    Vec3 wi = SampleCosineHemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    s->wi = wi;
    s->pdf = CosineHemispherePdf(std::abs(wi.z));
    s->pdfRev = CosineHemispherePdf(std::abs(wo.z));
    s->f = f(wo, wi, mode);
    s->flags = BSDF_REFLECTION | BSDF_DIFFUSE;
    s->eta = 1;
    return s->pdf > 0;
}

Float SubsurfaceExitBxDF::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    if (wo.z * wi.z <= 0) return 0;
    return CosineHemispherePdf(std::abs(wi.z));
}

}  // namespace gradus
