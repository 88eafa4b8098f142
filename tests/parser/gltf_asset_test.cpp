// The pbrt directive GltfAsset: a glTF asset placed under the current
// transform, its camera on request, located errors for the directive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

#include "parser/gltf.h"
#include "parser/scene_desc.h"

using namespace gradus;

namespace {

// A temporary directory holding quad.gltf + quad.bin: one quad in the z = 0
// plane under a node translated by (0, 0, -1), a camera node at z = 2 named
// "cam" and a point light.
class GltfAssetTest : public ::testing::Test {
  protected:
    void SetUp() override {
        char tmpl[] = "/tmp/gradus-gltf-asset-XXXXXX";
        ASSERT_NE(mkdtemp(tmpl), nullptr);
        dir_ = tmpl;
        const float P[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
        const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
        std::ofstream bin(dir_ + "/quad.bin", std::ios::binary);
        bin.write(reinterpret_cast<const char *>(P), sizeof P);
        bin.write(reinterpret_cast<const char *>(idx), sizeof idx);
        bin.close();
        std::ofstream(dir_ + "/quad.gltf") << R"({
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3}]}},
  "scene": 0,
  "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [{"mesh": 0, "translation": [0, 0, -1]},
            {"camera": 0, "name": "camnode", "translation": [0, 0, 2]},
            {"translation": [0, 1, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
  "cameras": [{"name": "cam", "type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": 60, "uri": "quad.bin"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [-1, -1, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]
}
)";
    }
    void TearDown() override {
        for (const char *f : {"quad.gltf", "quad.bin"}) std::remove((dir_ + "/" + f).c_str());
        rmdir(dir_.c_str());
    }
    SceneDesc parse(const std::string &world) {
        return ParseString("Camera \"perspective\"\nWorldBegin\n" + world + "\nWorldEnd\n", "s.pbrt", dir_);
    }
    std::string errorOf(const std::string &world) {
        try {
            parse(world);
        } catch (const Error &e) {
            return e.what();
        }
        return "";
    }
    std::string dir_;
};

void ExpectSameMatrix(const Transform &a, const Transform &b, double eps = 1e-12) {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(a.matrix().m[i][j], b.matrix().m[i][j], eps) << i << "," << j;
}

TEST_F(GltfAssetTest, PlacesTheAssetUnderTheCurrentTransform) {
    SceneDesc d = parse("Translate 5 0 0\nGltfAsset \"quad.gltf\"");
    ASSERT_EQ(d.shapes.size(), 1u);
    EXPECT_EQ(d.shapes[0].type, "trianglemesh");
    ExpectSameMatrix(d.shapes[0].worldFromObject, Translate(Vec3(5, 0, 0)) * Translate(Vec3(0, 0, -1)));
    ASSERT_EQ(d.lights.size(), 1u);
    EXPECT_EQ(d.lights[0].type, "point");
    ExpectSameMatrix(d.lights[0].worldFromLight, Translate(Vec3(5, 1, 0)));
    // The glTF default material (no material on the primitive).
    ASSERT_GE(d.shapes[0].material, 0);
    EXPECT_EQ(d.materials[d.shapes[0].material].type, "gltfpbr");
    // Without "camera" the scene's Camera stays.
    EXPECT_FALSE(d.camera.params.has("yfov"));
}

TEST_F(GltfAssetTest, CameraOfTheAssetReplacesTheScenesOnRequest) {
    for (const char *name : {"cam", "camnode"}) {
        SceneDesc d = parse("Translate 5 0 0\nGltfAsset \"quad.gltf\" \"string camera\" \"" + std::string(name) + "\"");
        ASSERT_TRUE(d.camera.params.has("yfov")) << name;
        EXPECT_NEAR(d.camera.params.getFloat("yfov", 0), Degrees(0.5), 1e-9);
        // glTF cameras look along -z: camera space is the node's with z flipped.
        ExpectSameMatrix(d.camera.cameraFromWorld, Scale(1, 1, -1) * (Translate(Vec3(5, 0, 0)) * Translate(Vec3(0, 0, 2))).inverse());
    }
}

TEST_F(GltfAssetTest, LocatedErrors) {
    std::string e = errorOf("GltfAsset \"quad.gltf\" \"string camrea\" \"cam\"");
    EXPECT_NE(e.find("s.pbrt:3:"), std::string::npos) << e;
    EXPECT_NE(e.find("camrea"), std::string::npos) << e;
    e = errorOf("GltfAsset \"missing.gltf\"");
    EXPECT_NE(e.find("s.pbrt:3:11"), std::string::npos) << e;
    EXPECT_NE(e.find("missing.gltf"), std::string::npos) << e;
    e = errorOf("GltfAsset \"quad.gltf\" \"string camera\" \"nosuch\"");
    EXPECT_NE(e.find("no camera named \"nosuch\""), std::string::npos) << e;
    EXPECT_NE(e.find("cam"), std::string::npos) << e;
    e = errorOf("ObjectBegin \"o\"\nGltfAsset \"quad.gltf\"\nObjectEnd");
    EXPECT_NE(e.find("GltfAsset inside ObjectBegin"), std::string::npos) << e;
    try {
        ParseString("GltfAsset \"quad.gltf\"\n", "s.pbrt", dir_);
        ADD_FAILURE() << "GltfAsset before WorldBegin accepted";
    } catch (const Error &) {
    }
}

TEST_F(GltfAssetTest, ErrorsInsideTheAssetNameItsLineAndPointer) {
    // Index 9 is beyond the 4 vertices: the message locates the indices accessor use.
    std::string text;
    {
        std::ifstream in(dir_ + "/quad.gltf");
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const uint16_t idx[6] = {0, 1, 2, 0, 2, 9};
    std::fstream bin(dir_ + "/quad.bin", std::ios::binary | std::ios::in | std::ios::out);
    bin.seekp(48);
    bin.write(reinterpret_cast<const char *>(idx), sizeof idx);
    bin.close();
    // Line and column of the value of "indices", found in the text independently.
    size_t off = text.find("\"indices\": 1") + std::string("\"indices\": ").size();
    int line = 1 + int(std::count(text.begin(), text.begin() + off, '\n'));
    int col = int(off - text.rfind('\n', off - 1));
    std::string e = errorOf("GltfAsset \"quad.gltf\"");
    std::string where = "quad.gltf:" + std::to_string(line) + ":" + std::to_string(col) + ":";
    EXPECT_NE(e.find(where), std::string::npos) << e << " (expected " << where << ")";
    EXPECT_NE(e.find("/meshes/0/primitives/0/indices"), std::string::npos) << e;
    EXPECT_NE(e.find("index 9"), std::string::npos) << e;
}

}  // namespace
