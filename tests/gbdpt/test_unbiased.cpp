// Statistical tests of G-BDPT against BDPT (the integrator it extends, run
// independently) on a box with a glass and a mirror sphere (caustics through
// light tracing, specular chains through the manifold walk).
//
// Reference: K independent BDPT renders (box filter) give per-pixel means and
// variances of the mean. G-BDPT gives dx, dy, the primal and their variance
// estimates. Gradients: z = (dx(p) - (P(p+1) - P(p))) / sqrt(var_dx + var_P(p)
// + var_P(p+1)) on disjoint pixel pairs (independent terms). Under
// unbiasedness S = mean z^2 is about 1 (somewhat above: estimated variances,
// heavy-tailed caustic samples) and Z = sum z / sqrt(n) ~ N(0,1). Thresholds
// S < 1.8 and |Z| < 4.5: with ~1000 terms the Gaussian false-positive rates are
// < 1e-9 and 7e-6; the seeds are fixed, so the outcome is deterministic.
// L2 reconstruction mean vs BDPT mean: two-sided z-test, |z| < 4.5 (6e-6).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "gbdpt_test_util.h"

using namespace gradus;
using namespace gradus::gbdpttest;

namespace {

using Reference = test::MeanOfRuns;

Reference BDPTReference(const std::string &scene, int runs, int spp) {
    return test::AverageRuns(runs, [&](int k) { return Render(scene, spp, 5000 + k, "bdpt").layerRGB(""); });
}

enum class TestScene { Box, Env, RoughGlassBox, GlossyBox };
std::string SceneText(TestScene sc, const std::string &line) {
    if (sc == TestScene::Env) return EnvScene(line, 24, 18, true);
    return BoxScene(line, 24, 18, sc == TestScene::GlossyBox, sc != TestScene::Box);
}

void Check(const std::string &line, const Reference &ref, int spp, TestScene sc = TestScene::Box) {
    Image g = Render(SceneText(sc, line), spp, 91);
    const Image &P = ref.mean, &V = ref.varMean;
    test::GradientZ gz = test::GradientZStats(g, ref);
    const int n = gz.n;
    ASSERT_GT(n, 500);
    double S = gz.meanZ2, Z = gz.Z;
    EXPECT_LT(S, 1.8) << line << ": mean z^2 over " << n << " gradient terms";
    EXPECT_LT(std::abs(Z), 4.5) << line << ": summed z over " << n << " gradient terms";
    std::printf("%s: %d gradient terms, mean z^2 = %.3f, Z = %.3f\n", line.c_str(), n, S, Z);
    Image p = g.layerRGB("primal"), pv = g.layerRGB("primal_var"), l2 = g.layerRGB("reconstructed_l2");
    for (int c = 0; c < 3; ++c) {
        double ml2 = 0, mp = 0, mref = 0, vg = 0, vref = 0;
        int np = g.width() * g.height();
        for (int y = 0; y < g.height(); ++y)
            for (int x = 0; x < g.width(); ++x) {
                ml2 += l2.at(x, y, c);
                mp += p.at(x, y, c);
                mref += P.at(x, y, c);
                vg += pv.at(x, y, c);
                vref += V.at(x, y, c);
            }
        double z = (ml2 - mref) / std::sqrt(vg + vref), zp = (mp - mref) / std::sqrt(vg + vref);
        EXPECT_LT(std::abs(z), 4.5) << line << ": L2 mean vs BDPT, channel " << c;
        EXPECT_LT(std::abs(zp), 4.5) << line << ": primal mean vs BDPT, channel " << c;
        std::printf("  channel %d: L2 mean %.5f, primal mean %.5f, BDPT mean %.5f, z = %.2f / %.2f\n", c, ml2 / np,
                    mp / np, mref / np, z, zp);
    }
}

}  // namespace

TEST(GBDPTUnbiased, GradientsAndL2MeanMatchBDPT) {
    Reference ref = BDPTReference(BoxScene("Integrator \"bdpt\""), 16, 256);
    Check("Integrator \"gbdpt\"", ref, 512);
    Check("Integrator \"gbdpt\" \"string shift\" \"halfvector\"", ref, 512);
    Check("Integrator \"gbdpt\" \"string mis\" \"simple\"", ref, 512);
    Check("Integrator \"gbdpt\" \"bool lighttracing\" \"false\"", ref, 512);
    // Roulette from the first bounce (the default starts at 3): the offsets'
    // 1/q factors are the base's (camera_shift.cpp).
    Check("Integrator \"gbdpt\" \"integer rrdepth\" [0]", ref, 512);
}

// Open scene lit by a sky, a sun and a point light, with glass and a mirror
// (gbdpt_test_util.h): the environment shift (escaped camera subpaths,
// next-event estimation of the sky and the sun, light subpaths from
// infinity) and reconnections to the point light in every strategy.
TEST(GBDPTUnbiased, EnvironmentAndPointLightGradientsMatchBDPT) {
    Reference ref = test::AverageRuns(16, [&](int k) {
        return Render(SceneText(TestScene::Env, "Integrator \"bdpt\""), 256, 7000 + k, "bdpt").layerRGB("");
    });
    Check("Integrator \"gbdpt\"", ref, 512, TestScene::Env);
    Check("Integrator \"gbdpt\" \"string shift\" \"halfvector\"", ref, 512, TestScene::Env);
}

// Near-specular rough glass (roughness 0.0005 < shiftthreshold): camera
// subpaths through it are shifted by half-vector refraction (they fell back
// before).
TEST(GBDPTUnbiased, RoughGlassGradientsMatchBDPT) {
    Reference ref = test::AverageRuns(16, [&](int k) {
        return Render(SceneText(TestScene::RoughGlassBox, "Integrator \"bdpt\""), 256, 8000 + k, "bdpt").layerRGB("");
    });
    Check("Integrator \"gbdpt\"", ref, 512, TestScene::RoughGlassBox);
}

// Near-specular metal sphere and rough glass (roughness 0.0005 < shiftthreshold):
// second chains b -> glossy vertices -> c are walked with their half-vectors
// kept (Phi of subpath_shift.h; they fell back before), in the camera-subpath
// and the light-tracing shifts (the metal sphere's caustic on the floor).
TEST(GBDPTUnbiased, GlossySecondChainGradientsMatchBDPT) {
    Reference ref = test::AverageRuns(16, [&](int k) {
        return Render(SceneText(TestScene::GlossyBox, "Integrator \"bdpt\""), 256, 9000 + k, "bdpt").layerRGB("");
    });
    Check("Integrator \"gbdpt\"", ref, 512, TestScene::GlossyBox);
}
