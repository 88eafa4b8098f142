// Sampling routines: warps from [0,1)^2 to common domains (with their pdfs and,
// where useful, inverses), MIS heuristics and tabulated 1D/2D distributions.
// All pdfs of directions are with respect to solid angle.
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/geometry.h"
#include "samplers/rng.h"

namespace gradus {

// Shirley-Chiu concentric map of the square onto the unit disk.
inline Point2 SampleUniformDiskConcentric(Point2 u) {
    Float ox = 2 * u.x - 1, oy = 2 * u.y - 1;
    if (ox == 0 && oy == 0) return {0, 0};
    Float r, theta;
    if (std::abs(ox) > std::abs(oy)) {
        r = ox;
        theta = (Pi / 4) * (oy / ox);
    } else {
        r = oy;
        theta = Pi / 2 - (Pi / 4) * (ox / oy);
    }
    return {r * std::cos(theta), r * std::sin(theta)};
}

// Inverse of SampleUniformDiskConcentric for a point in the unit disk.
inline Point2 InvertUniformDiskConcentric(Point2 p) {
    Float r = std::sqrt(p.x * p.x + p.y * p.y);
    if (r == 0) return {0.5, 0.5};
    Float phi = std::atan2(p.y, p.x);           // (-pi, pi]
    if (phi < -Pi / 4) phi += 2 * Pi;           // [-pi/4, 7pi/4)
    Float ox, oy;
    if (phi < Pi / 4) {                         // right wedge: r = ox > 0
        ox = r;
        oy = ox * phi * (4 / Pi);
    } else if (phi < 3 * Pi / 4) {              // top wedge: r = oy > 0
        oy = r;
        ox = oy * (Pi / 2 - phi) * (4 / Pi);
    } else if (phi < 5 * Pi / 4) {              // left wedge: r = ox < 0, angle phi - pi
        ox = -r;
        oy = ox * (phi - Pi) * (4 / Pi);
    } else {                                    // bottom wedge: r = oy < 0
        oy = -r;
        ox = oy * (Pi / 2 - (phi - Pi)) * (4 / Pi);
    }
    return {Clamp<Float>((ox + 1) / 2, 0, 1), Clamp<Float>((oy + 1) / 2, 0, 1)};
}

// Malley's method: project the concentric disk up to the hemisphere (z > 0).
inline Vec3 SampleCosineHemisphere(Point2 u) {
    Point2 d = SampleUniformDiskConcentric(u);
    Float z = SafeSqrt(1 - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}
inline Float CosineHemispherePdf(Float cosTheta) { return std::max<Float>(cosTheta, 0) * InvPi; }
inline Point2 InvertCosineHemisphere(const Vec3 &w) { return InvertUniformDiskConcentric({w.x, w.y}); }

inline Vec3 SampleUniformHemisphere(Point2 u) {
    Float z = u.x;
    Float r = SafeSqrt(1 - z * z);
    Float phi = 2 * Pi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline Float UniformHemispherePdf() { return Inv2Pi; }
inline Point2 InvertUniformHemisphere(const Vec3 &w) {
    return {Clamp<Float>(w.z, 0, 1), SphericalPhi(w) * Inv2Pi};
}

inline Vec3 SampleUniformSphere(Point2 u) {
    Float z = 1 - 2 * u.x;
    Float r = SafeSqrt(1 - z * z);
    Float phi = 2 * Pi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}
inline Float UniformSpherePdf() { return Inv4Pi; }
inline Point2 InvertUniformSphere(const Vec3 &w) {
    return {Clamp<Float>((1 - w.z) / 2, 0, 1), SphericalPhi(w) * Inv2Pi};
}

// Uniform over the cone of directions around +z with cos(theta) >= cosThetaMax.
inline Vec3 SampleUniformCone(Point2 u, Float cosThetaMax) {
    Float cosTheta = (1 - u.x) + u.x * cosThetaMax;
    Float sinTheta = SafeSqrt(1 - cosTheta * cosTheta);
    Float phi = 2 * Pi * u.y;
    return SphericalDirection(sinTheta, cosTheta, phi);
}
inline Float UniformConePdf(Float cosThetaMax) { return 1 / (2 * Pi * (1 - cosThetaMax)); }
inline Point2 InvertUniformCone(const Vec3 &w, Float cosThetaMax) {
    return {Clamp<Float>((1 - w.z) / (1 - cosThetaMax), 0, 1), SphericalPhi(w) * Inv2Pi};
}

// Uniform barycentrics (b0, b1) over a triangle; b2 = 1 - b0 - b1. pdf = 1/area.
inline Point2 SampleUniformTriangle(Point2 u) {
    Float su0 = std::sqrt(u.x);
    return {1 - su0, u.y * su0};
}
inline Point2 InvertUniformTriangle(Point2 b) {
    Float su0 = 1 - b.x;
    return {Clamp<Float>(su0 * su0, 0, 1), su0 > 0 ? Clamp<Float>(b.y / su0, 0, 1) : 0};
}

// Exponential distribution with rate a: pdf a exp(-a x) on [0, inf).
inline Float SampleExponential(Float u, Float a) { return -std::log1p(-u) / a; }
inline Float ExponentialPdf(Float x, Float a) { return x < 0 ? 0 : a * std::exp(-a * x); }

// Multiple importance sampling weights (Veach 1997, sec. 9.2). An infinite pdf
// (delta strategy) takes the whole weight; two zero pdfs give weight 0.
inline Float PowerHeuristic(int nf, Float fPdf, int ng, Float gPdf) {
    Float f = nf * fPdf, g = ng * gPdf;
    if (std::isinf(f)) return std::isinf(g) ? Float(0.5) : Float(1);
    if (std::isinf(g)) return 0;
    if (f == 0 && g == 0) return 0;
    // Written with the ratio of the smaller to the larger: no overflow of f^2.
    if (f >= g) {
        Float r = g / f;
        return 1 / (1 + r * r);
    }
    Float r = f / g;
    return r * r / (1 + r * r);
}
inline Float BalanceHeuristic(int nf, Float fPdf, int ng, Float gPdf) {
    Float f = nf * fPdf, g = ng * gPdf;
    if (std::isinf(f)) return std::isinf(g) ? Float(0.5) : Float(1);
    if (std::isinf(g)) return 0;
    if (f == 0 && g == 0) return 0;
    if (f >= g) return 1 / (1 + g / f);
    Float r = f / g;
    return r / (1 + r);
}

// One tabulated piecewise-constant row: for n buckets, n + 1 entries
// {cdf[i], pdf[i]} (pdf = f / integral, the last pdf unused), so the bucket's
// cdf bounds and density share cache lines, and a guide table of G + 1 bucket
// indices (G a power of two): bucket(u) lies in [guide[k], guide[k + 1]] for
// k = floor(u G), since the search is monotone in u and k / G <= u < (k+1) / G
// exactly (scaling by a power of two is exact). Sampling walks a few adjacent
// entries instead of a binary search over the whole row.
struct CdfEntry {
    Float cdf, pdf;
};
namespace detail {
// Guide size for n buckets: about one guide entry per four buckets.
inline int GuideSize(int n) {
    int g = 1;
    while (g * 4 < n) g <<= 1;
    return g;
}
// Fills e[0..n] and guide[0..G] from f[0..n-1] (throws on negative or
// non-finite values); returns the integral sum f / n.
Float BuildRow(const Float *f, int n, CdfEntry *e, int32_t *guide, int G, const char *who);
// Largest i in [0, n) with cdf[i] <= u (u in [0, 1)): bucket i has non-zero
// probability (zero-valued buckets are never returned).
inline int FindBucket(const CdfEntry *e, const int32_t *guide, int G, Float u) {
    int k = u >= 0 ? int(u * G) : 0;  // NaN: no out-of-range guide index
    int lo = guide[k], hi = guide[k + 1] + 1;  // invariant: cdf[lo] <= u, answer in [lo, hi)
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (e[mid].cdf <= u) lo = mid;
        else hi = mid;
    }
    return lo;
}
// x in bucket o of a row of n buckets for u (clamped to [0, 1)), with its pdf.
inline Float SampleRow(const CdfEntry *e, const int32_t *guide, int G, int n, Float u, Float *pdf, int *offset) {
    u = Clamp<Float>(u, 0, OneMinusEpsilon);
    int o = FindBucket(e, guide, G, u);
    if (offset) *offset = o;
    Float c0 = e[o].cdf, width = e[o + 1].cdf - c0;
    Float du = width > 0 ? (u - c0) / width : 0;
    if (pdf) *pdf = e[o].pdf;
    // Keep x inside bucket o despite rounding (the next bucket may have f = 0).
    Float x = (o + du) / n, end = Float(o + 1) / n;
    return x < end ? x : std::nextafter(end, Float(0));
}
}  // namespace detail

// Piecewise-constant distribution over [0, 1) with n equal-width buckets.
class Distribution1D {
  public:
    Distribution1D() = default;
    // Negative or non-finite entries throw gradus::Error. If every entry is
    // zero the distribution samples uniformly (and reports pdf 1 / pmf 1/n), so
    // sampling and pdf queries stay consistent.
    Distribution1D(const Float *f, int n);
    explicit Distribution1D(const std::vector<Float> &f) : Distribution1D(f.data(), int(f.size())) {}

    // Returns x in [0, 1), its density and the bucket it fell in.
    Float sampleContinuous(Float u, Float *pdf, int *offset = nullptr) const {
        return detail::SampleRow(e_.data(), guide_.data(), G_, count(), u, pdf, offset);
    }
    // Returns a bucket index with probability discretePmf(index); uRemapped
    // receives u rescaled to [0, 1) within the chosen bucket (reusable).
    int sampleDiscrete(Float u, Float *pmf = nullptr, Float *uRemapped = nullptr) const;
    Float discretePmf(int index) const;
    Float pdfContinuous(Float x) const {
        if (!(x >= 0 && x < 1) || func_.empty()) return 0;
        return e_[Clamp<int>(int(x * count()), 0, count() - 1)].pdf;
    }
    int count() const { return int(func_.size()); }
    // Integral of the (unnormalised) function over [0, 1): sum f / n.
    Float integral() const { return funcInt_; }
    Float value(int i) const { return func_[i]; }

  private:
    std::vector<Float> func_;
    std::vector<CdfEntry> e_;
    std::vector<int32_t> guide_;
    int G_ = 0;
    Float funcInt_ = 0;
};

// Piecewise-constant distribution over [0, 1)^2: a marginal over rows (v) and
// one conditional per row (u), the conditionals in one contiguous table
// (row v at entries v (nu + 1) .. v (nu + 1) + nu) with one guide table.
class Distribution2D {
  public:
    Distribution2D() = default;
    // f is row-major, nu values per row, nv rows (u fastest).
    Distribution2D(const Float *f, int nu, int nv);
    Point2 sampleContinuous(Point2 u, Float *pdf) const {
        Float pdfV, pdfU;
        int v;
        Float y = marginal_.sampleContinuous(u.y, &pdfV, &v);
        Float x = detail::SampleRow(&cond_[size_t(v) * (nu_ + 1)], &condGuide_[size_t(v) * (G_ + 1)], G_, nu_, u.x,
                                    &pdfU, nullptr);
        if (pdf) *pdf = pdfU * pdfV;
        return {x, y};
    }
    Float pdf(Point2 p) const {
        if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1) || nv_ == 0) return 0;
        int v = Clamp<int>(int(p.y * nv_), 0, nv_ - 1);
        int u = Clamp<int>(int(p.x * nu_), 0, nu_ - 1);
        return marginal_.pdfContinuous(p.y) * cond_[size_t(v) * (nu_ + 1) + u].pdf;
    }
    int countU() const { return nu_; }
    int countV() const { return nv_; }
    Float integral() const { return marginal_.integral(); }

  private:
    int nu_ = 0, nv_ = 0, G_ = 0;
    std::vector<CdfEntry> cond_;
    std::vector<int32_t> condGuide_;
    Distribution1D marginal_;
};

}  // namespace gradus
