// Statistical tests of G-PT against the path tracer ("path", an independent
// implementation) on a small scene that exercises every shift type.
//
// Reference: K independent path-traced renders (box filter) give per-pixel
// means and variances of the mean. G-PT at N spp gives dx, dy, the primal and
// their variance estimates (per-sample sums of squares).
//
// Gradients: z = (dx(p) - (P(p+1) - P(p))) / sqrt(var_dx + var_P(p) + var_P(p+1)),
// on disjoint pixel pairs (x even for dx, y even for dy) so the terms are
// independent. Under unbiasedness S = mean z^2 is about 1 (a little above,
// since the variances are estimated) and Z = sum z / sqrt(n) ~ N(0,1).
// Thresholds: S < 1.6 and |Z| < 4.5; with ~300 terms the Gaussian
// false-positive rates are < 1e-9 and 7e-6 (heavier tails of estimated
// variances raise them; the fixed seeds make the outcome deterministic).
// Mean of the L2 reconstruction vs the path tracer: two-sided z-test, |z| < 4.5.
#include <gtest/gtest.h>

#include <cmath>

#include "gpt_test_util.h"

using namespace gradus;
using namespace gradus::gpttest;

namespace {

using Reference = test::MeanOfRuns;

Reference PathReference(const std::string &scene, int runs, int spp) {
    return test::AverageRuns(runs, [&](int k) { return Render(scene, spp, 1000 + k, "path").layerRGB(""); });
}

void CheckGradients(const std::string &gptLine, const Reference &ref, int spp) {
    const std::string scene = ShiftScene(gptLine);
    Image g = Render(scene, spp, 77);
    const Image &P = ref.mean, &V = ref.varMean;
    test::GradientZ gz = test::GradientZStats(g, ref);
    const int n = gz.n;
    ASSERT_GT(n, 200);
    double S = gz.meanZ2, Z = gz.Z;
    EXPECT_LT(S, 1.6) << gptLine << ": mean z^2 over " << n << " gradient terms";
    EXPECT_LT(std::abs(Z), 4.5) << gptLine << ": summed z over " << n << " gradient terms";
    std::printf("%s: %d gradient terms, mean z^2 = %.3f, Z = %.3f\n", gptLine.c_str(), n, S, Z);

    // Primal (the base path tracer) and the L2 reconstruction's mean.
    Image p = g.layerRGB("primal"), pv = g.layerRGB("primal_var"), l2 = g.layerRGB("reconstructed_l2");
    for (int c = 0; c < 3; ++c) {
        double ml2 = 0, mref = 0, vg = 0, vref = 0, zp2 = 0;
        int np = g.width() * g.height();
        for (int y = 0; y < g.height(); ++y)
            for (int x = 0; x < g.width(); ++x) {
                ml2 += l2.at(x, y, c);
                mref += P.at(x, y, c);
                vg += pv.at(x, y, c);
                vref += V.at(x, y, c);
                double v = pv.at(x, y, c) + V.at(x, y, c);
                if (v > 1e-12) zp2 += Sqr(p.at(x, y, c) - P.at(x, y, c)) / v;
            }
        double z = (ml2 - mref) / std::sqrt(vg + vref);
        EXPECT_LT(std::abs(z), 4.5) << gptLine << ": L2 mean vs path tracer, channel " << c;
        EXPECT_LT(zp2 / np, 1.6) << gptLine << ": primal vs path tracer, channel " << c;
        std::printf("  channel %d: L2 mean %.5f, path mean %.5f, z = %.2f; primal mean z^2 = %.3f\n", c, ml2 / np,
                    mref / np, z, zp2 / np);
    }
}

}  // namespace

TEST(GPTUnbiased, GradientsAndL2MeanMatchPathTracer) {
    const std::string pathScene = ShiftScene("Integrator \"path\"");
    Reference ref = PathReference(pathScene, 16, 256);
    CheckGradients("Integrator \"gpt\"", ref, 1024);
    CheckGradients("Integrator \"gpt\" \"string shift\" \"hybrid\"", ref, 1024);
}
