// MLT renders: pbrt-v3 scenes unchanged, the normalisation b / (mutations per
// pixel) for any pass structure, and the pbrt bugs as regression tests (a
// bootstrap without light, 0/0 in acceptance and splats).
#include <csignal>
#include <thread>

#include "conformance/conformance_util.h"
#include "mlt_test_util.h"
#include "render/render_loop.h"

namespace gradus::mlt_test {
namespace {

const std::string kSmall = "\"integer maxdepth\" [3] \"integer bootstrapsamples\" [4000] \"integer chains\" [64]";

bool AllFinite(const Image &img) {
    for (float v : img.data())
        if (!std::isfinite(v)) return false;
    return true;
}

// A pbrt-v3 scene with Integrator "mlt" and its parameters renders with them:
// mutationsperpixel is the render's spp (not the Sampler's 16, nor rounded by
// a stratified sampler), every parameter is consumed.
TEST(MLTRender, PbrtV3SceneRendersWithItsParameters) {
    const std::string line = MLTLine(
        "\"integer maxdepth\" [4] \"integer bootstrapsamples\" [3000] \"integer chains\" [50] "
        "\"integer mutationsperpixel\" [6] \"float largestepprobability\" [0.25] \"float sigma\" [0.02]");
    Rendered r = Render(BoxScene(line, 12, "open", "Sampler \"lowdiscrepancy\" \"integer pixelsamples\" [16]"), 0, 5);
    const MLTSettings &s = r.mlt().settings();
    EXPECT_EQ(s.maxDepth, 4);
    EXPECT_EQ(s.bootstrapSamples, 3000);
    EXPECT_EQ(s.chains, 50);
    EXPECT_EQ(s.largeStepProbability, 0.25);
    EXPECT_EQ(s.sigma, 0.02);
    EXPECT_EQ(r.stats.spp, 6);
    EXPECT_EQ(r.mlt().counts().mutations, 6 * 144);
    EXPECT_EQ(r.image.metadata["mlt_mutations"].str(), "864");
    EXPECT_GT(MeanLum(r.image), 0);
    // --spp overrides mutationsperpixel.
    Rendered o = Render(BoxScene(line), 3, 5);
    EXPECT_EQ(o.stats.spp, 3);
    EXPECT_EQ(o.mlt().counts().mutations, 3 * 144);
}

TEST(MLTRender, StatisticsReportAcceptanceChainsBAndMutations) {
    Rendered r = Render(BoxScene(MLTLine(kSmall)), 4, 1);
    const auto c = r.mlt().counts();
    EXPECT_EQ(c.mutations, 4 * 144);
    EXPECT_EQ(c.small + c.large, c.mutations);
    EXPECT_GT(c.smallAccepted, 0);
    EXPECT_GT(c.largeAccepted, 0);
    EXPECT_EQ(c.startMismatch, 0) << "a chain start must re-create its bootstrap state exactly";
    for (const char *want : {"acceptance: small steps ", "large steps ", "chains: 64", "b = ", "mutations: 576"})
        EXPECT_NE(r.statistics.find(want), std::string::npos) << want << " in\n" << r.statistics;
}

// The image's mean luminance is b exactly (every splat carries luminance
// b * weight, the weights of a mutation sum to 1, all land on the film), for
// any split into passes, a time budget, and an interrupted pass (the skipped
// chains are compensated). A normalisation by the wrong mutation count fails.
TEST(MLTRender, NormalisationIsBOverMutationsPerPixelForAnyPassStructure) {
    const std::string scene = BoxScene(MLTLine(kSmall));
    for (int perPass : {1, 3, 7}) {
        Rendered r = Render(scene, 7, 11, 2, perPass);
        EXPECT_EQ(r.stats.spp, 7);
        EXPECT_NEAR(MeanLum(r.image) / r.mlt().b(), 1, 1e-5) << perPass << " spp per pass";
    }
    Rendered t = Render(scene, 0, 11, 2, 1, 0.3);
    EXPECT_TRUE(t.stats.timeLimited);
    EXPECT_GT(t.stats.spp, 1);
    EXPECT_NEAR(MeanLum(t.image) / t.mlt().b(), 1, 1e-5) << "time budget, " << t.stats.spp << " spp";

    // Interrupted while passes run (large passes: 400 mutations per pixel each).
    InstallInterruptHandler();
    ResetInterrupt();
    std::thread stopper([] {
        std::this_thread::sleep_for(std::chrono::milliseconds(400));
        std::raise(SIGINT);
    });
    Rendered i = Render(BoxScene(MLTLine(kSmall), 24), 1 << 20, 11, 2, 400);
    stopper.join();
    ResetInterrupt();
    EXPECT_TRUE(i.stats.interrupted);
    EXPECT_GT(i.mlt().counts().mutations, 0);
    EXPECT_NEAR(MeanLum(i.image) / i.mlt().b(), 1, 1e-5) << "interrupted after " << i.stats.passes << " passes";
}

TEST(MLTRender, ThreadCountIndependent) {
    const std::string scene = BoxScene(MLTLine(kSmall));
    Rendered a = Render(scene, 3, 2, 1), b = Render(scene, 3, 2, 3);
    EXPECT_EQ(a.image.data(), b.image.data());
}

// pbrt-v4 #77: a bootstrap that finds no light-carrying path crashed. Here: a
// black image, a message naming the cause, no chain, nothing non-finite.
TEST(MLTRender, BootstrapWithoutLightGivesBlackImageAndMessage) {
    for (const char *light : {"", "sealed"}) {
        SCOPED_TRACE(std::string("light: ") + light);
        Rendered r = Render(BoxScene(MLTLine(kSmall), 12, light), 2, 3);
        EXPECT_EQ(r.mlt().b(), 0);
        for (float v : r.image.data()) ASSERT_EQ(v, 0);
        EXPECT_NE(r.mlt().warning().find("bootstrap"), std::string::npos) << r.mlt().warning();
        EXPECT_NE(r.mlt().warning().find("b = 0"), std::string::npos) << r.mlt().warning();
        EXPECT_NE(r.statistics.find(r.mlt().warning()), std::string::npos) << r.statistics;
        EXPECT_EQ(r.image.metadata["mlt_warning"].str(), r.mlt().warning());
        EXPECT_EQ(r.mlt().counts().mutations, 0);
        EXPECT_EQ(r.stats.nonFinite, 0u);
        EXPECT_EQ(r.statistics.find("nan"), std::string::npos) << r.statistics;
    }
}

// pbrt-v4 #476, #134: 0/0 in the acceptance or the splat weights when a
// proposal (or the state) has zero luminance. Most proposals of a scene lit
// through a 2 cm gap carry nothing; none may produce a NaN, lose its
// weight (the mean would drop below b) or print "nan" statistics; without
// large steps the large-step rate is "-", not 0/0.
TEST(MLTRender, ZeroContributionProposalsGiveNoZeroOverZero) {
    for (const char *p : {"\"float largestepprobability\" [0.3]", "\"float largestepprobability\" [0]",
                          "\"float largestepprobability\" [1]"}) {
        SCOPED_TRACE(p);
        Rendered r = Render(BoxScene(MLTLine(kSmall + " " + p), 12, "up"), 4, 8);
        const auto c = r.mlt().counts();
        EXPECT_GT(c.zeroProposals, c.mutations / 3);
        EXPECT_EQ(c.nonFinite, 0);
        EXPECT_EQ(r.stats.nonFinite, 0u);
        EXPECT_TRUE(AllFinite(r.image));
        EXPECT_NEAR(MeanLum(r.image) / r.mlt().b(), 1, 1e-5);
        EXPECT_EQ(r.statistics.find("nan"), std::string::npos) << r.statistics;
        EXPECT_EQ(r.statistics.find("inf"), std::string::npos) << r.statistics;
    }
    Rendered r = Render(BoxScene(MLTLine(kSmall + " \"float largestepprobability\" [0]")), 2, 8);
    EXPECT_NE(r.statistics.find("large steps - of 0"), std::string::npos) << r.statistics;
}

// bootstrapvertices: N_d per depth as mlt.h states, and chains start at depth
// d with probability W_d / sum W, W_d = (1 / N_d) sum_k I_dk, an unbiased
// estimate of depth d's integral whatever N_d is. Each depth's share of the
// chains, averaged over K seeds, must equal the share under a bootstrap of
// equal N_d (Welch t per depth, alpha 1e-4 split over the 4 depths). The
// power check is a start drawn in proportion to I_dk alone (without 1 / N_d):
// N_d = 500, 333, 250, 200 shifts depth 1's share by ~0.08 (t ~ 10 here).
TEST(MLTRender, CappedBootstrapKeepsEachDepthsShareOfChains) {
    const std::string capped = MLTLine(
        "\"integer maxdepth\" [3] \"integer chains\" [200] \"integer bootstrapsamples\" [5000] "
        "\"integer bootstrapvertices\" [4000]");
    const std::string equal =
        MLTLine("\"integer maxdepth\" [3] \"integer chains\" [200] \"integer bootstrapsamples\" [1000]");
    Rendered one = Render(BoxScene(capped), 1, 1);
    EXPECT_EQ(one.mlt().bootstrapStatesPerDepth(), (std::vector<int64_t>{500, 333, 250, 200}));
    EXPECT_NE(one.statistics.find("bootstrapvertices 4000 gives 500 at depth 0 down to 200 at depth 3"),
              std::string::npos)
        << one.statistics;
    const std::vector<int64_t> N = one.mlt().bootstrapStatesPerDepth();
    const int K = 60;
    std::vector<std::vector<double>> shareC(4), shareE(4), shareWrong(4);
    for (int k = 0; k < K; ++k) {
        Rendered c = Render(BoxScene(capped), 1, uint64_t(100 + k));
        Rendered e = Render(BoxScene(equal), 1, uint64_t(5000 + k));
        const std::vector<int64_t> nc = c.mlt().chainsPerDepth(), ne = e.mlt().chainsPerDepth();
        ASSERT_EQ(nc.size(), 4u);
        // The power check's wrong estimator: depth shares reweighted by N_d.
        double wrongSum = 0;
        std::vector<double> wrong(4);
        for (int d = 0; d < 4; ++d) wrongSum += wrong[size_t(d)] = double(nc[size_t(d)]) * double(N[size_t(d)]);
        for (int d = 0; d < 4; ++d) {
            shareC[size_t(d)].push_back(double(nc[size_t(d)]) / 200);
            shareE[size_t(d)].push_back(double(ne[size_t(d)]) / 200);
            shareWrong[size_t(d)].push_back(wrong[size_t(d)] / wrongSum);
        }
    }
    double worst = 0, power = 0;
    for (int d = 0; d < 4; ++d) {
        if (shareE[size_t(d)] == std::vector<double>(size_t(K), 0.0)) continue;  // a depth without light
        const auto w = conformance::WelchTest(shareC[size_t(d)], shareE[size_t(d)]);
        const auto p = conformance::WelchTest(shareWrong[size_t(d)], shareE[size_t(d)]);
        worst = std::max(worst, std::abs(w.t) / conformance::StudentCritical(1e-4 / 4, w.dof));
        power = std::max(power, std::abs(p.t) / conformance::StudentCritical(1e-4 / 4, p.dof));
        std::cout << "[ mlt ] depth " << d << ": capped " << w.meanA << " +- " << w.seA << ", equal " << w.meanB
                  << " +- " << w.seB << ", wrong " << p.meanA << "\n";
    }
    EXPECT_LE(worst, 1) << "chain starts of a capped bootstrap differ from an equal one";
    EXPECT_GT(power, 1) << "power check: starts weighted without 1 / N_d are not detected";
}

// largestepmis (mlt.h; Kelemen et al. 2002, Sec. 4). Two emitters fill the
// view side by side, radiance 1e-3 (left) and 1e6 (right), maxdepth 0: every
// pixel of the left half is exactly 1e-3 (box footprint, unfiltered splats).
// The chains live on the bright half; pbrt-v3's estimator gives the dim half
// its light only through states that visit it (probability ~1e-9), so its
// mean there falls far short. With largestepmis the large steps carry it.
// One-sample t of the dim half's mean over K = 20 seeds against 1e-3 at
// alpha 1e-4 (Student, 19 dof); the same statistic rejects the default
// estimator (the power check: its loss is the bias this option exists for).
TEST(MLTRender, LargeStepMISRecoversADimEmitterBesideABrightOne) {
    auto scene = [](const char *mis) {
        return MLTLine(std::string("\"integer maxdepth\" [0] \"integer chains\" [64] "
                                   "\"integer bootstrapsamples\" [4000] \"bool largestepmis\" [") +
                       mis + "]") +
               "\nSampler \"random\"\nPixelFilter \"box\"\nFilm \"image\" \"integer xresolution\" [16] "
               "\"integer yresolution\" [8] \"string filename\" [\"unused.exr\"]\n"
               "LookAt 0 0 -1  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [90]\n"
               "WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
               "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1e-3 1e-3 1e-3]\n"
               "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [0 -2 0  0 2 0  3 2 0  3 -2 0]\n"
               "AttributeEnd\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1e6 1e6 1e6]\n"
               "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-3 -2 0  -3 2 0  0 2 0  0 -2 0]\n"
               "AttributeEnd\nWorldEnd\n";
    };
    const int K = 20;
    auto tStatistic = [&](const char *mis, double *mean) {
        std::vector<double> v;
        for (int k = 0; k < K; ++k) {
            Rendered r = Render(scene(mis), 16, uint64_t(700 + k));
            EXPECT_TRUE(AllFinite(r.image));
            // The dim half is the darker one; the two columns at the seam are left out.
            v.push_back(std::min(MeanLum(r.image, 0, 0, 7, 8), MeanLum(r.image, 9, 0, 16, 8)));
        }
        double m = 0, s2 = 0;
        for (double x : v) m += x / K;
        for (double x : v) s2 += (x - m) * (x - m) / (K - 1);
        *mean = m;
        return (m - 1e-3) / std::sqrt(s2 / K + 1e-300);
    };
    const double crit = conformance::StudentCritical(1e-4, K - 1);
    double meanMIS = 0, meanDefault = 0;
    const double tMIS = tStatistic("true", &meanMIS), tDefault = tStatistic("false", &meanDefault);
    std::cout << "[ mlt ] dim half: largestepmis " << meanMIS << " (t " << tMIS << "), default " << meanDefault
              << " (t " << tDefault << "), exact 1e-3, critical " << crit << "\n";
    EXPECT_LT(std::abs(tMIS), crit) << "largestepmis: the dim emitter's mean " << meanMIS << " is not 1e-3";
    EXPECT_GT(std::abs(tDefault), crit) << "power check: the default estimator's loss is not detected";
}

}  // namespace
}  // namespace gradus::mlt_test
