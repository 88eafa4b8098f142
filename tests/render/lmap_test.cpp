// Area-light parameter "texture Lmap" (glTF emissive textures): each
// triangle emits L times the texture's mean over it, from 16 stratified
// points (exact for constant textures, within the rule's 1% for linear ones).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.h"
#include "lights/light.h"
#include "parser/scene_desc.h"
#include "job/job.h"

using namespace gradus;

namespace {

// A unit quad in z = 0 with uv = (x, y), two triangles: (0,0) (1,0) (1,1) and
// (0,0) (1,1) (0,1), emitting L = 2 towards +z scaled by the texture "t".
std::string Scene(const std::string &texture, const std::string &shape = "") {
    return "LookAt 0.5 0.5 3  0.5 0.5 0  0 1 0\nCamera \"perspective\"\n"
           "Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\nWorldBegin\n" +
           texture + "\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2] \"texture Lmap\" \"t\"\n" +
           (shape.empty() ? "Shape \"trianglemesh\" \"point P\" [0 0 0  1 0 0  1 1 0  0 1 0] "
                            "\"integer indices\" [0 1 2  0 2 3] \"point2 uv\" [0 0  1 0  1 1  0 1]"
                          : shape) +
           "\nAttributeEnd\nWorldEnd\n";
}

// Emitted radiance of each area light, in creation order (power / (area pi)).
std::vector<double> Radiances(const std::string &text) {
    SceneDesc d = ParseString(text, "lmap.pbrt");
    auto scene = BuildScene(d, {4, 4});
    std::vector<double> L;
    for (const auto &l : scene->lights)
        if (l->flags & LIGHT_AREA) {
            const auto *al = static_cast<const AreaLight *>(l.get());
            L.push_back(al->power().g / (al->shape().area() * M_PI));
        }
    return L;
}

TEST(AreaLightLmap, ConstantTextureScalesExactly) {
    std::vector<double> L = Radiances(Scene("Texture \"t\" \"spectrum\" \"constant\" \"rgb value\" [0.25 0.25 0.25]"));
    ASSERT_EQ(L.size(), 2u);
    for (double v : L) EXPECT_DOUBLE_EQ(v, 0.5);
}

TEST(AreaLightLmap, LinearTextureGivesEachTriangleItsMean) {
    // bilerp with v10 = v11 = 1: the texture is u. Its mean over triangle 1
    // is u at the centroid, 2/3; over triangle 2, 1/3.
    std::vector<double> L = Radiances(Scene("Texture \"t\" \"spectrum\" \"bilerp\" \"rgb v00\" [0 0 0] "
                                            "\"rgb v01\" [0 0 0] \"rgb v10\" [1 1 1] \"rgb v11\" [1 1 1]"));
    ASSERT_EQ(L.size(), 2u);
    EXPECT_NEAR(L[0], 2 * 2.0 / 3, 0.01 * 2 * 2.0 / 3);
    EXPECT_NEAR(L[1], 2 * 1.0 / 3, 0.01 * 2 * 1.0 / 3 + 0.01);
    EXPECT_GT(L[0], 1.5 * L[1]);  // the brighter half is the one at larger u
}

TEST(AreaLightLmap, BlackTrianglesEmitNothing) {
    EXPECT_TRUE(Radiances(Scene("Texture \"t\" \"spectrum\" \"constant\" \"rgb value\" [0 0 0]")).empty());
}

TEST(AreaLightLmap, LocatedErrors) {
    auto error = [](const std::string &text) {
        try {
            Radiances(text);
        } catch (const Error &e) {
            return std::string(e.what());
        }
        return std::string();
    };
    std::string e = error(Scene("Texture \"u\" \"spectrum\" \"constant\" \"rgb value\" [1 1 1]"));
    EXPECT_NE(e.find("lmap.pbrt:"), std::string::npos) << e;
    EXPECT_NE(e.find("unknown spectrum texture \"t\""), std::string::npos) << e;
    e = error(Scene("Texture \"t\" \"spectrum\" \"constant\" \"rgb value\" [1 1 1]", "Shape \"sphere\""));
    EXPECT_NE(e.find("non-triangle shapes"), std::string::npos) << e;
}

}  // namespace
