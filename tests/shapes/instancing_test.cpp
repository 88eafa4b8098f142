// Object instancing through Embree instances: an object used more than once is
// stored once and placed by a transform per use. The reference is the same
// scene written out flat (each use as a transformed copy of the shapes), which
// takes the older, independent path through the builder (world-space meshes).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "core/error.h"
#include "parser/scene_desc.h"
#include "render/render_util.h"
#include "job/job.h"

namespace gradus {
namespace {

// The object's shapes (in the object's space, after its inner transform): a
// curved patch with per-vertex normals and uvs, a flat quad without normals
// (geometric normal, orientation flips with handedness), and a sphere
// (analytic: flattened per use).
const char *kObjectShapes =
    "Rotate 20 0 1 0\n"
    "Material \"plastic\" \"rgb Kd\" [0.5 0.4 0.3] \"float roughness\" [0.2]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 1 4 2]\n"
    "  \"point P\" [-0.3 0 -0.3  0.3 0 -0.3  0.3 0.1 0.3  -0.3 0.05 0.3  0.5 0.3 0]\n"
    "  \"normal N\" [0 1 0.2  0.1 1 0  0.2 1 -0.1  -0.1 1 0.1  0.5 1 0]\n"
    "  \"point2 uv\" [0 0 1 0 1 1 0 1 2 0.5]\n"
    "Material \"matte\" \"rgb Kd\" [0.2 0.6 0.3]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n"
    "  \"point P\" [-0.2 0.2 0  0.2 0.2 0  0.2 0.5 0.05  -0.2 0.5 0]\n"
    "Translate 0 0.15 0.2\n"
    "Shape \"sphere\" \"float radius\" [0.08]\n";

// Uses: translation; rotation with a non-uniform scale; a mirror (handedness swap).
const char *kUses[] = {"Translate -0.5 0.2 0.1", "Translate 0.4 0.3 -0.2\nRotate -35 1 0.3 0\nScale 1.3 0.7 1.1",
                       "Translate 0 1.1 0.4\nScale -1 1 1\nRotate 60 0 0 1"};

std::string Header(const std::string &integratorLine = "Integrator \"path\"") {
    return test::TestSceneHeader("0 1 1.15  0 0.9 0  0 1 0", 70, 24, 24, integratorLine);
}

std::string Room() {
    return test::ClosedBoxWallsAndSphere() +
           "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [8 8 8]\n"
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
           "[-0.3 1.99 -0.3  0.3 1.99 -0.3  0.3 1.99 0.3  -0.3 1.99 0.3]\nAttributeEnd\n";
}

std::string InstancedWorld() {
    std::string w = Room() + "AttributeBegin\nObjectBegin \"thing\"\n" + kObjectShapes + "ObjectEnd\nAttributeEnd\n";
    for (const char *u : kUses) w += "AttributeBegin\n" + std::string(u) + "\nObjectInstance \"thing\"\nAttributeEnd\n";
    return w;
}

std::string FlatWorld() {
    std::string w = Room();
    for (const char *u : kUses) w += "AttributeBegin\n" + std::string(u) + "\n" + kObjectShapes + "AttributeEnd\n";
    return w;
}

std::string SceneText(const std::string &world, const std::string &integratorLine = "Integrator \"path\"") {
    return Header(integratorLine) + "WorldBegin\n" + world + "WorldEnd\n";
}

std::unique_ptr<Scene> Build(const std::string &world) {
    return BuildScene(ParseString(SceneText(world), "test.pbrt"), Point2i{24, 24});
}

double Diff(const Vec3 &a, const Vec3 &b) { return (a - b).length(); }

TEST(Instancing, ObjectUsedThriceIsStoredOnce) {
    auto inst = Build(InstancedWorld());
    auto flat = Build(FlatWorld());
    EXPECT_EQ(inst->features.numInstances, 3);
    EXPECT_EQ(flat->features.numInstances, 0);
    EXPECT_EQ(inst->features.numTriangles, flat->features.numTriangles);
    EXPECT_EQ(inst->features.numInstancedTriangles, 3 * 5);
    EXPECT_EQ(inst->features.numStoredTriangles, flat->features.numStoredTriangles - 2 * 5);
    // The three uses' records share the object's two meshes.
    std::set<const TriangleMesh *> placedMeshes;
    int placedRecords = 0;
    for (const GeometryRecord &g : inst->geometry)
        if (g.placement) {
            ++placedRecords;
            placedMeshes.insert(g.mesh.get());
        }
    EXPECT_EQ(placedRecords, 6);
    EXPECT_EQ(placedMeshes.size(), 2u);
    // An instance is bounded by its object's box, placed: the instanced scene's
    // bounds contain the flat scene's exact ones.
    for (int k = 0; k < 3; ++k) {
        EXPECT_LE(inst->bounds.pMin[k], flat->bounds.pMin[k]);
        EXPECT_GE(inst->bounds.pMax[k], flat->bounds.pMax[k]);
    }
}

// Closest hits and shadow rays of random rays inside the room: the instanced
// scene's world-space interactions (position, both normals, uv, all partial
// derivatives) equal the flattened scene's, and a stored vertex's interaction
// rebuilt from its record and barycentrics (what BDPT and the shifts do)
// equals the hit's.
TEST(Instancing, InteractionsEqualTheFlattenedScene) {
    auto inst = Build(InstancedWorld());
    auto flat = Build(FlatWorld());
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    int hitsOnInstances = 0, compared = 0, differentSurface = 0, occlusionMismatch = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        Point3 o(-0.9 + 1.8 * u(rng), 0.05 + 1.9 * u(rng), -0.9 + 2.0 * u(rng));
        Float z = 1 - 2 * u(rng), phi = 2 * Pi * u(rng), r = std::sqrt(std::max<Float>(0, 1 - z * z));
        Vec3 d(r * std::cos(phi), r * std::sin(phi), z);
        Ray ray(o, d, Infinity);
        SurfaceInteraction a, b;
        const bool ha = inst->intersect(ray, &a), hb = flat->intersect(ray, &b);
        ASSERT_TRUE(ha && hb);  // a closed room
        Ray shadow(o, d, 0.5);
        if (inst->occluded(shadow) != flat->occluded(shadow)) ++occlusionMismatch;
        if (Diff(a.p - b.p, Vec3(0, 0, 0)) > 1e-7) {  // a float-precision edge case: another surface
            ++differentSurface;
            continue;
        }
        const GeometryRecord &ga = inst->geometry[a.geomId];
        if (!ga.placement) continue;
        ++hitsOnInstances;
        ++compared;
        EXPECT_LT(Diff(Vec3(a.n), Vec3(b.n)), 1e-9) << i;
        EXPECT_LT(Diff(Vec3(a.shading.n), Vec3(b.shading.n)), 1e-9) << i;
        EXPECT_LT(std::abs(a.uv.x - b.uv.x) + std::abs(a.uv.y - b.uv.y), 1e-9) << i;
        EXPECT_LT(Diff(a.dpdu, b.dpdu), 1e-9 * (1 + b.dpdu.length())) << i;
        EXPECT_LT(Diff(a.dpdv, b.dpdv), 1e-9 * (1 + b.dpdv.length())) << i;
        EXPECT_LT(Diff(a.shading.dpdu, b.shading.dpdu), 1e-9 * (1 + b.shading.dpdu.length())) << i;
        EXPECT_LT(Diff(Vec3(a.shading.dndu), Vec3(b.shading.dndu)), 1e-9 * (1 + b.shading.dndu.length())) << i;
        EXPECT_LT(Diff(Vec3(a.shading.dndv), Vec3(b.shading.dndv)), 1e-9 * (1 + b.shading.dndv.length())) << i;
        ASSERT_TRUE(ga.mesh && b.geomId >= 0 && flat->geometry[b.geomId].mesh);
        EXPECT_EQ(a.primId, b.primId);
        // Rebuild from (record, triangle, barycentrics): the corners are placed.
        Point3 c[3];
        ga.triangleCorners(a.primId, c);
        const Vec3 e1 = c[1] - c[0], e2 = c[2] - c[0], q = a.p - c[0];
        const Float d11 = Dot(e1, e1), d12 = Dot(e1, e2), d22 = Dot(e2, e2), den = d11 * d22 - d12 * d12;
        const Float b1 = (d22 * Dot(q, e1) - d12 * Dot(q, e2)) / den, b2 = (d11 * Dot(q, e2) - d12 * Dot(q, e1)) / den;
        SurfaceInteraction re;
        ga.meshInteraction(a.primId, b1, b2, a.wo, &re);
        EXPECT_LT(Diff(re.p - a.p, Vec3(0, 0, 0)), 1e-9) << i;
        EXPECT_LT(Diff(Vec3(re.shading.n), Vec3(a.shading.n)), 1e-9) << i;
    }
    EXPECT_GT(hitsOnInstances, 1000);  // the test looks at instances, not only walls
    EXPECT_LT(differentSurface, n / 500);
    EXPECT_LT(occlusionMismatch, n / 500);
    std::printf("compared %d instance hits; %d rays met another surface, %d shadow rays disagreed\n", compared,
                differentSurface, occlusionMismatch);
}

// Rendering: the two scenes give the same image up to the paths that meet a
// float-precision edge differently (same seed, same sampler): path, bdpt and
// gbdpt (whose shifts rebuild stored vertices from their records). path's
// default spatial light sampler is built over the scene's bounds, which are
// looser with instances (placed object boxes): it renders with "power" here.
TEST(Instancing, RendersEqualTheFlattenedScene) {
    for (const char *line : {"Integrator \"path\" \"string lightsamplestrategy\" \"power\"", "Integrator \"bdpt\"",
                             "Integrator \"gbdpt\""}) {
        const std::string integrator = line;
        auto a = test::RenderSceneText(SceneText(InstancedWorld(), line), 8, 3, 2);
        auto b = test::RenderSceneText(SceneText(FlatWorld(), line), 8, 3, 2);
        ASSERT_EQ(a.image.width(), b.image.width());
        double sa = 0, sb = 0;
        int differing = 0, pixels = a.image.width() * a.image.height();
        for (int y = 0; y < a.image.height(); ++y)
            for (int x = 0; x < a.image.width(); ++x) {
                bool same = true;
                for (int c = 0; c < 3; ++c) {
                    const double va = a.image.at(x, y, c), vb = b.image.at(x, y, c);
                    sa += va;
                    sb += vb;
                    same = same && std::abs(va - vb) <= 1e-4 * (std::abs(vb) + 1e-3);
                }
                differing += !same;
            }
        EXPECT_LT(differing, pixels / 20) << integrator;
        EXPECT_NEAR(sa / sb, 1.0, 2e-3) << integrator;
        std::printf("%s: %d of %d pixels differ, mean ratio %.6f\n", line, differing, pixels, sa / sb);
    }
}

TEST(Instancing, ObjectUsedOnceIsFlattened) {
    std::string w = Room() + "AttributeBegin\nObjectBegin \"thing\"\n" + kObjectShapes + "ObjectEnd\nAttributeEnd\n" +
                    "AttributeBegin\n" + kUses[1] + "\nObjectInstance \"thing\"\nAttributeEnd\n";
    auto s = Build(w);
    EXPECT_EQ(s->features.numInstances, 0);
    for (const GeometryRecord &g : s->geometry) EXPECT_EQ(g.placement, nullptr);
}

TEST(Instancing, HugeInstanceTransformIsLocatedError) {
    std::string w = Room() + "AttributeBegin\nObjectBegin \"thing\"\n" + kObjectShapes + "ObjectEnd\nAttributeEnd\n" +
                    "ObjectInstance \"thing\"\nAttributeBegin\nScale 1e20 1e20 1e20\nObjectInstance \"thing\"\n"
                    "AttributeEnd\n";
    try {
        Build(w);
        FAIL() << "no error";
    } catch (const Error &e) {
        const std::string what = e.what();
        // Line of the second ObjectInstance: header lines + world lines before it.
        const std::string text = SceneText(w);
        const size_t at = text.find("Scale 1e20");
        const int line = 2 + int(std::count(text.begin(), text.begin() + long(at), '\n'));
        EXPECT_NE(what.find("test.pbrt:" + std::to_string(line)), std::string::npos) << what;
    }
}

}  // namespace
}  // namespace gradus
