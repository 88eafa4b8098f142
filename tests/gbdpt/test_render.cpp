// Default-tier G-BDPT render tests: output layers, parameters, no NaN/Inf on
// scenes with glass and mirrors, statistics. Agreement with BDPT in
// expectation is tested by the conformance table (tests/conformance).
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "gbdpt_test_util.h"

using namespace gradus;
using namespace gradus::gbdpttest;

namespace {

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
