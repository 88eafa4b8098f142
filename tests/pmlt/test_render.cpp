// pmlt renders: parameters, statistics, the normalisation (every mutation
// splats luminance b in all, so the image mean is b), chain starts rebuilt
// from their bootstrap strategies, and a bootstrap without light.
#include "integrators/pmlt/pmlt.h"
#include "mlt/unbiased_util.h"

namespace gradus::pmlt_test {
namespace {

using mlt_test::BoxScene;
using mlt_test::MeanLum;
using mlt_test::Render;

const PMLTIntegrator &P(const mlt_test::Rendered &r) { return dynamic_cast<const PMLTIntegrator &>(*r.integrator); }

std::string Line(const std::string &extra = "") {
    return "Integrator \"pmlt\" \"integer maxdepth\" [4] \"integer bootstrapsamples\" [4000] "
           "\"integer chains\" [64] " + extra;
}

TEST(PMLTRender, ParametersStatisticsAndImageMeanIsB) {
    mlt_test::Rendered r = Render(BoxScene(Line("\"integer mutationsperpixel\" [6] \"float caustic\" [0.5]")), 0, 3);
    const PMLTIntegrator &p = P(r);
    EXPECT_EQ(p.settings().maxDepth, 4);
    EXPECT_EQ(p.settings().caustic, 0.5);
    EXPECT_EQ(r.stats.spp, 6);
    EXPECT_EQ(p.startMismatches(), 0) << "a chain start must rebuild its bootstrap strategy's path";
    int64_t total = 0;
    for (auto t : {pmlt::MutationType::Bidirectional, pmlt::MutationType::Lens}) {
        const auto c = p.counts(t);
        EXPECT_GT(c.accepted, 0) << pmlt::MutationName(t);
        total += c.proposed + c.zero + c.notApplicable;
    }
    for (auto t : {pmlt::MutationType::Caustic, pmlt::MutationType::MultiChain, pmlt::MutationType::Manifold})
        total += p.counts(t).proposed + p.counts(t).zero + p.counts(t).notApplicable;
    EXPECT_EQ(total, 6 * 144);
    ASSERT_GT(p.b(), 0);
    // Unfiltered splats of total luminance b per mutation, 6 x 144 mutations, film / (6 spp).
    EXPECT_NEAR(MeanLum(r.image), p.b(), 1e-4 * p.b());
    for (const char *want : {"bidirectional: ", "lens: ", "caustic: ", "multichain: ", "manifold: ", "manifold walks: ", "b = ",
                             "chains: 64"})
        EXPECT_NE(r.statistics.find(want), std::string::npos) << want << " in\n" << r.statistics;
}

// pbrt-v4 #77: a bootstrap that finds no light gives a black image and a message, not a crash.
TEST(PMLTRender, SealedLightGivesBlackImageAndWarning) {
    mlt_test::Rendered r = Render(BoxScene(Line(), 12, "sealed"), 2, 1);
    EXPECT_EQ(P(r).b(), 0);
    EXPECT_NE(P(r).warning().find("carries light"), std::string::npos);
    EXPECT_EQ(MeanLum(r.image), 0);
}

// directsamples (the chains render paths of two or more scattering vertices,
// the first pass the rest by the path tracer at maxdepth 1) and rrdepth
// (Russian roulette in the bootstrap's subpaths from the second bounce on:
// an unbiased weighting of the candidates, so b and the starts stay
// unbiased). K = 30 runs of each against bdpt at 16 spp, reduced to the 10
// pixel-set means of mlt/unbiased_util.h, Welch's t per set at alpha =
// 1e-4 / 20 (Bonferroni over both configurations: false-positive rate
// <= 1e-4); the same runs scaled by 1.05 or 1/1.05 must be rejected (power for
// a bias of 5%).
TEST(PMLTRender, DirectSamplesAndRouletteAgreeWithBdpt) {
    const int K = 30, S = 16;
    const std::string bd = BoxScene("Integrator \"bdpt\" \"integer maxdepth\" [4]");
    std::vector<std::vector<double>> rb;
    for (int k = 0; k < K; ++k) rb.push_back(mlt_test::Reduce(Render(bd, S, uint64_t(60001 + k)).image));
    const double alpha = 1e-4 / 20;
    for (const char *extra : {"\"integer directsamples\" [4]", "\"integer rrdepth\" [1]"}) {
        const std::string pm = BoxScene(Line(extra));
        std::vector<std::vector<double>> rp;
        for (int k = 0; k < K; ++k) rp.push_back(mlt_test::Reduce(Render(pm, S, uint64_t(50001 + k)).image));
        const mlt_test::Comparison c = mlt_test::Compare(rp, rb, 1, alpha);
        std::cout << "[ pmlt ] " << extra << " vs bdpt: |t|/crit " << c.maxMargin << " (" << c.describe << ")\n";
        EXPECT_LE(c.maxMargin, 1) << extra << ": " << c.describe;
        for (double scale : {1.05, 1 / 1.05}) {
            const mlt_test::Comparison p = mlt_test::Compare(rp, rb, scale, alpha);
            std::cout << "[ pmlt ] power x" << scale << ": " << p.maxMargin << "\n";
            EXPECT_GT(p.maxMargin, 1) << extra << ": a " << scale << " bias is not detected";
        }
    }
}

// bootstrapconnections caps the bootstrap by a count fixed by the parameters:
// maxdepth 4 has (4 + 2)^2 / 2 = 18 connections per sample.
TEST(PMLTRender, BootstrapConnectionsCapTheSampleCount) {
    auto count = [](const std::string &extra) {
        mlt_test::Rendered r = Render(BoxScene(Line(extra)), 1, 1);
        EXPECT_GT(P(r).b(), 0);
        return P(r).bootstrapSampleCount();
    };
    EXPECT_EQ(count(""), 4000);                                          // no cap by default
    EXPECT_EQ(count("\"integer bootstrapconnections\" [36000]"), 2000);  // 36000 / 18
    EXPECT_EQ(count("\"integer bootstrapconnections\" [18]"), 1000);     // at least 1000
    EXPECT_EQ(count("\"integer bootstrapconnections\" [0]"), 4000);      // no cap
}

TEST(PMLTRender, BidirectionalMutationIsRequired) {
    EXPECT_THROW(Render(BoxScene(Line("\"float bidirectional\" [0]")), 1, 1), Error);
}

}  // namespace
}  // namespace gradus::pmlt_test
