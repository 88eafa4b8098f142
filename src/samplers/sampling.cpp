#include "samplers/sampling.h"

#include <string>

#include "core/error.h"
#include "samplers/rng.h"

namespace gradus {

namespace detail {

Float BuildRow(const Float *f, int n, CdfEntry *e, int32_t *guide, int G, const char *who) {
    for (int i = 0; i < n; ++i)
        if (!(f[i] >= 0) || !std::isfinite(f[i]))
            throw Error(std::string(who) + ": value " + std::to_string(i) + " is negative or not finite (" +
                        std::to_string(f[i]) + ")");
    e[0].cdf = 0;
    for (int i = 0; i < n; ++i) e[i + 1].cdf = e[i].cdf + f[i] / n;
    Float funcInt = e[n].cdf;
    if (funcInt == 0) {
        for (int i = 1; i <= n; ++i) e[i].cdf = Float(i) / n;
    } else {
        for (int i = 1; i <= n; ++i) e[i].cdf /= funcInt;
    }
    e[n].cdf = 1;
    for (int i = 0; i < n; ++i) e[i].pdf = funcInt > 0 ? f[i] / funcInt : 1;
    e[n].pdf = 0;
    // guide[k] = bucket of u = k / G (largest i < n with cdf[i] <= k / G), one sweep.
    int i = 0;
    for (int k = 0; k <= G; ++k) {
        Float u = std::min<Float>(Float(k) / G, OneMinusEpsilon);
        while (i + 1 < n && e[i + 1].cdf <= u) ++i;
        guide[k] = i;
    }
    return funcInt;
}

}  // namespace detail

Distribution1D::Distribution1D(const Float *f, int n) {
    if (n <= 0) throw Error("Distribution1D: needs at least one value");
    func_.assign(f, f + n);
    e_.resize(size_t(n) + 1);
    G_ = detail::GuideSize(n);
    guide_.resize(size_t(G_) + 1);
    funcInt_ = detail::BuildRow(f, n, e_.data(), guide_.data(), G_, "Distribution1D");
}

int Distribution1D::sampleDiscrete(Float u, Float *pmf, Float *uRemapped) const {
    u = Clamp<Float>(u, 0, OneMinusEpsilon);
    int o = detail::FindBucket(e_.data(), guide_.data(), G_, u);
    if (pmf) *pmf = discretePmf(o);
    if (uRemapped) {
        Float width = e_[o + 1].cdf - e_[o].cdf;
        *uRemapped = std::min<Float>(width > 0 ? (u - e_[o].cdf) / width : 0, OneMinusEpsilon);
    }
    return o;
}

Float Distribution1D::discretePmf(int index) const {
    if (index < 0 || index >= count()) return 0;
    return funcInt_ > 0 ? func_[index] / (funcInt_ * count()) : Float(1) / count();
}

Distribution2D::Distribution2D(const Float *f, int nu, int nv) : nu_(nu), nv_(nv) {
    if (nu <= 0 || nv <= 0) throw Error("Distribution2D: needs a non-empty grid");
    G_ = detail::GuideSize(nu);
    cond_.resize(size_t(nv) * (nu + 1));
    condGuide_.resize(size_t(nv) * (G_ + 1));
    std::vector<Float> rowInt(nv);
    for (int v = 0; v < nv; ++v)
        rowInt[v] = detail::BuildRow(f + size_t(v) * nu, nu, &cond_[size_t(v) * (nu + 1)],
                                     &condGuide_[size_t(v) * (G_ + 1)], G_, "Distribution1D");
    marginal_ = Distribution1D(rowInt.data(), nv);
}

}  // namespace gradus
