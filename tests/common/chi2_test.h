// Chi-square goodness-of-fit helpers for testing sampling routines (header
// only, no test-framework dependency). Typical use in a gtest:
//
//   auto r = gradus::chi2::SphericalTest(
//       [](gradus::RNG &rng, gradus::Vec3 *w) { *w = SampleX({rng.uniform(), rng.uniform()}); return true; },
//       [](const gradus::Vec3 &w) { return PdfX(w); }, opts);
//   EXPECT_TRUE(r.pass) << r.message;
//
// The sample space is cut into bins ((cos theta, phi) for directions, a grid
// for [0,1]^2), the expected count of every bin is N times the numerically
// integrated pdf (midpoint rule on a fine sub-grid), bins expecting fewer than
// 5 samples are pooled, and the test passes when the p-value of the statistic
// exceeds alpha. Use SidakAlpha(0.01, numberOfTests) for alpha so that a whole
// suite of correct routines fails with probability 1%. Seeds are fixed, so a
// given routine passes or fails deterministically.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "samplers/rng.h"

namespace gradus {
namespace chi2 {

// Regularized lower incomplete gamma P(a, x) = gamma(a, x) / Gamma(a), by its
// power series (converges fast for x < a + 1).
inline double GammaPSeries(double a, double x) {
    double term = 1 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
        term *= x / (a + n);
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-16) break;
    }
    return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Regularized upper incomplete gamma Q(a, x) by its continued fraction
// (modified Lentz evaluation; for x >= a + 1).
inline double GammaQContinuedFraction(double a, double x) {
    const double tiny = 1e-300;
    double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        double an = -i * (i - a);
        b += 2;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1 / d;
        double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1) < 1e-16) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

inline double RegularizedGammaP(double a, double x) {
    if (x <= 0) return 0;
    if (std::isinf(x)) return 1;
    return x < a + 1 ? GammaPSeries(a, x) : 1 - GammaQContinuedFraction(a, x);
}

inline double RegularizedGammaQ(double a, double x) {
    if (x <= 0) return 1;
    if (std::isinf(x)) return 0;
    return x < a + 1 ? 1 - GammaPSeries(a, x) : GammaQContinuedFraction(a, x);
}

// Probability that a chi-square variable with `dof` degrees of freedom exceeds `stat`.
inline double PValue(double stat, int dof) { return RegularizedGammaQ(0.5 * dof, 0.5 * stat); }

// Per-test significance so that `numTests` independent tests of correct code
// all pass with probability 1 - overall (Sidak correction).
inline double SidakAlpha(double overall, int numTests) {
    return 1 - std::pow(1 - overall, 1.0 / numTests);
}

struct Result {
    bool pass = false;
    double statistic = 0;
    int dof = 0;
    double pValue = 0;
    double alpha = 0;
    int64_t invalid = 0;   // samples reported invalid
    std::string message;   // human-readable summary (why it failed)
};

// Chi-square test of observed counts against expected counts (same total up to
// rounding). Bins expecting fewer than minExpected are pooled into one bin,
// itself merged with the smallest regular bin if still below minExpected.
// Fails at once if a bin with (numerically) zero expectation has samples.
inline Result TestCounts(const std::vector<double> &observed, const std::vector<double> &expected,
                         double alpha, double minExpected = 5) {
    Result r;
    r.alpha = alpha;
    double total = std::accumulate(expected.begin(), expected.end(), 0.0);
    std::vector<size_t> order(expected.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    std::vector<std::pair<double, double>> bins;  // (observed, expected)
    double poolObs = 0, poolExp = 0;
    for (size_t i : order) {
        if (expected[i] <= 1e-12 * total && observed[i] > 0) {
            std::ostringstream os;
            os << "bin " << i << " has " << observed[i] << " samples but expected " << expected[i]
               << " (samples where the pdf is zero)";
            r.message = os.str();
            return r;
        }
        if (expected[i] < minExpected) {
            poolObs += observed[i];
            poolExp += expected[i];
        } else {
            bins.push_back({observed[i], expected[i]});
        }
    }
    if (poolExp > 0 || poolObs > 0) {
        if (poolExp >= minExpected || bins.empty()) {
            bins.push_back({poolObs, poolExp});
        } else {
            bins.front().first += poolObs;  // smallest regular bin (sorted ascending)
            bins.front().second += poolExp;
        }
    }
    if (bins.size() < 2) {
        r.message = "too few bins with enough expected samples for a chi-square test";
        return r;
    }
    double stat = 0;
    for (auto &b : bins) stat += (b.first - b.second) * (b.first - b.second) / b.second;
    r.statistic = stat;
    r.dof = int(bins.size()) - 1;
    r.pValue = PValue(stat, r.dof);
    r.pass = r.pValue > alpha;
    std::ostringstream os;
    os << "chi2 = " << stat << ", dof = " << r.dof << ", p = " << r.pValue << " (alpha = " << alpha << ")";
    r.message = os.str();
    return r;
}

// Midpoint rule on an n x n sub-grid of [x0,x1] x [y0,y1]. Only interior points
// are evaluated, so a pdf discontinuous along bin edges (hemispheres, tabulated
// distributions) is integrated exactly when it is constant inside each bin.
template <typename F>
double IntegrateCell(F f, double x0, double x1, double y0, double y1, int n) {
    double hx = (x1 - x0) / n, hy = (y1 - y0) / n, sum = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) sum += f(x0 + (i + 0.5) * hx, y0 + (j + 0.5) * hy);
    return sum * hx * hy;
}

struct Options {
    int xBins = 10;          // cos(theta) bins over [-1, 1] (directions) or x bins over [0, 1)
    int yBins = 20;          // phi bins over [0, 2 pi) (directions) or y bins over [0, 1)
    int64_t samples = 200000;
    int subdivisions = 16;   // integration sub-intervals per bin side
    double alpha = 0.01;
    uint64_t seed = 1;
    // Count invalid samples as an extra bin expecting N (1 - integral of pdf).
    // Turn off for routines whose pdf does not account for failures.
    bool invalidBin = true;
};

namespace detail {
inline Result Finish(std::vector<double> obs, std::vector<double> exp, int64_t invalid, const Options &o) {
    if (o.invalidBin) {
        double integral = std::accumulate(exp.begin(), exp.end(), 0.0) / double(o.samples);
        obs.push_back(double(invalid));
        exp.push_back(std::max(0.0, 1 - integral) * double(o.samples));
    }
    Result r = TestCounts(obs, exp, o.alpha);
    r.invalid = invalid;
    r.message += ", invalid samples = " + std::to_string(invalid);
    return r;
}
inline Result Fail(const std::string &why) {
    Result r;
    r.message = why;
    return r;
}
}  // namespace detail

// Directions: sample(RNG&, Vec3*) -> bool (false = no sample), pdf(const Vec3&)
// with respect to solid angle. Returned directions must be unit length.
template <typename SampleFn, typename PdfFn>
Result SphericalTest(SampleFn sample, PdfFn pdf, const Options &o = Options()) {
    const int nc = o.xBins, np = o.yBins;
    std::vector<double> obs(size_t(nc) * np, 0.0), exp(size_t(nc) * np, 0.0);
    RNG rng(o.seed);
    int64_t invalid = 0;
    for (int64_t s = 0; s < o.samples; ++s) {
        Vec3 w;
        if (!sample(rng, &w)) {
            ++invalid;
            continue;
        }
        if (!w.isFinite()) return detail::Fail("sample returned a non-finite direction");
        if (std::abs(w.length() - 1) > 1e-6) {
            std::ostringstream os;
            os << "sample returned a direction of length " << w.length() << ": " << w;
            return detail::Fail(os.str());
        }
        int ci = Clamp(int((w.z + 1) / 2 * nc), 0, nc - 1);
        int pi = Clamp(int(SphericalPhi(w) * Inv2Pi * np), 0, np - 1);
        obs[size_t(ci) * np + pi] += 1;
    }
    auto f = [&](double c, double phi) { return double(pdf(SphericalDirection(SafeSqrt(1 - c * c), c, phi))); };
    for (int ci = 0; ci < nc; ++ci)
        for (int pi = 0; pi < np; ++pi)
            exp[size_t(ci) * np + pi] =
                o.samples * IntegrateCell(f, -1 + 2.0 * ci / nc, -1 + 2.0 * (ci + 1) / nc, 2 * Pi * pi / np,
                                      2 * Pi * (pi + 1) / np, o.subdivisions);
    return detail::Finish(std::move(obs), std::move(exp), invalid, o);
}

// Points of [0,1)^2: sample(RNG&, Point2*) -> bool, pdf(Point2) w.r.t. area.
template <typename SampleFn, typename PdfFn>
Result PlanarTest(SampleFn sample, PdfFn pdf, const Options &o = Options()) {
    const int nx = o.xBins, ny = o.yBins;
    std::vector<double> obs(size_t(nx) * ny, 0.0), exp(size_t(nx) * ny, 0.0);
    RNG rng(o.seed);
    int64_t invalid = 0;
    for (int64_t s = 0; s < o.samples; ++s) {
        Point2 p;
        if (!sample(rng, &p)) {
            ++invalid;
            continue;
        }
        if (!(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1)) {
            std::ostringstream os;
            os << "sample returned (" << p.x << ", " << p.y << ") outside [0,1)^2";
            return detail::Fail(os.str());
        }
        obs[size_t(int(p.x * nx)) * ny + int(p.y * ny)] += 1;
    }
    auto f = [&](double x, double y) { return double(pdf(Point2(x, y))); };
    for (int i = 0; i < nx; ++i)
        for (int j = 0; j < ny; ++j)
            exp[size_t(i) * ny + j] =
                o.samples * IntegrateCell(f, double(i) / nx, double(i + 1) / nx, double(j) / ny, double(j + 1) / ny,
                                      o.subdivisions);
    return detail::Finish(std::move(obs), std::move(exp), invalid, o);
}

}  // namespace chi2
}  // namespace gradus
