// What the manifold walk is fed on real geometry (EmbreeManifoldScene over
// triangle meshes with per-vertex normals) against finite differences:
//   - the derivative of the unit shading normal along a vertex's motion axes
//     (ManifoldVertex::dnds/dndt), on tessellated spheres under a uniform scale
//     of 0.09 and a non-uniform scale (1, 1.5, 1), and on the shared scenes' meshes
//     (water-caustic's water, veach-ajar's meshes) when ../shared is present;
//   - the chain derivative dx_1/dx_end (FirstVertexDerivative) against re-traced
//     chains through a tessellated glass sphere under both scales and through
//     water-caustic's water surface.
// Before the unit-normal derivatives (shading.dnhatdu), the walk received the
// derivative of the interpolated, unnormalised vertex normal. Each test also
// runs that derivative ("legacy") and requires it to fail; largest relative
// errors measured, old vs new: tessellated sphere normals 10.2 vs 4e-10 (scale
// 0.09) and 0.46 vs 4e-10 (1, 1.5, 1); its chains 497 vs 5e-9 and 123 vs 1.5e-5;
// water-caustic's and veach-ajar's mesh normals 0.61 and 1.0 (triangles with degenerate
// uv: no derivative at all) vs 1.3e-7; water-caustic chains 0.41 vs 3e-9.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "integrators/manifold/manifold.h"
#include "integrators/manifold/manifold_scene.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "samplers/rng.h"
#include "shapes/triangle.h"

using namespace gradus;

namespace {

// A UV sphere of radius 1 with unit radial per-vertex normals, as pbrt text.
std::string TessellatedSphere(int nu = 32, int nv = 16) {
    std::ostringstream P, N, idx;
    P.precision(17);
    N.precision(17);
    for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i) {
            double th = Pi * j / nv, ph = 2 * Pi * i / nu;
            double x = std::sin(th) * std::cos(ph), y = std::cos(th), z = std::sin(th) * std::sin(ph);
            P << x << " " << y << " " << z << " ";
            N << x << " " << y << " " << z << " ";
        }
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            int a = j * (nu + 1) + i, b = a + 1, c = a + nu + 1, d = c + 1;
            if (j > 0) idx << a << " " << c << " " << b << " ";
            if (j < nv - 1) idx << b << " " << c << " " << d << " ";
        }
    return "Shape \"trianglemesh\" \"point P\" [" + P.str() + "] \"normal N\" [" + N.str() +
           "] \"integer indices\" [" + idx.str() + "]\n";
}

// Glass sphere (radius 0.09 or scaled (1, 1.5, 1)) above a diffuse floor at y = -2.
std::unique_ptr<Scene> SphereScene(const std::string &scale) {
    std::string text = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                       "AttributeBegin\nMaterial \"glass\" \"float index\" 1.5\nScale " + scale + "\n" +
                       TessellatedSphere() +
                       "AttributeEnd\nMaterial \"matte\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
                       "\"point P\" [-50 -2 -50 50 -2 -50 50 -2 50 -50 -2 50]\nWorldEnd\n";
    return BuildScene(ParseString(text, "sphere.pbrt"), Point2i{8, 8});
}

// The motion-axis normal derivatives of a mesh point, (dnds, dndt) of the walk's
// vertex, against central differences of the unit shading normal along ps and
// pt (the point moved on the triangle by barycentrics). Returns the larger
// relative error, or -1 if a difference leaves the triangle.
double NormalDerivativeError(const GeometryRecord &g, const EmbreeManifoldScene &ems, int tri, Float b1, Float b2,
                             bool legacy = false) {
    auto at = [&](Float u, Float v, SurfaceInteraction *si) {
        g.meshInteraction(tri, u, v, Vec3(0, 0, 1), si);
        si->geomId = 0;
    };
    SurfaceInteraction si;
    at(b1, b2, &si);
    ManifoldSurfacePoint sp = ems.fromInteraction(si);
    if (legacy) {  // what the walk was fed before: pbrt-v3's derivative of the unnormalised normal
        sp.dndu = Vec3(si.shading.dndu);
        sp.dndv = Vec3(si.shading.dndv);
    }
    ManifoldVertex v;
    SetupManifoldVertex(&v, sp);
    Point3 c[3];
    g.triangleCorners(tri, c);
    Vec3 e1 = c[1] - c[0], e2 = c[2] - c[0];
    double worst = 0;
    for (int axis = 0; axis < 2; ++axis) {
        const Vec3 &dir = axis == 0 ? v.ps : v.pt;
        // dir = a e1 + b e2 (dir lies in the triangle's plane).
        Float a11 = Dot(e1, e1), a12 = Dot(e1, e2), a22 = Dot(e2, e2), det = a11 * a22 - a12 * a12;
        Float r1 = Dot(e1, dir), r2 = Dot(e2, dir);
        Float a = (a22 * r1 - a12 * r2) / det, b = (a11 * r2 - a12 * r1) / det;
        Float h = 1e-4 / std::max(std::abs(a) + std::abs(b), Float(1e-12));
        Float u0 = b1 - a * h, v0 = b2 - b * h, u1 = b1 + a * h, v1 = b2 + b * h;
        for (Float x : {u0, v0, u1, v1, 1 - u0 - v0, 1 - u1 - v1})
            if (x < 0) return -1;
        SurfaceInteraction sm, spl;
        at(u0, v0, &sm);
        at(u1, v1, &spl);
        Vec3 fd = (Vec3(spl.shading.n) - Vec3(sm.shading.n)) / (2 * h);
        const Vec3 &an = axis == 0 ? v.dnds : v.dndt;
        worst = std::max(worst, double((an - fd).length() / std::max(fd.length(), Float(1e-3))));
    }
    return worst;
}

// Largest error over random interior points of random triangles of the listed
// meshes (each must have per-vertex normals).
double WorstNormalError(const Scene &scene, const std::vector<int> &geoms, int samples, bool legacy = false) {
    EmbreeManifoldScene ems(scene);
    RNG rng(7);
    double worst = 0;
    int used = 0;
    for (int i = 0; i < samples; ++i) {
        const GeometryRecord &g = scene.geometry[geoms[size_t(i) % geoms.size()]];
        int tri = std::min(int(rng.uniform() * g.mesh->numTriangles()), g.mesh->numTriangles() - 1);
        Float u = 0.1 + 0.8 * rng.uniform(), v = 0.1 + 0.8 * rng.uniform();
        if (u + v > 0.9) { u = 0.9 - u; v = 0.9 - v; u = std::max<Float>(u, 0.05); v = std::max<Float>(v, 0.05); }
        double e = NormalDerivativeError(g, ems, tri, u, v, legacy);
        if (e < 0) continue;
        worst = std::max(worst, e);
        ++used;
    }
    EXPECT_GT(used, samples / 2);
    return worst;
}

std::vector<int> MeshesWithNormals(const Scene &scene) {
    std::vector<int> ids;
    for (size_t i = 0; i < scene.geometry.size(); ++i)
        if (scene.geometry[i].mesh && !scene.geometry[i].mesh->n.empty() && scene.geometry[i].mesh->numTriangles() > 2)
            ids.push_back(int(i));
    return ids;
}

const char *kScales[] = {"0.09 0.09 0.09", "1 1.5 1"};

TEST(ManifoldMeshDerivatives, UnitNormalOnScaledTessellatedSpheres) {
    for (const char *scale : kScales) {
        auto scene = SphereScene(scale);
        std::vector<int> sphere = {0};
        ASSERT_FALSE(scene->geometry[0].mesh->n.empty());
        double now = WorstNormalError(*scene, sphere, 400);
        double before = WorstNormalError(*scene, sphere, 400, true);
        // Central differences over 1e-4 of a triangle: truncation ~1e-7 relative.
        EXPECT_LT(now, 1e-4) << scale;
        // The unnormalised derivative is off by ~1/0.09 - 1 = 10.1 and by 0.3-0.6 under (1, 1.5, 1).
        EXPECT_GT(before, 0.2) << scale;
        std::printf("scale %s: largest relative error %.3g (unnormalised derivative: %.3g)\n", scale, now, before);
    }
}

// Loop subdivision output (OpenSubdiv limit normals, unit before the transform)
// under both scales: the same mesh path, checked through the scene builder.
TEST(ManifoldMeshDerivatives, UnitNormalOnScaledLoopSubdivision) {
    for (const char *scale : kScales) {
        std::string text = std::string("LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\nScale ") + scale +
                           "\nShape \"loopsubdiv\" \"integer levels\" 3 \"point P\" [0 0 1 1 0 0 0 1 0 -1 0 0 0 -1 0 0 0 -1] "
                           "\"integer indices\" [0 1 2 0 2 3 0 3 4 0 4 1 5 2 1 5 3 2 5 4 3 5 1 4]\nWorldEnd\n";
        auto scene = BuildScene(ParseString(text, "loop.pbrt"), Point2i{8, 8});
        std::vector<int> meshes = MeshesWithNormals(*scene);
        ASSERT_EQ(meshes.size(), 1u) << scale;
        double now = WorstNormalError(*scene, meshes, 400);
        double before = WorstNormalError(*scene, meshes, 400, true);
        EXPECT_LT(now, 1e-4) << scale;
        EXPECT_GT(before, 0.1) << scale;
        std::printf("loopsubdiv, scale %s: largest relative error %.3g (unnormalised derivative: %.3g)\n", scale, now,
                    before);
    }
}

// A chain start -> glass interior vertices -> end traced from `start` along d.
bool TraceGlassChain(const EmbreeManifoldScene &ems, const ManifoldSurfacePoint &start, const Vec3 &d,
                     int glassGeom, int endGeom, int k, ManifoldChain *out) {
    ManifoldChain tmpl;
    tmpl.size = k + 2;
    SetupManifoldVertex(&tmpl.v[0], start);
    for (int i = 1; i <= k + 1; ++i) {
        ManifoldVertex &v = tmpl.v[i];
        v.sp.primitiveId = i <= k ? glassGeom : endGeom;
        v.reflect = false;
        v.specular = true;
        v.o = Vec2();
        v.frameRef = Vec3(0.36, 0.48, 0.8);
    }
    ManifoldChain traced;
    if (TraceChain(ems, start, d, tmpl, &traced) != ManifoldStatus::Success) return false;
    ManifoldSurfacePoint pts[kMaxManifoldVertices];
    bool refl[kMaxManifoldVertices] = {}, spec[kMaxManifoldVertices];
    for (int i = 0; i < traced.size; ++i) pts[i] = traced.v[i].sp;
    for (int i = 0; i < k; ++i) spec[i] = true;
    return MakeChain(pts, traced.size, refl, spec, out);
}

// dx_end/dx_1 by central differences of re-traced chains (x_1 moved along its
// motion axes by h, re-projected by the trace); false if the two step sizes
// disagree (a difference crossed a triangle edge, where shading normals kink).
bool FiniteDifferenceEndDerivative(const EmbreeManifoldScene &ems, const ManifoldChain &c, Float h, Mat2 *out) {
    auto run = [&](Float step, Mat2 *m) {
        Mat2 A, B;
        for (int axis = 0; axis < 2; ++axis) {
            const Vec3 &e = axis == 0 ? c.v[1].ps : c.v[1].pt;
            ManifoldChain cp, cm;
            auto tr = [&](Float s, ManifoldChain *o) {
                Vec3 d = Normalize(c.v[1].sp.p + e * s - c.front().sp.p);
                return TraceChain(ems, c.front().sp, d, c, o) == ManifoldStatus::Success;
            };
            if (!tr(step, &cp) || !tr(-step, &cm)) return false;
            Vec3 d1 = cp.v[1].sp.p - cm.v[1].sp.p, dE = cp.back().sp.p - cm.back().sp.p;
            Vec2 a(Dot(d1, c.v[1].ps), Dot(d1, c.v[1].pt)), b(Dot(dE, c.back().ps), Dot(dE, c.back().pt));
            if (axis == 0) { A.a = a.x; A.c = a.y; B.a = b.x; B.c = b.y; }
            else { A.b = a.x; A.d = a.y; B.b = b.x; B.d = b.y; }
        }
        *m = B * A.inverse();
        return true;
    };
    Mat2 m1, m2;
    if (!run(h, &m1) || !run(h / 4, &m2)) return false;
    if ((m1 - m2).maxAbs() > 1e-4 * m1.maxAbs()) return false;
    *out = m2;
    return true;
}

// Largest relative error of dx_end/dx_1 = (FirstVertexDerivative)^-1 over
// chains traced from `start` in random directions around `axis`.
double WorstChainError(const Scene &scene, const ManifoldSurfacePoint &start, const Vec3 &axis, Float spread,
                       int glassGeom, int endGeom, int k, Float eta, Float h, int *checked, bool legacy = false) {
    EmbreeManifoldScene ems(scene);
    ems.recordEta(glassGeom, eta);
    struct Legacy : ManifoldScene {  // feeds the walk pbrt-v3's unnormalised derivative
        const Scene &s;
        const EmbreeManifoldScene &e;
        Legacy(const Scene &s, const EmbreeManifoldScene &e) : s(s), e(e) {}
        bool intersect(const Ray &r, ManifoldSurfacePoint *hit) const override {
            Vec3 d = Normalize(r.d);
            SurfaceInteraction si;
            if (!s.intersect(Ray(r.o + d * e.epsilon(), d, r.tMax), &si)) return false;
            *hit = e.fromInteraction(si);
            hit->dndu = Vec3(si.shading.dndu);
            hit->dndv = Vec3(si.shading.dndv);
            return true;
        }
        bool visible(const Point3 &a, const Point3 &b) const override { return e.visible(a, b); }
    } legacyScene(scene, ems);
    const ManifoldScene &ms = legacy ? static_cast<const ManifoldScene &>(legacyScene) : ems;
    RNG rng(11);
    Vec3 s, t;
    CoordinateSystem(axis, &s, &t);
    double worst = 0;
    *checked = 0;
    for (int i = 0; i < 300 && *checked < 60; ++i) {
        Vec3 d = Normalize(axis + (s * (2 * rng.uniform() - 1) + t * (2 * rng.uniform() - 1)) * spread);
        ManifoldChain c;
        if (!TraceGlassChain(ems, start, d, glassGeom, endGeom, k, &c)) continue;
        // The legacy scene's chain: same points, its derivatives.
        if (legacy) {
            for (int j = 1; j < c.size; ++j) {
                ManifoldSurfacePoint hit;
                Vec3 dd = Normalize(c.v[j].sp.p - c.v[j - 1].sp.p);
                if (!ms.intersect(Ray(c.v[j - 1].sp.p, dd), &hit)) goto next;
                hit.p = c.v[j].sp.p;
                hit.etaInterior = c.v[j].sp.etaInterior;
                hit.etaExterior = c.v[j].sp.etaExterior;
                SetupManifoldVertex(&c.v[j], hit, &c.v[j].frameRef);
            }
        }
        {
            Mat2 fd, P;
            if (!FiniteDifferenceEndDerivative(ems, c, h, &fd)) continue;
            if (!FirstVertexDerivative(c, &P)) continue;
            Mat2 an = P.inverse();
            worst = std::max(worst, double((an - fd).maxAbs() / fd.maxAbs()));
            ++*checked;
        }
    next:;
    }
    return worst;
}

TEST(ManifoldMeshDerivatives, ChainThroughScaledTessellatedSpheres) {
    for (const char *scale : kScales) {
        auto scene = SphereScene(scale);
        bool small = scale[0] == '0';
        ManifoldSurfacePoint start;
        start.p = Point3(0.01, small ? 0.5 : 4, 0.02);
        start.n = Normal3(0, -1, 0);
        CoordinateSystem(Vec3(start.n), &start.dpdu, &start.dpdv);
        start.primitiveId = -1;
        Float spread = small ? 0.12 : 0.18;
        int checked = 0, checkedLegacy = 0;
        double now = WorstChainError(*scene, start, Vec3(0, -1, 0), spread, 0, 1, 2, 1.5, 1e-6, &checked);
        double before = WorstChainError(*scene, start, Vec3(0, -1, 0), spread, 0, 1, 2, 1.5, 1e-6, &checkedLegacy, true);
        EXPECT_GE(checked, 30) << scale;
        EXPECT_LT(now, 2e-3) << scale;
        EXPECT_GT(before, 0.1) << scale;
        std::printf("scale %s: %d chains, largest relative error %.3g (unnormalised derivative: %.3g)\n", scale, checked,
                    now, before);
    }
}

std::string SharedScene(const char *rel) {
    std::string f = std::string(GRADUS_SOURCE_DIR) + "/../shared/scenes/" + rel;
    return std::filesystem::exists(f) ? f : std::string();
}

TEST(ManifoldMeshDerivatives, SharedScenesMeshes) {
    bool any = false;
    for (const char *rel : {"water-caustic/scene.pbrt", "veach-ajar/scene.pbrt"}) {
        std::string f = SharedScene(rel);
        if (f.empty()) continue;
        any = true;
        auto scene = BuildScene(ParseFile(f), Point2i{16, 16});
        std::vector<int> meshes = MeshesWithNormals(*scene);
        ASSERT_FALSE(meshes.empty()) << rel;
        double now = WorstNormalError(*scene, meshes, 2000);
        double before = WorstNormalError(*scene, meshes, 2000, true);
        EXPECT_LT(now, 1e-3) << rel;
        EXPECT_GT(before, 0.05) << rel;
        std::printf("%s: %zu meshes, largest relative error %.3g (unnormalised derivative: %.3g)\n", rel,
                    meshes.size(), now, before);
    }
    if (!any) GTEST_SKIP() << "../shared/scenes is absent";
}

// Chains light -> water surface -> floor in water-caustic (the scene of G-VCM's
// case-2 walks): the water mesh has scale (1, 1.5, 1) in the scene file.
TEST(ManifoldMeshDerivatives, SharedWaterCausticChains) {
    std::string f = SharedScene("water-caustic/scene.pbrt");
    if (f.empty()) GTEST_SKIP() << "../shared/scenes is absent";
    auto scene = BuildScene(ParseFile(f), Point2i{16, 16});
    // The water: the mesh whose material is specular; the floor: what a ray straight down meets below it.
    int water = -1;
    SurfaceInteraction si;
    ASSERT_TRUE(scene->intersect(Ray(Point3(0.05, 1.9, 0.03), Vec3(0, -1, 0)), &si));
    water = si.geomId;
    SurfaceInteraction below;
    ASSERT_TRUE(scene->intersect(Ray(si.p + Vec3(0, -1e-4, 0), Vec3(0, -1, 0)), &below));
    int floor = below.geomId;
    ASSERT_NE(water, floor);
    ManifoldSurfacePoint start;
    start.p = Point3(0.05, 1.9, 0.03);
    start.n = Normal3(0, -1, 0);
    CoordinateSystem(Vec3(start.n), &start.dpdu, &start.dpdv);
    int checked = 0, checkedLegacy = 0;
    double now = WorstChainError(*scene, start, Vec3(0, -1, 0), 0.4, water, floor, 1, 1.8, 1e-7, &checked);
    double before = WorstChainError(*scene, start, Vec3(0, -1, 0), 0.4, water, floor, 1, 1.8, 1e-7, &checkedLegacy, true);
    EXPECT_GE(checked, 30);
    EXPECT_LT(now, 2e-3);
    EXPECT_GT(before, 0.05);
    std::printf("water-caustic: %d chains, largest relative error %.3g (unnormalised derivative: %.3g)\n", checked, now,
                before);
}

}  // namespace
