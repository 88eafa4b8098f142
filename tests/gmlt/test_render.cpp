// gmlt renders: the gradient bookkeeping on a known gradient, parameters and
// statistics (agreement with bdpt over long chains: test_render_slow.cpp).
#include "gmlt/gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

using mlt_test::BoxScene;
using mlt_test::Render;

// An emitter (L = 1, luminance 1) covering exactly one half of a 16 x 8 film
// (world x >= 0 at z = -1, fov 90 on the 8-pixel axis), nothing else: I = 1
// on one half, 0 on the other, so dx = +-1 on column 7 (the sign from a bdpt
// render: which half is lit) and 0 everywhere else, dy = 0. Only paths lens-emitter exist: shifts inside the
// emitter have F(y) |T'| = F(x) (|T'| = p_E(x_1) / p_E(y_1)) and those across
// the edge from column 8 towards -x lose the emitter (n = 1). With
// "separated" false: the emitter seen directly is shifted like the rest.
std::string EdgeScene() {
    return "Integrator \"gmlt\" \"integer bootstrapsamples\" [20000] \"integer chains\" [64] \"bool separated\" "
           "false\n"
           "Sampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [16] \"integer yresolution\" [8] \"string filename\" [\"u.exr\"]\n"
           "LookAt 0 0 0  0 0 -1  0 1 0\nCamera \"perspective\" \"float fov\" [90]\nWorldBegin\n"
           "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
           "Material \"matte\" \"rgb Kd\" [0 0 0]\n"
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
           "[0 -10 -1  10 -10 -1  10 10 -1  0 10 -1]\nAttributeEnd\nWorldEnd\n";
}

// K = 8 runs: the edge column's mean dx against the expected +-1 by Student's
// t (alpha 1e-3, two-sided); power: the same runs against half of it (one
// direction's splats lost or misplaced), twice it and its negative (a sign
// error of Eq. 9 / 10) must be rejected. Elsewhere
// dx and dy vanish up to rounding (|F(y) |T'| - F(x)| ~ 1e-7 F): their mean
// absolute value stays below 1e-4 per pixel in every run.
TEST(GMLTRender, EmitterEdgeGradient) {
    const int K = 8;
    std::string bdpt = EdgeScene();
    bdpt.replace(0, bdpt.find('\n'), "Integrator \"bdpt\"");
    const Image ref = Render(bdpt, 4, 1).image;
    const double expected = mlt_test::Lum(ref, 8, 4) - mlt_test::Lum(ref, 7, 4);  // exactly +-1 (L = 1, box filter)
    ASSERT_NEAR(std::abs(expected), 1, 1e-5);
    std::vector<double> edge;
    double worstRest = 0;
    for (int k = 0; k < K; ++k) {
        mlt_test::Rendered r = Render(EdgeScene(), 32, uint64_t(100 + k));
        const Image dx = r.image.layerRGB("dx"), dy = r.image.layerRGB("dy");
        double e = 0, rest = 0;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 16; ++x) {
                if (x == 7) e += mlt_test::Lum(dx, x, y) / 8;
                else if (x < 15) rest += std::abs(mlt_test::Lum(dx, x, y));
                if (y < 7) rest += std::abs(mlt_test::Lum(dy, x, y));
            }
        edge.push_back(e);
        worstRest = std::max(worstRest, rest / (8 * 15 + 7 * 16));
    }
    double mean = 0, var = 0;
    for (double v : edge) mean += v / K;
    for (double v : edge) var += (v - mean) * (v - mean) / (K - 1);
    const double se = std::sqrt(var / K), crit = conformance::StudentCritical(1e-3, K - 1);
    std::cout << "[ edge ] dx on the edge column: " << mean << " +- " << se << " (expected " << expected
              << "); mean |dx|, |dy| elsewhere " << worstRest << "\n";
    EXPECT_LT(std::abs(mean - expected) / se, crit);
    for (double wrong : {0.5 * expected, 2 * expected, -expected}) EXPECT_GT(std::abs(mean - wrong) / se, crit) << wrong;
    EXPECT_LT(worstRest, 1e-4);
}

TEST(GMLTRender, ParametersLayersAndStatistics) {
    mlt_test::Rendered r = Render(BoxScene("Integrator \"gmlt\" \"integer maxdepth\" [3] \"integer bootstrapsamples\" "
                                           "[2000] \"integer chains\" [16] \"float alpha\" [0.5] \"bool statelayers\" "
                                           "true \"string reconstruction\" \"l2\""),
                                  4, 7);
    const GMLTIntegrator &g = G(r);
    EXPECT_EQ(g.gsettings().alpha, 0.5);
    EXPECT_TRUE(g.gsettings().stateLayers);
    const auto layers = r.image.layers();
    for (const char *l : {"primal", "dx", "dy", "reconstructed_l1", "reconstructed_l2", "density", "irreversible"})
        EXPECT_NE(std::find(layers.begin(), layers.end(), l), layers.end()) << l;
    // The density layer: one splat per mutation, so its mean is 1; irreversible ones are a part of it.
    EXPECT_NEAR(mlt_test::MeanLum(r.image.layerRGB("density")), 1, 1e-4);
    const double irr = mlt_test::MeanLum(r.image.layerRGB("irreversible"));
    EXPECT_GT(irr, 0);
    EXPECT_LT(irr, 1);
    // The unprefixed image is the chosen reconstruction (l2).
    EXPECT_EQ(mlt_test::MeanLum(r.image), mlt_test::MeanLum(r.image.layerRGB("reconstructed_l2")));
    int64_t shifts = 0;
    for (int s = 0; s < 6; ++s) shifts += g.shiftCount(pmlt::Mutator::ShiftStatus(s));
    EXPECT_GT(g.shiftCount(pmlt::Mutator::ShiftStatus::Shifted), 0);
    EXPECT_LE(shifts, 16 + 4 * 144);  // the chain starts and the proposals with a contribution
    for (const char *want : {"Gradient-domain MLT", "shifts: ", "reversible", "near-specular", "Reconstruction:",
                             "bidirectional: "})
        EXPECT_NE(r.statistics.find(want), std::string::npos) << want << " in\n" << r.statistics;
    // Parameters gmlt does not take, misspelt or out of range.
    for (const char *bad : {"\"float shiftthresold\" [0.01]", "\"float shiftthreshold\" [-1]",
                            "\"string pixelfilter\" \"film\"", "\"float alpha\" [0]"})
        EXPECT_THROW(Render(BoxScene(std::string("Integrator \"gmlt\" ") + bad), 1, 1), Error) << bad;
}

}  // namespace
}  // namespace gradus::pmlt_test
