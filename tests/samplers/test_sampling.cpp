// Warping functions, their inverses, tabulated distributions and MIS weights,
// checked with the chi-square helpers of common/chi2_test.h.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/error.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"
#include "samplers/sampling.h"

using namespace gradus;

namespace {

// Every chi-square test of this file shares one family-wise false-positive
// rate of 1% (Sidak): kNumChi2Tests counts the chi-square tests below that
// must pass (the two deliberately failing ones in DetectsMismatchedPdf excluded).
constexpr int kNumChi2Tests = 11;
const double kAlpha = chi2::SidakAlpha(0.01, kNumChi2Tests);

chi2::Options Opts(int xBins, int yBins, uint64_t seed) {
    chi2::Options o;
    o.xBins = xBins;
    o.yBins = yBins;
    o.alpha = kAlpha;
    o.seed = seed;
    o.samples = 200000;
    return o;
}

Point2 U2(RNG &rng) {
    Float a = rng.uniform();
    return {a, rng.uniform()};
}

}  // namespace

TEST(Chi2, IncompleteGammaKnownValues) {
    // Chi-square critical values at 5% (tables): dof 1 -> 3.841459, dof 10 -> 18.307038.
    EXPECT_NEAR(chi2::PValue(3.841459, 1), 0.05, 1e-6);
    EXPECT_NEAR(chi2::PValue(18.307038, 10), 0.05, 1e-6);
    EXPECT_NEAR(chi2::PValue(124.342113, 100), 0.05, 1e-6);
    for (double x : {0.01, 0.5, 1.0, 3.0, 10.0, 40.0}) {
        EXPECT_NEAR(chi2::RegularizedGammaP(1, x), 1 - std::exp(-x), 1e-13) << x;
        EXPECT_NEAR(chi2::RegularizedGammaQ(0.5, x), std::erfc(std::sqrt(x)), 1e-13) << x;
        EXPECT_NEAR(chi2::RegularizedGammaP(3.5, x) + chi2::RegularizedGammaQ(3.5, x), 1, 1e-13);
    }
    EXPECT_NEAR(chi2::SidakAlpha(0.01, 1), 0.01, 1e-15);
    EXPECT_LT(chi2::SidakAlpha(0.01, 10), 0.01 / 9.9);
}

TEST(Chi2, PoolsSmallBinsAndFlagsZeroPdfSamples) {
    std::vector<double> obs{100, 98, 2, 0}, exp{100, 100, 0.5, 0.0};
    auto r = chi2::TestCounts(obs, exp, 0.01);
    EXPECT_EQ(r.dof, 1);  // the two small bins pooled into the smaller regular bin
    EXPECT_TRUE(r.pass) << r.message;
    obs = {100, 100, 0, 3};
    r = chi2::TestCounts(obs, exp, 0.01);
    EXPECT_FALSE(r.pass);
    EXPECT_NE(r.message.find("pdf is zero"), std::string::npos) << r.message;
}

// The harness must reject a sampler whose pdf is wrong.
TEST(Chi2, DetectsMismatchedPdf) {
    auto r = chi2::SphericalTest([](RNG &rng, Vec3 *w) { *w = SampleUniformHemisphere(U2(rng)); return true; },
                                 [](const Vec3 &w) { return CosineHemispherePdf(w.z); }, Opts(10, 20, 1));
    EXPECT_FALSE(r.pass) << r.message;
    // A missing 1% of samples (reported invalid) is detected by the invalid bin.
    r = chi2::SphericalTest(
        [](RNG &rng, Vec3 *w) { *w = SampleUniformSphere(U2(rng)); return rng.uniform() > 0.01; },
        [](const Vec3 &) { return UniformSpherePdf(); }, Opts(10, 20, 2));
    EXPECT_FALSE(r.pass) << r.message;
}

TEST(Warp, UniformDiskConcentric) {
    // Disk mapped onto [0,1)^2 by p -> (p + 1) / 2: density 4/pi inside.
    auto r = chi2::PlanarTest(
        [](RNG &rng, Point2 *p) {
            Point2 d = SampleUniformDiskConcentric(U2(rng));
            *p = {(d.x + 1) / 2, (d.y + 1) / 2};
            return true;
        },
        [](Point2 p) { return Sqr(2 * p.x - 1) + Sqr(2 * p.y - 1) < 1 ? 4 * InvPi : 0; }, Opts(16, 16, 3));
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Warp, CosineHemisphere) {
    auto r = chi2::SphericalTest([](RNG &rng, Vec3 *w) { *w = SampleCosineHemisphere(U2(rng)); return true; },
                                 [](const Vec3 &w) { return CosineHemispherePdf(w.z); }, Opts(10, 20, 4));
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Warp, UniformHemisphere) {
    auto r = chi2::SphericalTest([](RNG &rng, Vec3 *w) { *w = SampleUniformHemisphere(U2(rng)); return true; },
                                 [](const Vec3 &w) { return w.z > 0 ? UniformHemispherePdf() : 0; },
                                 Opts(10, 20, 5));
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Warp, UniformSphere) {
    auto r = chi2::SphericalTest([](RNG &rng, Vec3 *w) { *w = SampleUniformSphere(U2(rng)); return true; },
                                 [](const Vec3 &) { return UniformSpherePdf(); }, Opts(10, 20, 6));
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Warp, UniformCone) {
    // 20 cos(theta) bins put bin edges at 0.5 and 0.8, the cone boundaries.
    for (Float cosMax : {0.5, 0.8}) {
        auto r = chi2::SphericalTest(
            [cosMax](RNG &rng, Vec3 *w) { *w = SampleUniformCone(U2(rng), cosMax); return true; },
            [cosMax](const Vec3 &w) { return w.z >= cosMax ? UniformConePdf(cosMax) : 0; },
            Opts(20, 16, cosMax == 0.5 ? 7 : 8));
        EXPECT_TRUE(r.pass) << "cosThetaMax " << cosMax << ": " << r.message;
    }
}

TEST(Warp, UniformTriangle) {
    auto r = chi2::PlanarTest([](RNG &rng, Point2 *b) { *b = SampleUniformTriangle(U2(rng)); return true; },
                              [](Point2 b) { return b.x + b.y <= 1 ? 2.0 : 0.0; }, Opts(16, 16, 9));
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Warp, Exponential) {
    // Bins of width 0.25 / a on [0, 5 / a) plus a tail bin; exact expectations from the cdf.
    const Float a = 2.5;
    const int nb = 20, n = 200000;
    std::vector<double> obs(nb + 1, 0), exp(nb + 1, 0);
    RNG rng(10);
    for (int i = 0; i < n; ++i) {
        Float x = SampleExponential(rng.uniform(), a);
        ASSERT_GE(x, 0);
        obs[std::min(nb, int(x * a / 0.25))] += 1;
    }
    for (int b = 0; b < nb; ++b) exp[b] = n * (std::exp(-0.25 * b) - std::exp(-0.25 * (b + 1)));
    exp[nb] = n * std::exp(-0.25 * nb);
    auto r = chi2::TestCounts(obs, exp, kAlpha);
    EXPECT_TRUE(r.pass) << r.message;
    EXPECT_NEAR(ExponentialPdf(0.3, a), a * std::exp(-a * 0.3), 1e-15);
}

TEST(Warp, InversesRoundTrip) {
    RNG rng(11);
    for (int i = 0; i < 20000; ++i) {
        Point2 u = U2(rng);
        auto near2 = [](Point2 a, Point2 b) { return std::abs(a.x - b.x) < 1e-9 && std::abs(a.y - b.y) < 1e-9; };
        EXPECT_TRUE(near2(InvertUniformDiskConcentric(SampleUniformDiskConcentric(u)), u));
        EXPECT_TRUE(near2(InvertCosineHemisphere(SampleCosineHemisphere(u)), u));
        EXPECT_TRUE(near2(InvertUniformHemisphere(SampleUniformHemisphere(u)), u));
        EXPECT_TRUE(near2(InvertUniformSphere(SampleUniformSphere(u)), u));
        EXPECT_TRUE(near2(InvertUniformCone(SampleUniformCone(u, 0.3), 0.3), u));
        EXPECT_TRUE(near2(InvertUniformTriangle(SampleUniformTriangle(u)), u));
        // Sample(Invert(x)) == x for points of the target domains.
        Vec3 w = SampleUniformSphere(U2(rng));
        EXPECT_LT((SampleUniformSphere(InvertUniformSphere(w)) - w).length(), 1e-9);
        Vec3 h{w.x, w.y, std::abs(w.z)};
        EXPECT_LT((SampleCosineHemisphere(InvertCosineHemisphere(h)) - h).length(), 1e-7);
        Point2 d{w.x, w.y};
        Point2 d2 = SampleUniformDiskConcentric(InvertUniformDiskConcentric(d));
        EXPECT_LT(std::hypot(d2.x - d.x, d2.y - d.y), 1e-9);
        if (HasFailure()) break;
    }
    // Exact corners and the centre.
    EXPECT_EQ(InvertUniformDiskConcentric({0, 0}), Point2(0.5, 0.5));
    Point2 c = InvertUniformDiskConcentric(SampleUniformDiskConcentric({0, 0}));
    EXPECT_NEAR(c.x, 0, 1e-12);
    EXPECT_NEAR(c.y, 0, 1e-12);
}

TEST(Warp, PdfsIntegrateToOne) {
    EXPECT_NEAR(UniformConePdf(0.0), UniformHemispherePdf(), 1e-15);
    EXPECT_NEAR(UniformConePdf(-1.0), UniformSpherePdf(), 1e-15);
    EXPECT_NEAR(CosineHemispherePdf(1), InvPi, 1e-15);
    EXPECT_EQ(CosineHemispherePdf(-0.5), 0);
}

TEST(Mis, Heuristics) {
    EXPECT_DOUBLE_EQ(PowerHeuristic(1, 1, 1, 1), 0.5);
    EXPECT_DOUBLE_EQ(PowerHeuristic(1, 2, 1, 1), 0.8);
    EXPECT_DOUBLE_EQ(PowerHeuristic(1, 1, 2, 1), 0.2);
    EXPECT_DOUBLE_EQ(BalanceHeuristic(1, 3, 1, 1), 0.75);
    EXPECT_EQ(PowerHeuristic(1, Infinity, 1, 5), 1);
    EXPECT_EQ(PowerHeuristic(1, 5, 1, Infinity), 0);
    EXPECT_EQ(BalanceHeuristic(1, Infinity, 1, 5), 1);
    EXPECT_EQ(PowerHeuristic(1, 0, 1, 0), 0);
    EXPECT_EQ(BalanceHeuristic(1, 0, 1, 0), 0);
    // Huge but finite pdfs: f^2 overflows, the weight must not.
    EXPECT_DOUBLE_EQ(PowerHeuristic(1, 1e200, 1, 1e200), 0.5);
    RNG rng(12);
    for (int i = 0; i < 1000; ++i) {
        Float f = std::exp(20 * (rng.uniform() - 0.5)), g = std::exp(20 * (rng.uniform() - 0.5));
        EXPECT_NEAR(PowerHeuristic(1, f, 1, g) + PowerHeuristic(1, g, 1, f), 1, 1e-14);
        EXPECT_NEAR(BalanceHeuristic(2, f, 3, g) + BalanceHeuristic(3, g, 2, f), 1, 1e-14);
        EXPECT_NEAR(PowerHeuristic(1, f, 1, g), f * f / (f * f + g * g), 1e-14);
    }
}

TEST(Distribution1D, ContinuousAndDiscreteChi2) {
    std::vector<Float> f{0.5, 0, 3, 1, 0, 0, 2.25, 7, 0.1, 1};
    Distribution1D d(f);
    double sum = 0;
    for (Float v : f) sum += v;
    EXPECT_NEAR(d.integral(), sum / f.size(), 1e-15);
    EXPECT_EQ(d.count(), 10);
    // Continuous: 4 bins per bucket; expectation is exact for a piecewise-constant pdf.
    const int n = 200000, nb = 40;
    std::vector<double> obs(nb, 0), exp(nb, 0), dobs(f.size(), 0), dexp(f.size(), 0);
    RNG rng(13);
    for (int i = 0; i < n; ++i) {
        Float pdf;
        int off;
        Float x = d.sampleContinuous(rng.uniform(), &pdf, &off);
        ASSERT_TRUE(x >= 0 && x < 1);
        ASSERT_EQ(off, int(x * 10));
        ASSERT_DOUBLE_EQ(pdf, f[off] / d.integral());
        ASSERT_DOUBLE_EQ(pdf, d.pdfContinuous(x));
        obs[int(x * nb)] += 1;
        Float pmf, ur;
        int k = d.sampleDiscrete(rng.uniform(), &pmf, &ur);
        ASSERT_GT(f[k], 0);
        ASSERT_DOUBLE_EQ(pmf, d.discretePmf(k));
        ASSERT_TRUE(ur >= 0 && ur < 1);
        dobs[k] += 1;
    }
    for (int b = 0; b < nb; ++b) exp[b] = n * f[b / 4] / sum / 4;
    for (size_t k = 0; k < f.size(); ++k) dexp[k] = n * d.discretePmf(int(k));
    for (size_t k = 0; k < f.size(); ++k) EXPECT_NEAR(d.discretePmf(int(k)), f[k] / sum, 1e-15);
    auto r = chi2::TestCounts(obs, exp, kAlpha);
    EXPECT_TRUE(r.pass) << r.message;
    r = chi2::TestCounts(dobs, dexp, kAlpha);
    EXPECT_TRUE(r.pass) << r.message;
}

TEST(Distribution1D, EdgeCases) {
    std::vector<Float> neg{1, -0.5, 2};
    EXPECT_THROW(Distribution1D{neg}, Error);
    std::vector<Float> nan{1, std::nan(""), 2};
    EXPECT_THROW(Distribution1D{nan}, Error);
    std::vector<Float> zero(4, 0.0);
    Distribution1D z(zero);
    Float pdf;
    Float x = z.sampleContinuous(0.6, &pdf);
    EXPECT_DOUBLE_EQ(x, 0.6);
    EXPECT_EQ(pdf, 1);
    EXPECT_EQ(z.discretePmf(3), 0.25);
    EXPECT_EQ(z.sampleDiscrete(0.6), 2);
    // u just below 1 stays in range and never picks a zero bucket at the end.
    std::vector<Float> f{1, 1, 0};
    Distribution1D d(f);
    EXPECT_EQ(d.sampleDiscrete(OneMinusEpsilon), 1);
    EXPECT_LT(d.sampleContinuous(OneMinusEpsilon, &pdf), 2.0 / 3);
    // The remapped u of a discrete sample is the position within its bucket.
    Float ur;
    EXPECT_EQ(d.sampleDiscrete(0.75, nullptr, &ur), 1);
    EXPECT_NEAR(ur, 0.5, 1e-15);
}

namespace {
// Reference inversion of a piecewise-constant row, written out with a linear
// scan (the distributions search a guide table and a short binary search):
// the same normalised cdf, the bucket o with cdf[o] <= u < cdf[o+1], x = (o + du) / n.
struct RefRow {
    std::vector<double> cdf, pdf;
    explicit RefRow(const std::vector<Float> &f) {
        int n = int(f.size());
        cdf.assign(n + 1, 0);
        for (int i = 0; i < n; ++i) cdf[i + 1] = cdf[i] + f[i] / n;
        double I = cdf[n];
        for (int i = 1; i <= n; ++i) cdf[i] = I == 0 ? double(i) / n : cdf[i] / I;
        cdf[n] = 1;
        for (int i = 0; i < n; ++i) pdf.push_back(I > 0 ? f[i] / I : 1);
    }
    double sample(double u, double *p, int *bucket) const {
        int n = int(pdf.size()), o = 0;
        for (int i = 0; i < n; ++i)
            if (cdf[i] <= u) o = i;
        *bucket = o;
        *p = pdf[o];
        double w = cdf[o + 1] - cdf[o], du = w > 0 ? (u - cdf[o]) / w : 0;
        double x = (o + du) / n, end = double(o + 1) / n;
        return x < end ? x : std::nextafter(end, 0.0);
    }
};

// Rows like an environment map's: long runs of zeros, a narrow spike, noise.
std::vector<Float> SpikyRow(RNG &rng, int n) {
    std::vector<Float> f(n);
    int spike = int(rng.uniform() * n);
    for (int i = 0; i < n; ++i) {
        double r = rng.uniform();
        f[i] = r < 0.3 ? 0 : r * 0.01;
        if (std::abs(i - spike) < 3) f[i] = 5000 * rng.uniform();
    }
    for (int i = n / 3; i < n / 3 + n / 10; ++i) f[i] = 0;
    return f;
}
}  // namespace

// The guided search returns exactly the reference's bucket, x and pdf, at
// random u and at every cdf value and its neighbours (the bucket edges).
TEST(Distribution1D, GuidedSearchMatchesLinearScan) {
    RNG rng(21);
    for (int n : {1, 2, 3, 5, 7, 64, 1000, 1337}) {
        std::vector<Float> f = SpikyRow(rng, n);
        if (n == 7) f.assign(7, 0.0);  // all zero: uniform
        Distribution1D d(f);
        RefRow ref(f);
        std::vector<double> us;
        for (int i = 0; i < 2000; ++i) us.push_back(rng.uniform());
        for (double c : ref.cdf)
            for (double u : {std::nextafter(c, 0.0), c, std::nextafter(c, 1.0)})
                if (u >= 0 && u < 1) us.push_back(u);
        for (double u : us) {
            double pr, p;
            int br, b;
            double xr = ref.sample(u, &pr, &br);
            double x = d.sampleContinuous(u, &p, &b);
            ASSERT_EQ(b, br) << "n " << n << " u " << u;
            ASSERT_EQ(x, xr);
            ASSERT_EQ(p, pr);
            ASSERT_EQ(d.sampleDiscrete(u), br);
        }
    }
}

TEST(Distribution2D, GuidedSearchMatchesLinearScan) {
    RNG rng(22);
    const int nu = 300, nv = 40;
    std::vector<Float> f;
    std::vector<RefRow> rows;
    std::vector<Float> rowInt;
    for (int v = 0; v < nv; ++v) {
        std::vector<Float> r = SpikyRow(rng, nu);
        if (v == 5) r.assign(nu, 0.0);
        rows.emplace_back(r);
        double s = 0;
        for (int i = 0; i < nu; ++i) s += r[i] / nu;  // the row integral, as the marginal sums it
        rowInt.push_back(s);
        f.insert(f.end(), r.begin(), r.end());
    }
    RefRow marg(rowInt);
    Distribution2D d(f.data(), nu, nv);
    for (int i = 0; i < 20000; ++i) {
        Point2 u = U2(rng);
        double pv, pu, p;
        int v, b;
        double y = marg.sample(u.y, &pv, &v);
        double x = rows[v].sample(u.x, &pu, &b);
        Point2 s = d.sampleContinuous(u, &p);
        ASSERT_EQ(s.x, x);
        ASSERT_EQ(s.y, y);
        ASSERT_EQ(p, pu * pv);
        ASSERT_EQ(d.pdf(s), pu * pv);
    }
}

TEST(Distribution2D, Chi2AndPdf) {
    const int nu = 7, nv = 5;
    std::vector<Float> f(nu * nv);
    RNG rng(14);
    for (auto &v : f) v = rng.uniform() < 0.15 ? 0 : rng.uniform() * 4;
    for (int u = 0; u < nu; ++u) f[2 * nu + u] = 0;  // an all-zero row
    double sum = 0;
    for (Float v : f) sum += v;
    Distribution2D d(f.data(), nu, nv);
    EXPECT_NEAR(d.integral(), sum / (nu * nv), 1e-14);
    // The pdf is the function normalised over [0,1)^2.
    for (int v = 0; v < nv; ++v)
        for (int u = 0; u < nu; ++u)
            EXPECT_NEAR(d.pdf({(u + 0.5) / nu, (v + 0.5) / nv}), f[v * nu + u] / (sum / (nu * nv)), 1e-12);
    // Sampling follows that pdf, and reports it (bins aligned: 2 per cell).
    auto r = chi2::PlanarTest(
        [&](RNG &g, Point2 *p) {
            Float pdf;
            *p = d.sampleContinuous(U2(g), &pdf);
            return pdf > 0 && std::abs(pdf - d.pdf(*p)) < 1e-12 * pdf;
        },
        [&](Point2 p) { return d.pdf(p); }, Opts(2 * nu, 2 * nv, 15));
    EXPECT_TRUE(r.pass) << r.message;
    EXPECT_EQ(r.invalid, 0);
    EXPECT_EQ(d.pdf({1.0, 0.5}), 0);
}
