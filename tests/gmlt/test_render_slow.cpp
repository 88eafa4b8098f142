// Slow tier: gmlt renders with the near-specular shift (Fig. 5a) against bdpt.
#include "gmlt/gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

using mlt_test::Render;

// The glossy box (both spheres near-specular, Fig. 5a) with the shift
// treating them as specular (shiftthreshold 0.1): gmlt's primal and L2
// reconstruction against bdpt, K = 24 runs each (8 chains, 1024 mutations per
// pixel), image mean and 36 block means, Welch's t at alpha = 1e-4 / 74
// (Bonferroni); the runs scaled by 1.1 or 1 / 1.1 must be rejected.
TEST(GMLTRenderSlow, NearSpecularShiftAgreesWithBdpt) {
    const int K = 24, S = 1024;
    std::vector<std::vector<double>> rb, rg, rl;
    int64_t nearShifts = 0;
    for (int k = 0; k < K; ++k) {
        rb.push_back(Blocks(Render(WithIntegrator(GlossyBox(), "Integrator \"bdpt\" \"integer maxdepth\" [5]"), S / 4,
                                   uint64_t(74001 + k)).image));
        mlt_test::Rendered g = Render(
            WithIntegrator(GlossyBox(), "Integrator \"gmlt\" \"integer maxdepth\" [5] \"integer bootstrapsamples\" "
                                        "[20000] \"integer chains\" [8] \"float shiftthreshold\" [0.1]"),
            S, uint64_t(75001 + k));
        EXPECT_EQ(G(g).gsettings().shiftThreshold, Float(0.1));
        nearShifts += G(g).nearSpecularShifts();
        rg.push_back(Blocks(g.image.layerRGB("primal")));
        rl.push_back(Blocks(g.image.layerRGB("reconstructed_l2")));
    }
    EXPECT_GT(nearShifts, 0);
    const double alpha = 1e-4 / (2 * double(rb[0].size()));
    const char *names[] = {"gmlt primal", "gmlt reconstructed_l2"};
    const std::vector<std::vector<double>> *runs[] = {&rg, &rl};
    for (int i = 0; i < 2; ++i) ExpectAgreesWithBdpt("glossy box", names[i], *runs[i], rb, alpha);
}

}  // namespace
}  // namespace gradus::pmlt_test
