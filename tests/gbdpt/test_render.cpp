// Default-tier G-BDPT render tests: output layers, parameters, no NaN/Inf on
// scenes with glass and mirrors, statistics. Agreement with BDPT in
// expectation is tested by the conformance table (tests/conformance).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "gbdpt_test_util.h"

using namespace gradus;
using namespace gradus::gbdpttest;

namespace {

double Mean(const Image &im, int c) {
    double s = 0;
    for (int y = 0; y < im.height(); ++y)
        for (int x = 0; x < im.width(); ++x) s += im.at(x, y, c);
    return s / (im.width() * im.height());
}

bool AllFinite(const Image &im) {
    for (float v : im.data())
        if (!std::isfinite(v)) return false;
    return true;
}

}  // namespace

TEST(GBDPTRender, LayersFiniteAndStatistics) {
    for (bool glossy : {false, true})
        for (const char *line : {"Integrator \"gbdpt\"", "Integrator \"gbdpt\" \"string shift\" \"halfvector\"",
                                 "Integrator \"gbdpt\" \"string mis\" \"simple\" \"bool lighttracing\" \"false\""}) {
            std::string stats;
            Image g = Render(BoxScene(line, 24, 18, glossy), 32, 7, "", &stats);
            for (const char *layer : {"primal", "dx", "dy", "reconstructed_l1", "reconstructed_l2"}) {
                Image l = g.layerRGB(layer);
                ASSERT_EQ(l.width(), 24) << layer;
                EXPECT_TRUE(AllFinite(l)) << line << " " << layer;
            }
            EXPECT_NE(stats.find("case (iii)"), std::string::npos);
            if (!glossy && std::string(line) == "Integrator \"gbdpt\"") {
                EXPECT_EQ(stats.find("manifold walks 0,"), std::string::npos) << stats;
            }
        }
}

TEST(GBDPTRender, DiffuseSceneSkipsManifoldWalks) {
    std::string scene = BoxScene("Integrator \"gbdpt\"");
    // Replace both spheres' materials with matte.
    for (const char *m : {"Material \"glass\"", "Material \"mirror\""}) {
        size_t at = scene.find(m);
        ASSERT_NE(at, std::string::npos);
        scene.replace(at, std::string(m).size(), "Material \"matte\"");
    }
    std::string stats;
    Image g = Render(scene, 4, 1, "", &stats);
    EXPECT_NE(stats.find("manifold walks: skipped"), std::string::npos) << stats;
    EXPECT_NE(stats.find("manifold walks 0,"), std::string::npos) << stats;
}

TEST(GBDPTRender, ParameterErrors) {
    EXPECT_THROW(Render(BoxScene("Integrator \"gbdpt\" \"string shift\" \"bogus\""), 1, 0), Error);
    EXPECT_THROW(Render(BoxScene("Integrator \"gbdpt\" \"string mis\" \"bogus\""), 1, 0), Error);
    EXPECT_THROW(Render(BoxScene("Integrator \"gbdpt\" \"string reconstruction\" \"l3\""), 1, 0), Error);
    EXPECT_THROW(Render(BoxScene("Integrator \"gbdpt\" \"float shiftthreshold\" [-1]"), 1, 0), Error);
}

// "lighttracing false" next to an infinite light: on a diffuse scene (no path
// needs light tracing) the primal without light-tracing strategies estimates
// the same image as with them, with about the same variance. The weights of
// next-event estimation towards the environment once left out the
// light-tracing term computed with the light subpath's origin instead of the
// sampled light vertex: +0.7% here at 512 spp (z ~ 8 below) and a primal
// variance 7x that of the render with light tracing. The variance of both
// means is taken from the render with light tracing (the other's estimate is
// heavy-tailed when its weights are wrong).
TEST(GBDPTRender, NoLightTracingUnbiasedWithInfiniteLight) {
    auto scene = [](const std::string &integrator) {
        return R"(
Sampler "random"
PixelFilter "box"
Film "image" "integer xresolution" [24] "integer yresolution" [20] "string filename" ["unused.exr"]
LookAt 0 1.5 4  0 0.4 0  0 1 0
Camera "perspective" "float fov" [45]
)" + integrator + R"(
WorldBegin
LightSource "infinite" "rgb L" [0.4 0.5 0.7]
Material "matte" "rgb Kd" [0.6 0.6 0.6]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-3 0 -3  -3 0 3  3 0 3  3 0 -3]
AttributeBegin
Material "matte" "rgb Kd" [0.5 0.4 0.3]
Translate -0.5 0.5 0
Shape "sphere" "float radius" [0.5]
AttributeEnd
AttributeBegin
Material "matte" "rgb Kd" [0.3 0.3 0.6]
Translate 0.6 0.4 -0.4
Shape "sphere" "float radius" [0.4]
AttributeEnd
AttributeBegin
AreaLightSource "diffuse" "rgb L" [3 3 3]
Material "matte" "rgb Kd" [0 0 0]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [-0.3 2.5 -0.3 0.3 2.5 -0.3 0.3 2.5 0.3 -0.3 2.5 0.3]
AttributeEnd
WorldEnd
)";
    };
    const int spp = 512;
    Image on = Render(scene("Integrator \"gbdpt\""), spp, 11);
    Image off = Render(scene("Integrator \"gbdpt\" \"bool lighttracing\" \"false\""), spp, 12);
    for (int c = 0; c < 3; ++c) {
        double mOn = Mean(on.layerRGB("primal"), c), mOff = Mean(off.layerRGB("primal"), c);
        double vOn = Mean(on.layerRGB("primal_var"), c), vOff = Mean(off.layerRGB("primal_var"), c);
        // Variance of an image mean: mean pixel variance / number of pixels.
        double z = (mOff - mOn) / std::sqrt(2 * vOn / (on.width() * on.height()));
        EXPECT_LT(std::abs(z), 4.5) << "channel " << c << ": mean " << mOff << " without, " << mOn << " with";
        EXPECT_LT(vOff, 2 * vOn) << "channel " << c << ": primal variance without light tracing";
        std::printf("channel %d: primal mean %.5f without light tracing, %.5f with, z = %.2f; variance %.3g / %.3g\n",
                    c, mOff, mOn, z, vOff, vOn);
    }
}
