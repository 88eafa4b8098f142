// Screened-Poisson reconstruction: exactness, linearity/unbiasedness, limits,
// robustness of L1, agreement of the solvers, odd shapes and input errors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include <tbb/global_control.h>

#include "core/error.h"
#include "recon_test_util.h"
#include "reconstruction/reconstruction.h"

using namespace gradus;
using namespace gradus::testutil;

namespace {

std::vector<ReconstructionOptions> AllSolvers() {
    ReconstructionOptions l1ref = ReconstructionOptions::L1Reference();
    return {ReconstructionOptions::L2Exact(), ReconstructionOptions::L2CG(),
            ReconstructionOptions::L1Default(), l1ref};
}

// Exact primal + exact gradients must return the image (1e-5 relative to its range).
void ExpectExact(int W, int H, const std::vector<float> &img, const ReconstructionOptions &opt) {
    GradientImages g = ExactInputs(img, W, H);
    ReconstructionResult r = Reconstruct(g, opt);
    ASSERT_EQ(r.width, W);
    ASSERT_EQ(r.height, H);
    double scale = std::max(1e-6, MaxAbs(img));
    EXPECT_LE(MaxAbsDiff(r.image, img), 1e-5 * scale)
        << r.stats.method << " on " << W << "x" << H;
}

}  // namespace

TEST(Reconstruction, ExactInputsReturnTheImage) {
    for (const auto &opt : AllSolvers()) ExpectExact(64, 48, SceneImage(64, 48), opt);
}

TEST(Reconstruction, ExactInputsWeighted) {
    const int W = 40, H = 30;
    std::vector<float> img = SceneImage(W, H);
    GradientImages g = ExactInputs(img, W, H);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.01f, 1.f);
    for (auto *v : {&g.primalVar, &g.dxVar, &g.dyVar}) {
        v->resize(img.size());
        for (float &x : *v) x = u(rng);
    }
    ReconstructionResult r = Reconstruct(g, ReconstructionOptions::Weighted());
    EXPECT_LE(MaxAbsDiff(r.image, img), 1e-5 * MaxAbs(img));
}

TEST(Reconstruction, ConstantRampAndOddShapes) {
    struct Size { int W, H; };
    for (Size s : {Size{1, 1}, Size{1, 17}, Size{23, 1}, Size{37, 23}, Size{2, 2}, Size{64, 3}}) {
        std::vector<float> constant(size_t(s.W) * s.H * 3, 0.75f), ramp(constant.size());
        for (int y = 0; y < s.H; ++y)
            for (int x = 0; x < s.W; ++x)
                for (int c = 0; c < 3; ++c) ramp[(size_t(y) * s.W + x) * 3 + c] = 0.1f * x - 0.05f * y + c;
        for (const auto &opt : AllSolvers()) {
            ExpectExact(s.W, s.H, constant, opt);
            ExpectExact(s.W, s.H, ramp, opt);
            ExpectExact(s.W, s.H, SceneImage(s.W, s.H), opt);
        }
    }
}

// Only the differences matter in 1xN / Nx1: a noisy 1-D problem must still
// agree between the DCT and CG solvers (checks the boundary treatment).
TEST(Reconstruction, ExactAndCGAgree) {
    struct Size { int W, H; };
    for (Size s : {Size{96, 64}, Size{1, 50}, Size{50, 1}, Size{31, 17}}) {
        GradientImages g = ExactInputs(SceneImage(s.W, s.H), s.W, s.H);
        AddNoise(g, 0.2, 0.05, 11);
        for (double alpha : {0.05, 0.2, 1.0})
            for (Preconditioner pc : {Preconditioner::Multigrid, Preconditioner::Jacobi}) {
                ReconstructionResult a = Reconstruct(g, ReconstructionOptions::L2Exact(alpha));
                ReconstructionOptions cg = ReconstructionOptions::L2CG(alpha);
                cg.preconditioner = pc;
                ReconstructionResult b = Reconstruct(g, cg);
                EXPECT_LE(MaxAbsDiff(a.image, b.image), 2e-4 * MaxAbs(a.image))
                    << s.W << "x" << s.H << " alpha " << alpha << " " << b.stats.method << " its "
                    << b.stats.cgIterations;
                EXPECT_LE(b.stats.finalRelativeResidual, 1e-6);
                // Both minimise the same objective; the exact one is not worse.
                EXPECT_LE(a.stats.objective, b.stats.objective * (1 + 1e-4));
            }
    }
}

// The exact solution satisfies the normal equations: perturbing it in any
// direction cannot lower the L2 objective.
TEST(Reconstruction, L2ExactIsAMinimum) {
    const int W = 30, H = 20;
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    AddNoise(g, 0.3, 0.1, 5);
    ReconstructionResult r = Reconstruct(g, ReconstructionOptions::L2Exact());
    auto objective = [&](const std::vector<float> &x) {
        const double a2 = 0.04;
        double e = 0;
        for (int y = 0; y < H; ++y)
            for (int xi = 0; xi < W; ++xi)
                for (int c = 0; c < 3; ++c) {
                    size_t i = (size_t(y) * W + xi) * 3 + c;
                    e += a2 * std::pow(double(x[i]) - g.primal[i], 2);
                    if (xi + 1 < W) e += std::pow(double(x[i + 3]) - x[i] - g.dx[i], 2);
                    if (y + 1 < H) e += std::pow(double(x[i + 3 * W]) - x[i] - g.dy[i], 2);
                }
        return e;
    };
    const double e0 = objective(r.image);
    EXPECT_NEAR(e0, r.stats.objective, 1e-6 * e0);
    std::mt19937 rng(3);
    std::normal_distribution<float> n(0.f, 1.f);
    for (int t = 0; t < 5; ++t) {
        std::vector<float> x = r.image;
        for (float &v : x) v += 1e-2f * n(rng);
        EXPECT_GT(objective(x), e0);
    }
}

TEST(Reconstruction, L2IsLinear) {
    const int W = 33, H = 21;
    GradientImages u = ExactInputs(SceneImage(W, H), W, H), v = u;
    AddNoise(u, 0.5, 0.2, 1);
    AddNoise(v, 0.5, 0.2, 2);
    GradientImages w = u;
    const float a = 0.7f, b = -1.3f;
    for (size_t i = 0; i < u.primal.size(); ++i) {
        w.primal[i] = a * u.primal[i] + b * v.primal[i];
        w.dx[i] = a * u.dx[i] + b * v.dx[i];
        w.dy[i] = a * u.dy[i] + b * v.dy[i];
    }
    for (auto opt : {ReconstructionOptions::L2Exact(), ReconstructionOptions::L2CG()}) {
        auto su = Reconstruct(u, opt).image, sv = Reconstruct(v, opt).image, sw = Reconstruct(w, opt).image;
        std::vector<float> comb(su.size());
        for (size_t i = 0; i < su.size(); ++i) comb[i] = a * su[i] + b * sv[i];
        EXPECT_LE(MaxAbsDiff(sw, comb), 1e-4 * MaxAbs(sw));
    }
}

// Unbiasedness (G-MLT Sec. 6 claim): the mean of M reconstructions of
// independent zero-mean noisy inputs equals the truth. Two-sided z-test at
// |z| < 4 for 6 pixels x 3 channels: false-positive rate < 18 * 6.4e-5 = 1.2e-3.
// The same test must reject a deliberately biased input (power check).
namespace {
struct ZTestResult { double maxAbsZ; };
ZTestResult RunZTest(double gradientBias) {
    const int W = 16, H = 12, M = 400;
    std::vector<float> truth = SceneImage(W, H);
    const int pixels[6][2] = {{0, 0}, {15, 11}, {7, 5}, {3, 9}, {12, 2}, {9, 4}};
    double sum[6][3] = {}, sum2[6][3] = {};
    for (int m = 0; m < M; ++m) {
        GradientImages g = ExactInputs(truth, W, H);
        // Heavy-tailed (firefly) noise, zero mean.
        AddNoise(g, 0.3, 0.1, 1000 + m, 0.02, 5.0);
        for (float &v : g.dx) v += float(gradientBias);
        ReconstructionResult r = Reconstruct(g, ReconstructionOptions::L2Exact());
        for (int k = 0; k < 6; ++k)
            for (int c = 0; c < 3; ++c) {
                double e = r.at(pixels[k][0], pixels[k][1], c) -
                           truth[(size_t(pixels[k][1]) * W + pixels[k][0]) * 3 + c];
                sum[k][c] += e;
                sum2[k][c] += e * e;
            }
    }
    double maxZ = 0;
    for (int k = 0; k < 6; ++k)
        for (int c = 0; c < 3; ++c) {
            double mean = sum[k][c] / M, var = (sum2[k][c] - M * mean * mean) / (M - 1);
            maxZ = std::max(maxZ, std::fabs(mean) / std::sqrt(var / M));
        }
    return {maxZ};
}
}  // namespace

TEST(Reconstruction, L2IsUnbiasedZTest) {
    ZTestResult unbiased = RunZTest(0.0);
    EXPECT_LT(unbiased.maxAbsZ, 4.0);
    // A bias of 0.05 in every dx (a systematic error) must be detected.
    ZTestResult biased = RunZTest(0.05);
    EXPECT_GT(biased.maxAbsZ, 4.0);
}

TEST(Reconstruction, AlphaInfinityReturnsPrimal) {
    const int W = 40, H = 30;
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    AddNoise(g, 0.3, 0.3, 9);
    for (auto base : {ReconstructionOptions::L2Exact(), ReconstructionOptions::L2CG(),
                      ReconstructionOptions::L1Default()}) {
        base.alpha = std::numeric_limits<double>::infinity();
        EXPECT_EQ(MaxAbsDiff(Reconstruct(g, base).image, g.primal), 0.0);
    }
    // Convergence to the primal as alpha grows: the distance falls like 1/alpha^2.
    double prev = 0;
    for (double alpha : {10.0, 100.0, 1000.0}) {
        double d = MaxAbsDiff(Reconstruct(g, ReconstructionOptions::L2Exact(alpha)).image, g.primal);
        if (prev > 0) {
            EXPECT_LT(d, prev / 50);
        }
        prev = d;
    }
    EXPECT_LT(prev, 1e-5);
    // alpha = 0 keeps the primal's mean.
    ReconstructionResult r0 = Reconstruct(g, ReconstructionOptions::L2Exact(0.0));
    double m0 = 0, mp = 0;
    for (size_t i = 0; i < g.primal.size(); ++i) m0 += r0.image[i], mp += g.primal[i];
    EXPECT_NEAR(m0, mp, 1e-4 * std::fabs(mp));
}

// G-MLT Fig. 7: L1 resists an outlier gradient that L2 spreads over an area.
TEST(Reconstruction, L1ResistsGradientOutlier) {
    const int W = 64, H = 64;
    std::vector<float> truth = SceneImage(W, H);
    GradientImages g = ExactInputs(truth, W, H);
    const size_t at = (size_t(32) * W + 20) * 3;
    for (int c = 0; c < 3; ++c) g.dx[at + c] += 10.f;  // one corrupted edge
    auto stats = [&](const ReconstructionResult &r, double *sumErr, int *spread) {
        *sumErr = 0;
        *spread = 0;
        for (size_t p = 0; p < size_t(W) * H; ++p) {
            double e = 0;
            for (int c = 0; c < 3; ++c) e = std::max(e, double(std::fabs(r.image[p * 3 + c] - truth[p * 3 + c])));
            *sumErr += e;
            if (e > 1e-2) ++*spread;
        }
    };
    double e2, e1;
    int s2, s1;
    stats(Reconstruct(g, ReconstructionOptions::L2Exact()), &e2, &s2);
    stats(Reconstruct(g, ReconstructionOptions::L1Default()), &e1, &s1);
    RecordProperty("l2_total_error", std::to_string(e2));
    RecordProperty("l1_total_error", std::to_string(e1));
    std::printf("outlier: L2 total error %.4f over %d pixels > 1e-2; L1 %.4f over %d pixels\n", e2, s2,
                e1, s1);
    EXPECT_GT(s2, 50);       // L2 spreads the outlier
    EXPECT_LE(s1, 2);        // L1 confines it to (at most) the two pixels of the edge
    EXPECT_LT(e1, 0.05 * e2);
}

// Our default L1 preset must be at least as accurate (lower L1 objective) as
// the reference implementation's default schedule (20 IRLS x 50 plain CG from
// the primal), on noisy render-like inputs.
class L1VersusReference : public ::testing::TestWithParam<int> {};

TEST_P(L1VersusReference, DefaultAtLeastAsAccurate) {
    const int W = 160, H = 120;
    std::vector<float> truth = SceneImage(W, H);
    GradientImages g = ExactInputs(truth, W, H);
    // Two noise regimes: noisy primal with frequent fireflies, and noisy
    // gradients with rare strong fireflies.
    if (GetParam() == 0) AddNoise(g, 0.3, 0.05, 21, 0.01, 8.0);
    else AddNoise(g, 0.1, 0.1, 5, 0.002, 30.0);
    ReconstructionResult d = Reconstruct(g, ReconstructionOptions::L1Default());
    ReconstructionResult ref = Reconstruct(g, ReconstructionOptions::L1Reference());
    ReconstructionResult l2 = Reconstruct(g, ReconstructionOptions::L2Exact());
    std::printf("L1 objective: default %.3f (%d CG its), reference schedule %.3f (%d CG its), L2 %.3f\n",
                d.stats.objective, d.stats.cgIterations, ref.stats.objective, ref.stats.cgIterations,
                0.2 * l2.stats.primalL1 + l2.stats.gradientL1);
    EXPECT_LE(d.stats.objective, ref.stats.objective);
    // And L1 lowers the L1 objective relative to the L2 solution.
    EXPECT_LT(d.stats.objective, 0.2 * l2.stats.primalL1 + l2.stats.gradientL1);
}
INSTANTIATE_TEST_SUITE_P(Reconstruction, L1VersusReference, ::testing::Values(0, 1));

// Weighted with constant variances is L2 with alpha^2 = v_gradient / v_primal.
TEST(Reconstruction, WeightedWithConstantVariancesIsL2) {
    const int W = 48, H = 32;
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    AddNoise(g, 0.4, 0.1, 4);
    const float vp = 0.16f, vg = 0.01f;
    g.primalVar.assign(g.primal.size(), vp);
    g.dxVar.assign(g.primal.size(), vg);
    g.dyVar.assign(g.primal.size(), vg);
    ReconstructionResult w = Reconstruct(g, ReconstructionOptions::Weighted());
    ReconstructionResult l2 = Reconstruct(g, ReconstructionOptions::L2Exact(std::sqrt(vg / vp)));
    EXPECT_LE(MaxAbsDiff(w.image, l2.image), 1e-4 * MaxAbs(l2.image)) << w.stats.cgIterations;
}

// With spatially varying noise, inverse-variance weights beat plain L2.
TEST(Reconstruction, WeightedBeatsL2WithVaryingNoise) {
    const int W = 64, H = 48;
    std::vector<float> truth = SceneImage(W, H);
    GradientImages g = ExactInputs(truth, W, H);
    std::mt19937 rng(17);
    std::normal_distribution<double> n(0, 1);
    g.primalVar.resize(truth.size());
    g.dxVar.resize(truth.size());
    g.dyVar.resize(truth.size());
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) {
                size_t i = (size_t(y) * W + x) * 3 + c;
                double sp = x < W / 2 ? 1.0 : 0.05, sg = 0.1;
                g.primal[i] += float(sp * n(rng));
                g.dx[i] += float(sg * n(rng));
                g.dy[i] += float(sg * n(rng));
                g.primalVar[i] = float(sp * sp);
                g.dxVar[i] = g.dyVar[i] = float(sg * sg);
            }
    double mseW = Mse(Reconstruct(g, ReconstructionOptions::Weighted()).image, truth);
    double mse2 = Mse(Reconstruct(g, ReconstructionOptions::L2Exact()).image, truth);
    std::printf("varying noise: MSE weighted %.5f, L2(alpha=0.2) %.5f\n", mseW, mse2);
    EXPECT_LT(mseW, 0.8 * mse2);
}

TEST(Reconstruction, IndependentOfThreadCount) {
    const int W = 80, H = 60;
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    AddNoise(g, 0.3, 0.05, 8, 0.01, 5.0);
    std::vector<float> one, two;
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
        one = Reconstruct(g, ReconstructionOptions::L1Default()).image;
    }
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
        two = Reconstruct(g, ReconstructionOptions::L1Default()).image;
    }
    EXPECT_EQ(one, two);
}

TEST(Reconstruction, RejectsBadInput) {
    const int W = 8, H = 6;
    GradientImages good = ExactInputs(SceneImage(W, H), W, H);
    auto expectError = [&](const GradientImages &g, const ReconstructionOptions &o, const char *what) {
        try {
            Reconstruct(g, o);
            ADD_FAILURE() << "no error, expected one mentioning '" << what << "'";
        } catch (const Error &e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    GradientImages nan = good;
    nan.dx[(size_t(2) * W + 3) * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
    expectError(nan, ReconstructionOptions::L2Exact(), "layer 'dx' has a NaN value at pixel (3, 2), channel 1");
    GradientImages inf = good;
    inf.primal[0] = std::numeric_limits<float>::infinity();
    expectError(inf, ReconstructionOptions::L1Default(), "'primal' has an infinite value");
    // NaN in the unused last column of dx is ignored (no gradient there).
    GradientImages unused = good;
    unused.dx[(size_t(1) * W + W - 1) * 3] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NO_THROW(Reconstruct(unused, ReconstructionOptions::L2Exact()));
    GradientImages small = good;
    small.dy.pop_back();
    expectError(small, ReconstructionOptions::L2Exact(), "layer 'dy' has");
    GradientImages empty;
    expectError(empty, ReconstructionOptions::L2Exact(), "empty");
    ReconstructionOptions neg = ReconstructionOptions::L2Exact(-1.0);
    expectError(good, neg, "alpha must be >= 0");
    expectError(good, ReconstructionOptions::Weighted(), "variance layers");
    GradientImages negVar = good;
    negVar.primalVar.assign(good.primal.size(), 1.f);
    negVar.dxVar = negVar.dyVar = negVar.primalVar;
    negVar.dyVar[5] = -1.f;
    expectError(negVar, ReconstructionOptions::Weighted(), "'dy_var' has a negative value");
    EXPECT_THROW(ParseReconstructionNorm("l3"), Error);
    EXPECT_EQ(ParseReconstructionNorm("weighted"), ReconstructionNorm::Weighted);
}

// Inputs near the float limit (a 1e40 emitter after the film's output clamp)
// are solved in a power-of-two scaled range: no overflow, and for L2 the exact
// scaled solution (the scaling by 2^k is exact in floating point). L1 applies
// its IRLS regularisation in the normalised range, so it is compared with the
// unscaled solve of the same normalised input.
TEST(Reconstruction, HugeInputsScaleExactly) {
    const int W = 24, H = 18;
    GradientImages g = testutil::ExactInputs(testutil::SceneImage(W, H), W, H);
    testutil::AddNoise(g, 0.05, 0.05, 7);
    float maxAbs = 0;
    for (auto *v : {&g.primal, &g.dx, &g.dy})
        for (float f : *v) maxAbs = std::max(maxAbs, std::abs(f));
    const int norm = std::ilogb(maxAbs) + 1;  // g * 2^-norm is the solvers' normalised input
    auto scaled = [&](int e) {
        GradientImages s = g;
        for (auto *v : {&s.primal, &s.dx, &s.dy})
            for (float &f : *v) f = std::ldexp(f, e);
        return s;
    };
    GradientImages big = scaled(120);  // max ~ 3e36
    for (ReconstructionOptions o : {ReconstructionOptions::L2Exact(), ReconstructionOptions::L1Default()}) {
        const bool l2 = o.norm == ReconstructionNorm::L2;
        ReconstructionResult a = Reconstruct(l2 ? g : scaled(-norm), o), b = Reconstruct(big, o);
        const int e = l2 ? 120 : 120 + norm;
        ASSERT_EQ(a.image.size(), b.image.size());
        double worst = 0;
        for (size_t i = 0; i < a.image.size(); ++i) {
            ASSERT_TRUE(std::isfinite(b.image[i])) << i;
            double ref = std::ldexp(double(a.image[i]), e);
            worst = std::max(worst, std::abs(b.image[i] - ref) / (std::abs(ref) + std::ldexp(1e-3, 120)));
        }
        EXPECT_LT(worst, 1e-5) << a.stats.method;
    }
}
