// pmlt's path evaluation against the bidirectional estimator: for the path of
// every strategy (s >= 2 or s = 0, t >= 2) of many bdpt samples, F(x) must
// equal the strategy's unweighted contribution C*_st = F / p_st times the
// technique density p_st that Evaluate reports (pE on the camera side, pL on
// the light side). The scenes hold glass (refraction chains: the eta^2
// delta-free convention of path.h), a mirror, glossy metal, a point light, a
// distant light and an environment light, so the check covers the densities of
// every vertex kind from both sides.
#include "pmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

// Vertices store normals and barycentrics in float and BSDFs are rebuilt
// from them (sphere points re-intersected): F and C* p differ by rounding,
// measured up to 6.4e-4 (near-grazing cosines). A convention error (a missing
// eta^2 = 2.25 at a refraction, a cosine, a lobe probability) is a factor
// far outside 2e-3.
constexpr double kTolerance = 2e-3;

struct Checked {
    int paths = 0, specular = 0, infinite = 0;
    double worst = 0;
};

Checked CheckScene(const std::string &scene, int samples) {
    SceneSetup su(ConformanceScene(scene));
    Arena arena;
    Checked c;
    for (int k = 0; k < samples; ++k) {
        RNG rng(Hash(0x5eed, uint64_t(k)));
        BidirSample smp;
        if (!smp.make(su, rng, arena)) continue;
        for (int t = 2; t <= smp.nC; ++t)
            for (int s = 0; s <= smp.nL; ++s) {
                if (s == 1 || s + t - 2 > su.maxDepth) continue;
                const ConnectSamples cu = Numbers(rng);
                ConnectResult r;
                if (!ConnectBDPT(su.ctx, smp.light(s), smp.camera(t), s, t, cu, &r)) continue;
                pmlt::State st;
                EXPECT_TRUE(pmlt::StrategyPath(su.ctx, smp.light(s), smp.camera(t), s, t, cu, &st.x));
                pmlt::BuildBSDFs(su.ctx, st.x, arena, &st.bsdf);
                const bool ok = pmlt::Evaluate(su.ctx, su.film, st.x, st.bsdf.data(), &st.e);
                EXPECT_TRUE(ok) << scene << " sample " << k << " (s, t) = (" << s << ", " << t << ")";
                if (!ok) continue;
                const int n = st.x.size();
                const Float p = st.e.splitDensity(st.x, su.ctx, t, 0, n);
                EXPECT_GT(p, 0) << "(s, t) = (" << s << ", " << t << ")";
                const Spectrum expect = r.unweighted * p;
                for (int ch = 0; ch < 3; ++ch) {
                    const double a = st.e.F[ch], b = expect[ch];
                    const double rel = std::abs(a - b) / std::max(std::abs(b), 1e-30);
                    c.worst = std::max(c.worst, rel);
                    EXPECT_LT(rel, kTolerance) << scene << " sample " << k << " (s, t) = (" << s << ", " << t
                                         << ") channel " << ch << ": F " << a << ", C* p " << b;
                }
                ++c.paths;
                for (const PathVertex &v : st.x.v) {
                    c.specular += v.delta();
                    c.infinite += v.isInfiniteLight();
                }
            }
        arena.reset();
    }
    return c;
}

TEST(PMLTPath, ContributionEqualsBidirectionalEstimateTimesDensity) {
    const Checked spec = CheckScene("specular-box", 3000);
    const Checked out = CheckScene("outdoor", 3000);
    std::cout << "[ pmlt ] specular-box: " << spec.paths << " paths, " << spec.specular
              << " specular vertices, worst relative difference " << spec.worst << "\n"
              << "[ pmlt ] outdoor: " << out.paths << " paths, " << out.infinite << " ending at infinity, worst "
              << out.worst << "\n";
    // The check must have seen what it is about.
    EXPECT_GT(spec.paths, 5000);
    EXPECT_GT(spec.specular, 500);
    EXPECT_GT(out.infinite, 500);
}

// The bidirectional mutation's choices are distributions: deletion counts and
// added counts sum to one wherever a move exists, and a full regeneration is
// always possible (ergodicity).
TEST(PMLTMutation, ChoiceProbabilitiesSumToOne) {
    SceneSetup su(ConformanceScene("diffuse-box"));
    pmlt::MutationSettings ms;
    ms.maxDepth = 9;
    pmlt::Mutator m(su.ctx, su.film, ms);
    for (int n = 2; n <= ms.maxDepth + 2; ++n) {
        for (int nd = 0; nd <= n; ++nd) {  // the closed form against the rules
            int count = 0;
            for (int a = 0; a + nd <= n; ++a) count += m.allowedPosition(n, nd, a);
            EXPECT_EQ(m.positionCount(n, nd), count) << "n " << n << " nd " << nd;
        }
        double sum = 0;
        for (int nd = 0; nd <= n; ++nd) sum += m.deletionProbability(n, nd);
        EXPECT_NEAR(sum, 1, 1e-12) << "n " << n;
        EXPECT_GT(m.deletionProbability(n, n), 0) << "n " << n;
        EXPECT_EQ(m.positionCount(n, n), 1);
        for (int nd = 0; nd <= n; ++nd)
            for (int a = 0; a + nd <= n; ++a) {
                double add = 0;
                for (int na = 0; na <= ms.maxDepth + 2; ++na) add += m.additionProbability(n, nd, a, na);
                if (add > 0) {
                    EXPECT_NEAR(add, 1, 1e-12) << "n " << n << " nd " << nd << " a " << a;
                }
            }
    }
}

}  // namespace
}  // namespace gradus::pmlt_test
