#include "samplers/sampling.h"

#include <string>

#include "core/error.h"
#include "samplers/rng.h"

namespace gradus {

Distribution1D::Distribution1D(const Float *f, int n) {
    if (n <= 0) throw Error("Distribution1D: needs at least one value");
    func_.assign(f, f + n);
    for (int i = 0; i < n; ++i)
        if (!(func_[i] >= 0) || !std::isfinite(func_[i]))
            throw Error("Distribution1D: value " + std::to_string(i) + " is negative or not finite (" +
                        std::to_string(func_[i]) + ")");
    cdf_.resize(n + 1);
    cdf_[0] = 0;
    for (int i = 0; i < n; ++i) cdf_[i + 1] = cdf_[i] + func_[i] / n;
    funcInt_ = cdf_[n];
    if (funcInt_ == 0) {
        for (int i = 1; i <= n; ++i) cdf_[i] = Float(i) / n;
    } else {
        for (int i = 1; i <= n; ++i) cdf_[i] /= funcInt_;
    }
    cdf_[n] = 1;
}

// Largest i with cdf[i] <= u; then cdf[i] <= u < cdf[i+1], so the bucket has
// non-zero probability (zero-valued buckets are never returned).
int Distribution1D::findBucket(Float u) const {
    int n = count();
    int lo = 0, hi = n;  // invariant: cdf[lo] <= u, answer in [lo, hi)
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (cdf_[mid] <= u) lo = mid;
        else hi = mid;
    }
    return lo;
}

Float Distribution1D::sampleContinuous(Float u, Float *pdf, int *offset) const {
    u = Clamp<Float>(u, 0, OneMinusEpsilon);
    int o = findBucket(u);
    if (offset) *offset = o;
    Float width = cdf_[o + 1] - cdf_[o];
    Float du = width > 0 ? (u - cdf_[o]) / width : 0;
    if (pdf) *pdf = funcInt_ > 0 ? func_[o] / funcInt_ : 1;
    // Keep x inside bucket o despite rounding (the next bucket may have f = 0).
    Float x = (o + du) / count(), end = Float(o + 1) / count();
    return x < end ? x : std::nextafter(end, Float(0));
}

int Distribution1D::sampleDiscrete(Float u, Float *pmf, Float *uRemapped) const {
    u = Clamp<Float>(u, 0, OneMinusEpsilon);
    int o = findBucket(u);
    if (pmf) *pmf = discretePmf(o);
    if (uRemapped) {
        Float width = cdf_[o + 1] - cdf_[o];
        *uRemapped = std::min<Float>(width > 0 ? (u - cdf_[o]) / width : 0, OneMinusEpsilon);
    }
    return o;
}

Float Distribution1D::discretePmf(int index) const {
    if (index < 0 || index >= count()) return 0;
    return funcInt_ > 0 ? func_[index] / (funcInt_ * count()) : Float(1) / count();
}

Float Distribution1D::pdfContinuous(Float x) const {
    if (!(x >= 0 && x < 1) || func_.empty()) return 0;
    int o = Clamp<int>(int(x * count()), 0, count() - 1);
    return funcInt_ > 0 ? func_[o] / funcInt_ : 1;
}

Distribution2D::Distribution2D(const Float *f, int nu, int nv) : nu_(nu), nv_(nv) {
    if (nu <= 0 || nv <= 0) throw Error("Distribution2D: needs a non-empty grid");
    conditional_.reserve(nv);
    std::vector<Float> rowInt(nv);
    for (int v = 0; v < nv; ++v) {
        conditional_.emplace_back(f + size_t(v) * nu, nu);
        rowInt[v] = conditional_.back().integral();
    }
    marginal_ = Distribution1D(rowInt.data(), nv);
}

Point2 Distribution2D::sampleContinuous(Point2 u, Float *pdf) const {
    Float pdfV, pdfU;
    int v;
    Float y = marginal_.sampleContinuous(u.y, &pdfV, &v);
    Float x = conditional_[v].sampleContinuous(u.x, &pdfU);
    if (pdf) *pdf = pdfU * pdfV;
    return {x, y};
}

Float Distribution2D::pdf(Point2 p) const {
    if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1) || nv_ == 0) return 0;
    int v = Clamp<int>(int(p.y * nv_), 0, nv_ - 1);
    return marginal_.pdfContinuous(p.y) * conditional_[v].pdfContinuous(p.x);
}

}  // namespace gradus
