// Slow tier: pmlt and gmlt over long chains, and gmlt with the near-specular
// shift (Fig. 5a), against bdpt.
#include "gmlt/gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

using mlt_test::Render;

// The conformance table's diffuse box (24 x 24, its ceiling light in view)
// with another Integrator directive.
std::string DiffuseBox(const std::string &integrator) {
    return WithIntegrator(ConformanceScene("diffuse-box"), integrator);
}

// Long chains (8 chains, 256 mutations per pixel of the 24 x 24 diffuse box:
// 18 432 mutations each) against bdpt: K = 32 runs each, reduced to the
// image mean and 36 block means, Welch's t at alpha = 1e-4 / 148 (Bonferroni
// over pmlt's image, gmlt's primal and L2 reconstruction, and gmlt's L2
// reconstruction with direct light by 4 path-traced samples per pixel, added
// after the solve, Sec. 7). Power: the runs
// scaled by 1.1 or 1 / 1.1 must be rejected. The error of a wrong stationary
// distribution grows with the chain length, and short chains started from the
// bootstrap (the conformance table) hide it: pmlt's proposals of lens-emitter
// paths through a split its transition density left out put 50% more light on
// the emitter's pixels after 4096 mutations per pixel, which this test
// rejects (measured before the fix, K = 24: |t|/critical 12.3 for pmlt,
// 9.5 and 11.1 for gmlt's primal and L2 reconstruction; after it 0.24, 0.44, 0.29).
TEST(GMLTRenderSlow, LongChainsAgreeWithBdpt) {
    const int K = 32, S = 256;
    const std::string chains = "\"integer maxdepth\" [5] \"integer bootstrapsamples\" [20000] \"integer chains\" [8]";
    std::vector<std::vector<double>> rb, rp, rg, rl, rd;
    for (int k = 0; k < K; ++k) {
        rb.push_back(Blocks(Render(DiffuseBox("Integrator \"bdpt\" \"integer maxdepth\" [5]"), S / 4,
                                   uint64_t(70001 + k)).image));
        rp.push_back(Blocks(Render(DiffuseBox("Integrator \"pmlt\" " + chains), S, uint64_t(71001 + k)).image));
        const Image g = Render(DiffuseBox("Integrator \"gmlt\" " + chains), S, uint64_t(72001 + k)).image;
        rg.push_back(Blocks(g.layerRGB("primal")));
        rl.push_back(Blocks(g.layerRGB("reconstructed_l2")));
        const Image gd = Render(DiffuseBox("Integrator \"gmlt\" \"integer directsamples\" [4] " + chains), S,
                                uint64_t(73001 + k)).image;
        rd.push_back(Blocks(gd.layerRGB("reconstructed_l2")));
    }
    const double alpha = 1e-4 / (4 * double(rb[0].size()));
    const char *names[] = {"pmlt", "gmlt primal", "gmlt reconstructed_l2", "gmlt directsamples 4 reconstructed_l2"};
    const std::vector<std::vector<double>> *runs[] = {&rp, &rg, &rl, &rd};
    for (int i = 0; i < 4; ++i) ExpectAgreesWithBdpt("long chains", names[i], *runs[i], rb, alpha);
}

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
