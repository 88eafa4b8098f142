// Degenerate input renders without NaN/Inf and without crashing, or fails
// with a located error: zero-area triangles (also as emitters), zero-length
// normals, empty meshes, degenerate quadrics, roughness 0 and 1, glass with
// index 1, NaN vertices. Also replays fuzzer-found PLY inputs (data/).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/stats.h"
#include "parser/ply.h"
#include "render_util.h"

namespace gradus {
namespace {

const char *kHeader = R"(
LookAt 0 -4 2  0 0 0.3  0 0 1
Camera "perspective" "float fov" 45
Film "image" "integer xresolution" 24 "integer yresolution" 16
Sampler "random"
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.2 0.2]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [5 5 5]
  Translate 0 0 3
  Shape "sphere" "float radius" 0.4
AttributeEnd
Shape "trianglemesh" "point P" [-4 -4 0 4 -4 0 4 4 0 -4 4 0] "integer indices" [0 1 2 0 2 3]
)";

void ExpectFiniteRender(const std::string &world, const std::string &integrator = "path", int spp = 4) {
    RenderResult r = test::RenderSceneText(std::string(kHeader) + world + "\nWorldEnd\n", spp, 1, 2, integrator);
    EXPECT_EQ(r.stats.nonFinite, 0u) << "non-finite samples discarded";
    int bad = 0;
    for (float v : r.image.data())
        if (!std::isfinite(v)) ++bad;
    EXPECT_EQ(bad, 0) << "non-finite pixels";
}

TEST(Robustness, ZeroAreaTriangles) {
    // Collinear and coincident vertices, as plain geometry and as an emitter.
    ExpectFiniteRender(R"(Shape "trianglemesh" "point P" [0 0 0.5 1 0 0.5 2 0 0.5 0 0 1] "integer indices" [0 1 2 3 3 3])");
    ExpectFiniteRender(R"(AttributeBegin
AreaLightSource "diffuse" "rgb L" [3 3 3]
Shape "trianglemesh" "point P" [0 0 0.5 1 0 0.5 2 0 0.5 0 1 0.5] "integer indices" [0 1 2 0 1 3]
AttributeEnd)");
}

TEST(Robustness, ZeroLengthAndOpposedNormals) {
    ExpectFiniteRender(R"(Shape "trianglemesh" "point P" [-1 -1 0.5 1 -1 0.5 0 1 0.5]
  "normal N" [0 0 0 0 0 0 0 0 1] "integer indices" [0 1 2])");
    ExpectFiniteRender(R"(Shape "trianglemesh" "point P" [-1 -1 0.5 1 -1 0.5 0 1 0.5]
  "normal N" [0 0 1 0 0 -1 1 0 0] "integer indices" [0 1 2])");
}

TEST(Robustness, EmptyAndDegenerateMeshes) {
    namespace fs = std::filesystem;
    fs::path dir = fs::temp_directory_path() / ("gradus_robustness_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    {
        std::ofstream f(dir / "empty.ply");
        f << "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
    }
    std::string scene = std::string(kHeader) + "Shape \"plymesh\" \"string filename\" \"empty.ply\"\n" +
                        "Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 0 1]\n" +
                        "WorldEnd\n";
    RenderResult r = test::RenderSceneText(scene, 2, 1, 2, "path", dir.string());
    EXPECT_EQ(r.stats.nonFinite, 0u);
    fs::remove_all(dir);
}

TEST(Robustness, DegenerateQuadrics) {
    ExpectFiniteRender(R"(AttributeBegin
AreaLightSource "diffuse" "rgb L" [3 3 3]
Shape "sphere" "float zmin" 0.2 "float zmax" 0.2
Shape "cylinder" "float phimax" 0
Shape "disk" "float radius" 1e-9
AttributeEnd
Shape "cone" "float height" 1e-6 "float radius" 5
Shape "paraboloid" "float zmin" 0 "float zmax" 1e-8)");
}

TEST(Robustness, RoughnessExtremesAndIndexOne) {
    for (const char *integrator : {"path", "bdpt"}) {
        ExpectFiniteRender(R"(Material "metal" "float roughness" 0 "bool remaproughness" false
Shape "sphere" "float radius" 0.5
Material "metal" "float roughness" 1 "bool remaproughness" false
Translate 1 0 0
Shape "sphere" "float radius" 0.4
Material "glass" "float index" 1
Translate -2 0 0
Shape "sphere" "float radius" 0.4
Material "plastic" "float roughness" 0
Translate 0 1 0
Shape "disk" "float radius" 0.5 "float height" 0.01
Material "glass" "float index" 1 "float uroughness" 0.3 "float vroughness" 0.3
Translate 2 0 0
Shape "cylinder" "float radius" 0.3 "float zmin" 0 "float zmax" 0.5)", integrator);
    }
}

TEST(Robustness, NanVertexIsLocatedError) {
    std::string scene = std::string(kHeader) +
                        "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 0 nan 0] \"integer indices\" [0 1 2]\n"
                        "WorldEnd\n";
    try {
        test::RenderSceneText(scene, 1);
        FAIL() << "no error";
    } catch (const Error &e) {
        // The parser may reject "nan" itself; either way the error names a line.
        EXPECT_NE(std::string(e.what()).find("test.pbrt:"), std::string::npos) << e.what();
    }
    // Infinite coordinates after the transform (overflow) are rejected too.
    std::string overflow = std::string(kHeader) + "Scale 1e300 1e300 1e300\n"
                           "Shape \"trianglemesh\" \"point P\" [0 0 0 1e300 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
                           "WorldEnd\n";
    EXPECT_THROW(test::RenderSceneText(overflow, 1), Error);
}

// Inputs that crashed or misbehaved under the PLY fuzzer stay as regression tests.
TEST(Robustness, FuzzerPlyRegressions) {
    namespace fs = std::filesystem;
    fs::path dir = fs::path(GRADUS_SOURCE_DIR) / "tests/robustness/data";
    int n = 0;
    for (const auto &e : fs::directory_iterator(dir)) {
        if (e.path().extension() != ".ply") continue;
        std::ifstream f(e.path(), std::ios::binary);
        std::stringstream ss;
        ss << f.rdbuf();
        std::string s = ss.str();
        try {
            PlyMesh m = ReadPlyFromMemory(s.data(), s.size(), e.path().filename().string());
            TriangleMesh::Create(Transform(), false, m.P, m.indices, m.N, {}, m.uv, FileLoc());
        } catch (const Error &) {
        }
        ++n;
    }
    EXPECT_GE(n, 1);
}

// A fuzz-found scene (tests/fuzz/regressions) with a huge interface triangle
// (material "none", vertices near 1e6): Embree's float triangle lies ahead of
// the refined double hit by more than the spawn offset, so a ray re-hit the
// same interface forever (31 million closest-hit rays for 56 paths, 8 s, with
// path; gpt the same). Every walk stops after kMaxInterfaceCrossings.
TEST(Robustness, InterfaceRecrossingIsBounded) {
    namespace fs = std::filesystem;
    const fs::path file = fs::path(GRADUS_SOURCE_DIR) / "tests/fuzz/regressions/interface-recrossing-huge-triangle.pbrt";
    for (const char *integrator : {"path", "gpt", "bdpt", "gbdpt"}) {
        auto rays = [] {
            auto s = StatRegistry::get().snapshot();
            return s["Rays/Closest-hit rays"];
        };
        const uint64_t before = rays();
        RenderResult r = test::RenderSceneFile(file.string(), 1, 7, integrator);
        const uint64_t traced = rays() - before;
        // 112 film pixels at 1 spp: with at most 64 crossings per segment and
        // maxdepth 6 a path traces a few hundred rays at the very most.
        EXPECT_LT(traced, 200000u) << integrator;
        for (float v : r.image.data()) ASSERT_TRUE(std::isfinite(v)) << integrator;
    }
}

}  // namespace
}  // namespace gradus
