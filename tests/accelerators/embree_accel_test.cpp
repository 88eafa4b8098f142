// EmbreeAccel against brute force: random triangles (two meshes), full and
// partial spheres, and instances of a two-mesh object (rotated, non-uniformly
// scaled, mirrored), all with a fixed seed. The reference is written here in
// double precision: Moller-Trumbore for triangles, the world-space quadratic
// for spheres (cut in object space by zmin, zmax, phimax). Embree traces in
// single precision, so a ray is judged only when brute force is unambiguous:
// no candidate within 1e-4 (barycentric) of a triangle's edge, of a sphere's
// cut or tangent, and the nearest hit separated from the next by more than
// the t tolerance; at least 97% of the rays must be judged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "accelerators/embree_accel.h"
#include "samplers/rng.h"
#include "shapes/sphere.h"

namespace gradus {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEdge = 1e-4;  // barycentric / relative margin below which a candidate is ambiguous
constexpr double kTolT = 1e-4;  // t agreement (scene ~10 units across, float ~1e-6 relative)

struct Candidate {
    double t;
    int geom, prim;
    bool certain;     // clearly a hit (false: too close to call)
    double b1, b2;    // triangle barycentrics
};

struct RefTriangle {
    Vec3 p[3];
    int geom, prim;
};

struct RefSphere {
    std::shared_ptr<Sphere> shape;
    Transform objectFromWorld;
    Vec3 centre;
    double radius;  // world (uniform scale)
    double zMin, zMax, phiMax;  // object space; phiMax in radians
    bool full;
    int geom;
};

// Moller-Trumbore, double precision.
void TestTriangle(const Ray &r, const RefTriangle &tri, std::vector<Candidate> *out) {
    const Vec3 e1 = tri.p[1] - tri.p[0], e2 = tri.p[2] - tri.p[0];
    const Vec3 pv = Cross(r.d, e2);
    const double det = Dot(e1, pv);
    if (std::abs(det) < 1e-12 * Cross(e1, e2).length() * r.d.length()) return;  // parallel
    const Vec3 tv = r.o - tri.p[0];
    const double u = Dot(tv, pv) / det;
    const Vec3 qv = Cross(tv, e1);
    const double v = Dot(r.d, qv) / det, t = Dot(e2, qv) / det;
    const double margin = std::min({u, v, 1 - u - v});
    if (margin < -kEdge || t <= 0) return;
    // Grazing rays: Embree's float error grows as 1 / |cos|.
    const double cosAbs = std::abs(Dot(Normalize(Cross(e1, e2)), Normalize(r.d)));
    out->push_back({t, tri.geom, tri.prim, margin > kEdge && cosAbs > 1e-3, u, v});
}

void TestSphere(const Ray &r, const RefSphere &s, std::vector<Candidate> *out) {
    const Vec3 oc = r.o - s.centre;
    const double a = Dot(r.d, r.d), b = Dot(r.d, oc);
    const Vec3 perp = oc - r.d * (b / a);  // closest approach
    const double h2 = s.radius * s.radius - perp.lengthSquared();
    if (h2 < -kEdge * s.radius * s.radius) return;
    const bool tangent = std::abs(h2) <= kEdge * s.radius * s.radius;
    const double h = std::sqrt(std::max(0.0, h2) / a);
    for (double t : {-b / a - h, -b / a + h}) {
        if (t <= 0) continue;
        bool certain = !tangent;
        if (!s.full) {
            const Vec3 q = s.objectFromWorld.applyPoint(r(t));
            const double ro = q.length();
            double phi = std::atan2(q.y, q.x);
            if (phi < 0) phi += 2 * M_PI;
            const double dz = std::min(q.z - s.zMin, s.zMax - q.z) / ro, dphi = std::min(phi, s.phiMax - phi);
            const double dphiWrap = 2 * M_PI - phi;  // phi just below 2 pi is near phi = 0
            if (dz < -kEdge || dphi < -kEdge) continue;
            if (dz < kEdge || dphi < kEdge || dphiWrap < kEdge) certain = false;
        }
        out->push_back({t, s.geom, 0, certain, 0, 0});
    }
}

struct RefScene {
    std::vector<RefTriangle> tris;
    std::vector<RefSphere> spheres;
    std::vector<Candidate> candidates(const Ray &r) const {
        std::vector<Candidate> c;
        for (const auto &t : tris) TestTriangle(r, t, &c);
        for (const auto &s : spheres) TestSphere(r, s, &c);
        std::sort(c.begin(), c.end(), [](const Candidate &a, const Candidate &b) { return a.t < b.t; });
        return c;
    }
};

// The expected closest hit below tMax; false when ambiguous. *best = nullptr: none.
bool Decide(const std::vector<Candidate> &c, double tMax, const Candidate **best) {
    *best = nullptr;
    for (size_t i = 0; i < c.size(); ++i) {
        if (c[i].t >= tMax + kTolT) break;
        if (!c[i].certain || std::abs(c[i].t - tMax) < kTolT) return false;
        if (i + 1 < c.size() && c[i + 1].t < c[i].t + kTolT) return false;  // a near tie
        *best = &c[i];
        return true;
    }
    return true;
}

Vec3 RandomIn(RNG &rng, double lo, double hi) {
    return Vec3(lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform());
}

Vec3 RandomDirection(RNG &rng) {
    const double z = 2 * rng.uniform() - 1, phi = 2 * M_PI * rng.uniform(), s = std::sqrt(1 - z * z);
    return Vec3(s * std::cos(phi), s * std::sin(phi), z);
}

// Random triangles around random centres in [-4, 4]^3 (as one mesh).
std::shared_ptr<TriangleMesh> RandomMesh(RNG &rng, int n, double size, const Transform &xf = Transform()) {
    std::vector<Point3> P;
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) {
        const Vec3 c = RandomIn(rng, -4, 4);
        for (int k = 0; k < 3; ++k) {
            idx.push_back(int(P.size()));
            P.push_back(c + RandomIn(rng, -size, size));
        }
    }
    return TriangleMesh::Create(xf, false, P, idx, {}, {}, {}, FileLoc());
}

void AddMeshReference(const TriangleMesh &m, int geom, const Transform &worldFromMesh, RefScene *ref) {
    for (int i = 0; i < m.numTriangles(); ++i) {
        RefTriangle t;
        for (int k = 0; k < 3; ++k) t.p[k] = worldFromMesh.applyPoint(m.p[size_t(m.indices[size_t(3 * i + k)])]);
        t.geom = geom;
        t.prim = i;
        ref->tris.push_back(t);
    }
}

// The world scene: two meshes, six full spheres, four partial ones under rotations.
void BuildWorld(EmbreeAccel *accel, RefScene *ref, RNG &rng) {
    for (int m = 0; m < 2; ++m) {
        auto mesh = RandomMesh(rng, m == 0 ? 150 : 40, m == 0 ? 1.0 : 2.5);
        AddMeshReference(*mesh, accel->addMesh(mesh), Transform(), ref);
    }
    for (int i = 0; i < 10; ++i) {
        const bool full = i < 6;
        const Vec3 c = RandomIn(rng, -4, 4);
        const double r = 0.4 + 0.6 * rng.uniform(), scale = 0.5 + rng.uniform();
        const Transform xf = Translate(c) * Rotate(360 * rng.uniform(), RandomDirection(rng)) * Scale(scale, scale, scale);
        const double zMin = full ? -r : -r + 0.5 * r * rng.uniform(), zMax = full ? r : r - 0.5 * r * rng.uniform();
        const double phiMaxDeg = full ? 360 : 120 + 200 * rng.uniform();
        auto s = std::make_shared<Sphere>(xf, false, r, zMin, zMax, phiMaxDeg);
        ASSERT_EQ(s->isFull(), full);
        RefSphere rs{s, xf.inverse(), c, r * scale, zMin, zMax, phiMaxDeg * M_PI / 180, full, accel->addSphere(s)};
        ref->spheres.push_back(rs);
    }
}

// Rays from outside the scene aimed into it, and from inside in any direction.
Ray RandomRay(RNG &rng, int k) {
    if (k % 2 == 0) {
        const Vec3 o = RandomDirection(rng) * 12;
        return Ray(o, Normalize(RandomIn(rng, -4, 4) - o));
    }
    return Ray(RandomIn(rng, -4.5, 4.5), RandomDirection(rng));
}

void ExpectHitIs(const RayHit &h, const Candidate &c, const Ray &r, const RefScene &ref) {
    EXPECT_EQ(h.geomId, c.geom);
    EXPECT_EQ(h.primId, c.prim);
    EXPECT_NEAR(h.t, c.t, kTolT);
    if (h.geomId != c.geom || h.primId != c.prim) return;
    for (const RefTriangle &t : ref.tris)
        if (t.geom == c.geom && t.prim == c.prim) {
            // Embree's barycentrics place the hit point: (1 - b1 - b2) p0 + b1 p1 + b2 p2 = r(t).
            // They are single precision (the renderer refines them): 1e-3.
            EXPECT_NEAR(h.b1, c.b1, 1e-3);
            EXPECT_NEAR(h.b2, c.b2, 1e-3);
            const Vec3 p = t.p[0] * (1 - h.b1 - h.b2) + t.p[1] * h.b1 + t.p[2] * h.b2;
            EXPECT_LT((p - r(h.t)).length(), 1e-3);
        }
}

TEST(EmbreeAccel, ClosestHitsMatchBruteForce) {
    RNG rng(31);
    EmbreeAccel accel;
    RefScene ref;
    BuildWorld(&accel, &ref, rng);
    accel.commit();
    EXPECT_EQ(accel.recordCount(), 12);
    const int n = 10000;
    int judged = 0, hits = 0, sphereHits = 0, partialHits = 0;
    for (int k = 0; k < n; ++k) {
        const Ray r = RandomRay(rng, k);
        const auto c = ref.candidates(r);
        const Candidate *best;
        if (!Decide(c, kInf, &best)) continue;
        ++judged;
        RayHit h;
        const bool hit = accel.intersect(r, &h);
        ASSERT_EQ(hit, best != nullptr) << "ray " << k << (hit ? " hit geom " + std::to_string(h.geomId) : " missed");
        if (!hit) continue;
        ++hits;
        sphereHits += best->geom >= 2;
        partialHits += best->geom >= 8;
        ExpectHitIs(h, *best, r, ref);
    }
    EXPECT_GE(judged, 0.97 * n);
    EXPECT_GT(hits, n / 3);
    EXPECT_GT(n - hits, n / 10);
    EXPECT_GT(sphereHits, 1000);
    EXPECT_GT(partialHits, 250);
}

// Shadow rays with random lengths; and each judged hit at t re-traced with
// tMax = t (1 -+ 1e-4): before it nothing (it was the closest), after it that hit.
TEST(EmbreeAccel, OcclusionAndTMaxMatchBruteForce) {
    RNG rng(32);
    EmbreeAccel accel;
    RefScene ref;
    BuildWorld(&accel, &ref, rng);
    accel.commit();
    const int n = 10000;
    int judged = 0, blocked = 0, edges = 0;
    for (int k = 0; k < n; ++k) {
        Ray r = RandomRay(rng, k);
        const auto c = ref.candidates(r);
        r.tMax = 16 * rng.uniform();
        const Candidate *best;
        if (Decide(c, r.tMax, &best)) {
            ++judged;
            blocked += best != nullptr;
            EXPECT_EQ(accel.occluded(r), best != nullptr) << "ray " << k;
            RayHit h;
            EXPECT_EQ(accel.intersect(r, &h), best != nullptr) << "ray " << k;
        }
        // Just before and just after the closest hit.
        if (!Decide(c, kInf, &best) || !best) continue;
        const double t = best->t, d = 1e-4 * std::max(1.0, t);
        if (t < 10 * d) continue;
        const Candidate *ignored;
        if (!Decide(c, t - d, &ignored) || !Decide(c, t + d, &ignored)) continue;
        ++edges;
        RayHit h;
        EXPECT_FALSE(accel.intersect(Ray(r.o, r.d, t - d), &h)) << "ray " << k << " t " << t;
        EXPECT_FALSE(accel.occluded(Ray(r.o, r.d, t - d))) << "ray " << k << " t " << t;
        ASSERT_TRUE(accel.intersect(Ray(r.o, r.d, t + d), &h)) << "ray " << k << " t " << t;
        ExpectHitIs(h, *best, r, ref);
        EXPECT_TRUE(accel.occluded(Ray(r.o, r.d, t + d))) << "ray " << k << " t " << t;
    }
    EXPECT_GE(judged, 0.97 * n);
    EXPECT_GT(blocked, n / 5);
    EXPECT_GT(judged - blocked, n / 5);
    EXPECT_GT(edges, n / 3);
}

// Object instances: one object of two meshes (object space) used three times
// (rotation; non-uniform scale; mirror), beside a world mesh. Record ids:
// addInstance's return value plus the mesh's index in the object.
TEST(EmbreeAccel, InstancesMatchBruteForce) {
    RNG rng(33);
    EmbreeAccel accel;
    RefScene ref;
    auto world = RandomMesh(rng, 60, 1.0);
    AddMeshReference(*world, accel.addMesh(world), Transform(), &ref);
    const int obj = accel.newObject();
    std::shared_ptr<TriangleMesh> parts[2] = {RandomMesh(rng, 40, 0.8, Scale(0.6, 0.6, 0.6)),
                                              RandomMesh(rng, 15, 1.2, Scale(0.5, 0.5, 0.5))};
    for (auto &m : parts) accel.addObjectMesh(obj, m);
    EXPECT_EQ(accel.objectMeshCount(obj), 2);
    const Transform uses[3] = {Translate(Vec3(-2, 1, 0.5)) * Rotate(35, Vec3(1, 1, 0)),
                               Translate(Vec3(2, -1, 1)) * Rotate(-60, Vec3(0, 0.3, 1)) * Scale(1.6, 0.5, 1.1),
                               Translate(Vec3(0.5, 2, -2)) * Scale(-1, 1, 1) * Rotate(70, Vec3(0, 1, 0))};
    for (const Transform &xf : uses) {
        const int first = accel.addInstance(obj, xf);
        for (int m = 0; m < 2; ++m) AddMeshReference(*parts[m], first + m, xf, &ref);
    }
    accel.commit();
    EXPECT_EQ(accel.recordCount(), 1 + 3 * 2);
    const int n = 10000;
    int judged = 0, instanceHits = 0;
    std::vector<int> perRecord(7, 0);
    for (int k = 0; k < n; ++k) {
        Ray r = RandomRay(rng, k);
        const auto c = ref.candidates(r);
        const Candidate *best;
        if (!Decide(c, kInf, &best)) continue;
        ++judged;
        RayHit h;
        const bool hit = accel.intersect(r, &h);
        ASSERT_EQ(hit, best != nullptr) << "ray " << k;
        if (hit) {
            ExpectHitIs(h, *best, r, ref);
            instanceHits += best->geom > 0;
            ++perRecord[size_t(best->geom)];
        }
        r.tMax = hit ? h.t * 0.999 : kInf;
        EXPECT_FALSE(accel.occluded(r)) << "ray " << k;
        if (hit) {
            r.tMax = h.t * 1.001;
            EXPECT_TRUE(accel.occluded(r)) << "ray " << k;
        }
    }
    EXPECT_GE(judged, 0.97 * n);
    EXPECT_GT(instanceHits, 500);
    for (int g = 0; g < 7; ++g) EXPECT_GT(perRecord[size_t(g)], 50) << "record " << g;
}

// Directions of any length: t is in units of the given direction, tMax too
// (the accelerator rescales directions outside [1e-8, 1e8] for Embree).
TEST(EmbreeAccel, TIsInUnitsOfTheRayDirection) {
    RNG rng(34);
    EmbreeAccel accel;
    RefScene ref;
    BuildWorld(&accel, &ref, rng);
    accel.commit();
    int tested = 0;
    for (int k = 0; k < 400; ++k) {
        const Ray r = RandomRay(rng, k);
        const auto c = ref.candidates(r);
        const Candidate *best;
        if (!Decide(c, kInf, &best) || !best) continue;
        ++tested;
        for (double s : {1e-12, 1e-6, 0.37, 5e3, 1e10}) {
            RayHit h;
            ASSERT_TRUE(accel.intersect(Ray(r.o, r.d * s), &h)) << s;
            EXPECT_EQ(h.geomId, best->geom);
            EXPECT_NEAR(h.t * s, best->t, kTolT) << s;
            EXPECT_FALSE(accel.occluded(Ray(r.o, r.d * s, best->t * (1 - 1e-4) / s))) << s;
            EXPECT_TRUE(accel.occluded(Ray(r.o, r.d * s, best->t * (1 + 1e-4) / s))) << s;
        }
    }
    EXPECT_GT(tested, 100);
}

// Rays Embree cannot trace (non-finite or zero direction, non-finite origin)
// are dropped: a miss for closest hits, blocked for shadow rays (documented).
TEST(EmbreeAccel, UntraceableRaysAreDropped) {
    RNG rng(35);
    EmbreeAccel accel;
    RefScene ref;
    BuildWorld(&accel, &ref, rng);
    accel.commit();
    const double nan = std::nan("");
    for (const Ray &r : {Ray(Vec3(0, 0, -20), Vec3(0, 0, 0)), Ray(Vec3(0, 0, -20), Vec3(nan, 0, 1)),
                         Ray(Vec3(nan, 0, -20), Vec3(0, 0, 1)), Ray(Vec3(0, 0, -20), Vec3(0, kInf, 1)),
                         Ray(Vec3(0, 0, -20), Vec3(0, 0, 1), nan)}) {
        RayHit h;
        EXPECT_FALSE(accel.intersect(r, &h));
        EXPECT_TRUE(accel.occluded(r));
    }
}

}  // namespace
}  // namespace gradus
