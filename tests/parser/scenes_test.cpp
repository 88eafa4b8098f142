// Every shared third-party pbrt-v3 scene and every reference variant parses,
// and every PLY mesh they reference reads with in-range indices.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "parser/ply.h"
#include "parser/scene_desc.h"

using namespace gradus;
namespace fs = std::filesystem;

namespace {

std::vector<std::string> SceneFiles() {
    std::vector<std::string> files;
    const fs::path scenes = std::string(GRADUS_SOURCE_DIR) + "/../shared/scenes",
                   refs = std::string(GRADUS_SOURCE_DIR) + "/../shared/references";
    std::error_code ec;
    if (fs::is_directory(scenes, ec))
        for (const auto &e : fs::recursive_directory_iterator(scenes, ec))
            if (e.is_regular_file() && e.path().extension() == ".pbrt") files.push_back(e.path().string());
    if (fs::is_directory(refs, ec))
        for (const auto &e : fs::directory_iterator(refs, ec))
            if (fs::is_regular_file(e.path() / "ref.pbrt")) files.push_back((e.path() / "ref.pbrt").string());
    return files;
}

}  // namespace

TEST(SharedScenes, AllParse) {
    std::vector<std::string> files = SceneFiles();
    if (files.empty()) GTEST_SKIP() << "../shared/scenes and ../shared/references are absent";
    for (const std::string &f : files) {
        SCOPED_TRACE(f);
        SceneDesc s;
        ASSERT_NO_THROW(s = ParseFile(f));
        EXPECT_TRUE(s.camera.present);
        EXPECT_TRUE(s.film.present);
        EXPECT_FALSE(s.shapes.empty());
        for (const ShapeDesc &sh : s.shapes) {
            EXPECT_TRUE(sh.material >= -1 && sh.material < int(s.materials.size()));
            EXPECT_TRUE(sh.areaLight >= -1 && sh.areaLight < int(s.areaLights.size()));
            if (sh.type != "plymesh") continue;
            std::string ply = s.resolve(sh.params.getString("filename", ""));
            PlyMesh m;
            ASSERT_NO_THROW(m = ReadPly(ply)) << ply;
            EXPECT_FALSE(m.indices.empty()) << ply;
            EXPECT_EQ(m.indices.size() % 3, 0u);
            for (int i : m.indices) ASSERT_TRUE(i >= 0 && size_t(i) < m.P.size()) << ply;
        }
    }
}

TEST(SharedScenes, CornellBoxContents) {
    const std::string f = std::string(GRADUS_SOURCE_DIR) + "/../shared/scenes/cornell-box/scene.pbrt";
    if (!fs::exists(f)) GTEST_SKIP() << f << " is absent";
    SceneDesc s = ParseFile(f);
    EXPECT_EQ(s.camera.type, "perspective");
    EXPECT_NEAR(s.camera.params.getFloat("fov", 0), 19.5, 1e-12);
    EXPECT_EQ(s.integrator.type, "path");
    EXPECT_EQ(s.shapes.size(), 8u);
    EXPECT_EQ(s.namedMaterials.size(), 8u);
    ASSERT_EQ(s.areaLights.size(), 1u);
    EXPECT_EQ(s.shapes.back().areaLight, 0);
    EXPECT_EQ(s.materials[s.shapes.back().material].name, "Light");
    // The camera sits at (0, 1, 6.8) looking down -z (Transform directive, column-major).
    Point3 eye = s.camera.cameraFromWorld.inverse().applyPoint(Point3(0, 0, 0));
    EXPECT_NEAR(eye.x, 0, 1e-9);
    EXPECT_NEAR(eye.y, 1, 1e-9);
    EXPECT_NEAR(eye.z, 6.8, 1e-9);
    Vec3 fwd = s.camera.cameraFromWorld.inverse().applyVector(Vec3(0, 0, 1));
    EXPECT_NEAR(fwd.z, -1, 1e-9);
}
