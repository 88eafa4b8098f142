// Analytic shapes against brute-force answers: intersections (ray marching on
// the implicit surface), closed-form areas, area/solid-angle pdfs that
// integrate to the visible fraction, chi-square of sampled directions, and
// pbrt-v3 normal orientation under ReverseOrientation and mirror transforms.
#include <gtest/gtest.h>

#include "common/chi2_test.h"
#include "samplers/rng.h"
#include "shape_cases.h"
#include "shapes/triangle.h"

namespace gradus {
namespace {

using test::AnalyticCase;
using test::AnalyticCases;

// A rigid motion with uniform scale (keeps closed-form areas exact).
Transform Similarity() { return Translate(Vec3(0.3, -0.2, 0.5)) * Rotate(37, Vec3(1, 2, 0.5)) * Scale(1.5, 1.5, 1.5); }

// Brute force: first t in (0, tMax) where F changes sign along the object ray
// and the point is in the shape's domain (marching, then bisection).
bool BruteForceHit(const AnalyticCase &c, const Ray &r, Float tMax, Float *tHit, int steps = 20000) {
    Float h = tMax / steps;
    Float f0 = c.F(r.o);
    for (int i = 1; i <= steps; ++i) {
        Float t1 = i * h, f1 = c.F(r(t1));
        if ((f0 < 0) != (f1 < 0)) {
            Float a = t1 - h, b = t1, fa = f0;
            for (int k = 0; k < 80; ++k) {
                Float m = 0.5 * (a + b), fm = c.F(r(m));
                if ((fm < 0) == (fa < 0)) a = m, fa = fm;
                else b = m;
            }
            Float t = 0.5 * (a + b);
            if (t > 1e-9 && c.inDomain(r(t))) {
                *tHit = t;
                return true;
            }
        }
        f0 = f1;
    }
    return false;
}

TEST(AnalyticShapes, IntersectionMatchesBruteForce) {
    for (const AnalyticCase &c : AnalyticCases()) {
        for (int xf = 0; xf < 2; ++xf) {
            Transform w = xf ? Similarity() : Transform();
            auto shape = c.make(w, false);
            Transform objFromWorld = w.inverse();
            Bounds3 ob = shape->objectBound();
            RNG rng(7 + xf);
            int hits = 0, mismatches = 0;
            for (int i = 0; i < 400; ++i) {
                // World ray from a random point towards a random point of the object bounds.
                Point3 oObj(rng.uniform() * 6 - 3, rng.uniform() * 6 - 3, rng.uniform() * 6 - 3);
                Point3 target(Lerp(rng.uniform(), ob.pMin.x, ob.pMax.x), Lerp(rng.uniform(), ob.pMin.y, ob.pMax.y),
                              Lerp(rng.uniform(), ob.pMin.z, ob.pMax.z));
                Ray world(w.applyPoint(oObj), Normalize(w.applyVector(target - oObj)));
                Ray obj = objFromWorld.applyRay(world);
                Float tShape, tBrute;
                Interaction it;
                bool a = shape->intersectP(world, &tShape, &it);
                bool b = BruteForceHit(c, obj, 12 / obj.d.length(), &tBrute);
                if (a) ++hits;
                if (a && b && std::abs(tShape - tBrute) < 1e-6 * (1 + tBrute)) continue;
                if (!a && !b) continue;
                // Two roots within one marching step (grazing ray) are invisible to brute force.
                if (a && !b) {
                    Float step = 12 / obj.d.length() / 20000;
                    if ((c.F(obj(tShape - step)) < 0) == (c.F(obj(tShape + step)) < 0)) continue;
                }
                ++mismatches;
                ADD_FAILURE() << c.name << " xf " << xf << " ray " << i << ": shape " << a << " t=" << tShape
                              << ", brute force " << b << " t=" << tBrute;
            }
            EXPECT_EQ(mismatches, 0) << c.name;
            EXPECT_GT(hits, 40) << c.name << ": too few hits to test anything";
        }
    }
}

TEST(AnalyticShapes, AreaMatchesClosedForm) {
    for (const AnalyticCase &c : AnalyticCases()) {
        EXPECT_NEAR(c.make(Transform(), false)->area(), c.area, 1e-6 * c.area) << c.name;
        // Uniform scale s multiplies the area by s^2.
        EXPECT_NEAR(c.make(Similarity(), false)->area(), 2.25 * c.area, 1e-6 * c.area) << c.name;
    }
}

// Sampled points lie on the surface, inside the domain, with pdf 1/area.
TEST(AnalyticShapes, AreaSamplesOnSurface) {
    for (const AnalyticCase &c : AnalyticCases()) {
        auto shape = c.make(Similarity(), false);
        Transform objFromWorld = Similarity().inverse();
        RNG rng(3);
        for (int i = 0; i < 2000; ++i) {
            Float pdf;
            Interaction it = shape->sampleArea(Point2(rng.uniform(), rng.uniform()), &pdf);
            Point3 p = objFromWorld.applyPoint(it.p);
            ASSERT_NEAR(c.F(p), 0, 1e-9) << c.name;
            ASSERT_TRUE(c.inDomain(p) || c.inDomain(p * (1 + 1e-12))) << c.name << " " << p;
            ASSERT_NEAR(pdf, 1 / shape->area(), 1e-9 / shape->area()) << c.name;
            ASSERT_NEAR(shape->pdfArea(it), pdf, 1e-9 * pdf) << c.name;
        }
    }
}

TEST(AnalyticShapes, NonUniformScaleAreaPdf) {
    // Under a non-uniform scale the area density varies over the surface; its
    // integral over the surface must still be 1: E_uniform-param[1/pdf] = area.
    for (const AnalyticCase &c : AnalyticCases()) {
        Transform w = Scale(1, 2.5, 0.7);
        auto shape = c.make(w, false);
        RNG rng(11);
        // Importance-sampled estimate of the world area: E[1 / pdf] over samples.
        double sum = 0, sum2 = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i) {
            Float pdf;
            shape->sampleArea(Point2(rng.uniform(), rng.uniform()), &pdf);
            ASSERT_GT(pdf, 0) << c.name;
            sum += 1 / pdf;
            sum2 += 1 / (pdf * pdf);
        }
        double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
        // Reference world area from the parameterisation: Monte Carlo over a fine
        // stratified grid of sampled points would be circular; use the identity
        // transform's pdf scaled by the exact per-point Jacobian instead.
        auto ref = c.make(Transform(), false);
        double sumRef = 0;
        RNG rng2(12);
        for (int i = 0; i < n; ++i) {
            Float pdf;
            Interaction it = ref->sampleArea(Point2(rng2.uniform(), rng2.uniform()), &pdf);
            Normal3 nObj = Normalize(it.n);
            Vec3 a = w.applyVector(Vec3(1, 0, 0)), b = w.applyVector(Vec3(0, 1, 0)), cc = w.applyVector(Vec3(0, 0, 1));
            double det = std::abs(Dot(a, Cross(b, cc)));
            sumRef += det * w.applyNormal(nObj).length() / pdf;  // Nanson's formula
        }
        double refArea = sumRef / n;
        EXPECT_NEAR(mean, refArea, 5 * se + 5e-3 * refArea) << c.name;
    }
}

// All hits of a world ray on one shape, nearest first.
std::vector<Interaction> AllHits(const Shape &s, Point3 o, const Vec3 &w) {
    std::vector<Interaction> out;
    for (int k = 0; k < 6; ++k) {
        Float t;
        Interaction it;
        if (!s.intersectP(Ray(o, w), &t, &it)) break;
        out.push_back(it);
        o = it.p + w * (1e-9 * (1 + MaxComponent(Abs(it.p))));
    }
    return out;
}

struct RefCase {
    Point3 p;
    bool coneSampled;  // full sphere seen from outside: uniform cone of directions
};

// Reference points without grazing lines of sight (bounded pdfs, suited to
// chi-square binning); a full sphere is also seen from outside (cone sampling).
std::vector<RefCase> RefPoints(const AnalyticCase &c, const Transform &w) {
    std::vector<RefCase> r = {{w.applyPoint(c.inside), false}};
    if (c.name == "sphere_full") r.push_back({w.applyPoint(Point3(2.0, -1.5, 1.2)), true});
    return r;
}

// Direction density of sampleFrom() at ref: cone pdf, or the area pdf summed
// over every point of the shape along w (area sampling can pick hidden points).
Float DirectionDensity(const Shape &s, const RefCase &r, const Vec3 &w) {
    Interaction ref(r.p, Normal3(0, 0, 0), Vec3(0, 0, 0));
    if (r.coneSampled) return s.pdfFrom(ref, w);
    Float sum = 0;
    for (const Interaction &h : AllHits(s, r.p, w)) {
        Float cosL = AbsDot(h.n, w);
        if (cosL > 0) sum += s.pdfArea(h) * DistanceSquared(r.p, h.p) / cosL;
    }
    return sum;
}

TEST(AnalyticShapes, SampledDirectionsChiSquare) {
    auto cases = AnalyticCases();
    const double alpha = chi2::SidakAlpha(0.01, int(cases.size()) + 1);
    for (const AnalyticCase &c : cases) {
        auto shape = c.make(Similarity(), false);
        for (const RefCase &rc : RefPoints(c, Similarity())) {
            // Cone-sampled directions are binned in the cone's own frame so the
            // cone boundary is a circle of constant cos(theta).
            Frame frame = rc.coneSampled
                              ? Frame(Normalize(Similarity().applyPoint(Point3(0, 0, 0)) - rc.p))
                              : Frame();
            Interaction ref(rc.p, Normal3(0, 0, 0), Vec3(0, 0, 0));
            chi2::Options o;
            o.xBins = 16;
            o.yBins = 32;
            o.samples = 50000;
            o.subdivisions = 32;
            o.alpha = alpha;
            auto r = test::DirectionalChi2(
                [&](RNG &rng, Vec3 *w) {
                    Float pdf;
                    Interaction it = shape->sampleFrom(ref, Point2(rng.uniform(), rng.uniform()), &pdf);
                    if (pdf == 0) return false;
                    *w = frame.toLocal(Normalize(it.p - rc.p));
                    return true;
                },
                [&](const Vec3 &w) { return DirectionDensity(*shape, rc, frame.toWorld(w)); }, o);
            EXPECT_TRUE(r.pass) << c.name << " from " << rc.p << ": " << r.message;
        }
    }
}

// pdfFrom() integrated over all directions equals the probability that
// sampleFrom() returns the point a ray from ref sees first (1 when nothing of
// the shape hides other parts of it).
TEST(AnalyticShapes, SolidAnglePdfIntegratesToVisibleFraction) {
    for (const AnalyticCase &c : AnalyticCases()) {
        auto shape = c.make(Similarity(), false);
        auto refs = RefPoints(c, Similarity());
        refs.push_back({Similarity().applyPoint(Point3(2.2, 1.3, 0.35)), c.name == "sphere_full"});  // outside
        for (const RefCase &rc : refs) {
            Interaction ref(rc.p, Normal3(0, 0, 0), Vec3(0, 0, 0));
            RNG rng(5);
            const int n = 100000;
            int visible = 0;
            for (int i = 0; i < n; ++i) {
                Float pdf;
                Interaction it = shape->sampleFrom(ref, Point2(rng.uniform(), rng.uniform()), &pdf);
                if (pdf == 0) continue;
                Vec3 w = Normalize(it.p - rc.p);
                Float t;
                Interaction first;
                if (shape->intersectP(Ray(rc.p, w), &t, &first) &&
                    Distance(first.p, it.p) < 1e-6 * (1 + Distance(rc.p, it.p)))
                    ++visible;
            }
            double frac = double(visible) / n, seFrac = std::sqrt(frac * (1 - frac) / n);
            // Stratified quadrature of pdfFrom over the sphere in (cos theta, phi).
            const int nc = 500, np = 1000;
            double integral = 0;
            RNG rq(9);
            for (int i = 0; i < nc; ++i)
                for (int j = 0; j < np; ++j) {
                    Float cz = -1 + 2 * (i + rq.uniform()) / nc, phi = 2 * Pi * (j + rq.uniform()) / np;
                    integral += shape->pdfFrom(ref, SphericalDirection(SafeSqrt(1 - cz * cz), cz, phi));
                }
            integral *= 4 * Pi / (double(nc) * np);
            EXPECT_NEAR(integral, frac, 4 * seFrac + 0.01) << c.name << " from " << rc.p;
        }
    }
}

// pbrt-v3 orientation: object normal Cross(dpdu, dpdv) carried as a normal,
// flipped when ReverseOrientation XOR the transform swaps handedness. All of
// sampleArea(), intersectP() and interaction() agree.
TEST(AnalyticShapes, NormalOrientation) {
    for (const AnalyticCase &c : AnalyticCases()) {
        for (int ro = 0; ro < 2; ++ro)
            for (int mirror = 0; mirror < 2; ++mirror) {
                Transform w = Similarity() * (mirror ? Scale(-1, 1, 1) : Transform());
                ASSERT_EQ(w.swapsHandedness(), bool(mirror));
                auto shape = c.make(w, ro);
                Transform objFromWorld = w.inverse();
                Float sign = (ro ^ mirror) ? -1 : 1;
                RNG rng(17);
                for (int i = 0; i < 200; ++i) {
                    Float pdf;
                    Interaction s = shape->sampleArea(Point2(rng.uniform(), rng.uniform()), &pdf);
                    Point3 pObj = objFromWorld.applyPoint(s.p);
                    Vec3 expected = Normalize(w.applyNormal(c.normal(pObj))) * sign;
                    ASSERT_GT(Dot(s.n, expected), 0.999) << c.name << " ro " << ro << " mirror " << mirror;
                    // Hit the same point with a ray along the expected normal.
                    Point3 o = s.p + expected * 1e-3;
                    Ray ray(o, -expected);
                    Float t;
                    Interaction hit;
                    ASSERT_TRUE(shape->intersectP(ray, &t, &hit)) << c.name;
                    ASSERT_GT(Dot(hit.n, expected), 0.999) << c.name;
                    SurfaceInteraction si;
                    shape->interaction(ray, t, &si);
                    ASSERT_GT(Dot(si.n, expected), 0.999) << c.name;
                    ASSERT_GT(Dot(si.shading.n, expected), 0.999) << c.name;
                    // n agrees with the world-space partial derivatives up to the pbrt-v3 flips.
                    // (Cross(dpdu, dpdv) of world derivatives already flips with the mirror.)
                    Vec3 cr = Normalize(Cross(si.dpdu, si.dpdv)) * (ro ? -1 : 1);
                    ASSERT_GT(Dot(cr, si.n), 0.999) << c.name;
                    ASSERT_GE(si.uv.x, -1e-9);
                    ASSERT_LE(si.uv.x, 1 + 1e-9);
                    ASSERT_GE(si.uv.y, -1e-9);
                    ASSERT_LE(si.uv.y, 1 + 1e-9);
                }
            }
    }
}

// Weingarten normal derivatives match finite differences of the normal along dp/du.
TEST(AnalyticShapes, NormalDerivativesMatchFiniteDifferences) {
    for (const AnalyticCase &c : AnalyticCases()) {
        auto shape = c.make(Transform(), false);
        RNG rng(23);
        for (int i = 0; i < 50; ++i) {
            Float pdf;
            Interaction s = shape->sampleArea(Point2(0.1 + 0.8 * rng.uniform(), 0.1 + 0.8 * rng.uniform()), &pdf);
            auto at = [&](const Point3 &p, SurfaceInteraction *si) {
                Ray r(p + s.n * 1e-2, -s.n);
                Float t;
                Interaction h;
                if (!shape->intersectP(r, &t, &h)) return false;
                shape->interaction(r, t, si);
                return true;
            };
            SurfaceInteraction si, si2;
            ASSERT_TRUE(at(s.p, &si)) << c.name;
            Float e = 1e-5;
            if (!at(si.p + si.dpdu * e, &si2)) continue;
            Vec3 fd = (si2.n - si.n) / e;
            ASSERT_LT((fd - si.dndu).length(), 1e-3 * (1 + si.dndu.length())) << c.name << " at " << si.p;
        }
    }
}

// The derivatives of the unit shading normal (shading.dnhatdu/dv, what manifold
// walks use) against central differences of si.shading.n along dp/du and dp/dv,
// for every analytic shape under a uniform scale of 0.09, a non-uniform scale
// (1, 1.5, 1) after a rotation, a mirror, and with ReverseOrientation. pbrt-v3's
// si.dndu (the object-space derivative carried as a normal, which the walk got
// before) fails here: by 1/0.09 - 1 = 10.1 relative under the uniform scale, and
// with the wrong sign where the normal is flipped (checked below).
TEST(AnalyticShapes, UnitNormalDerivativesUnderTransforms) {
    const Transform xfs[] = {Scale(0.09, 0.09, 0.09), Scale(1, 1.5, 1) * Rotate(37, Vec3(1, 2, 0.5)),
                             Scale(-1, 1, 1) * Rotate(20, Vec3(0, 1, 1))};
    for (const AnalyticCase &c : AnalyticCases())
        for (const Transform &xf : xfs)
            for (bool ro : {false, true}) {
                auto shape = c.make(xf, ro);
                RNG rng(29);
                double worst = 0, worstLegacy = 0;
                int used = 0;
                for (int i = 0; i < 40; ++i) {
                    Float pdf;
                    Interaction s = shape->sampleArea(Point2(0.1 + 0.8 * rng.uniform(), 0.1 + 0.8 * rng.uniform()), &pdf);
                    Float size = std::max<Float>(1e-3, shape->worldBound().diagonal().length());
                    auto at = [&](const Point3 &p, SurfaceInteraction *si) {
                        Ray r(p + Vec3(s.n) * (1e-2 * size), -Vec3(s.n));
                        Float t;
                        Interaction h;
                        if (!shape->intersectP(r, &t, &h)) return false;
                        shape->interaction(r, t, si);
                        return true;
                    };
                    SurfaceInteraction si;
                    if (!at(s.p, &si)) continue;
                    for (int axis = 0; axis < 2; ++axis) {
                        Vec3 dp = axis == 0 ? si.dpdu : si.dpdv;
                        Float e = 1e-6 * size / std::max<Float>(dp.length(), 1e-12);
                        SurfaceInteraction sp, sm;
                        if (!at(si.p + dp * e, &sp) || !at(si.p - dp * e, &sm)) continue;
                        // Differences of points that the projection back onto the surface moved by O(e^2).
                        Vec3 fd = (Vec3(sp.shading.n) - Vec3(sm.shading.n)) / (2 * e);
                        Vec3 an(axis == 0 ? si.shading.dnhatdu : si.shading.dnhatdv);
                        Vec3 legacy(axis == 0 ? si.dndu : si.dndv);
                        Float scale = std::max<Float>(fd.length(), 1e-3 * dp.length() / size);
                        worst = std::max(worst, double((an - fd).length() / scale));
                        worstLegacy = std::max(worstLegacy, double((legacy - fd).length() / scale));
                        ++used;
                    }
                }
                ASSERT_GT(used, 20) << c.name;
                EXPECT_LT(worst, 1e-4) << c.name << " ro " << ro;
                // pbrt-v3's derivative misses 1/|M^-T n| (Disks have no curvature: 0 under any convention.)
                if (&xf == &xfs[0] && c.name.rfind("disk", 0) != 0) EXPECT_GT(worstLegacy, 5) << c.name << " ro " << ro;
            }
}

// Triangles follow pbrt-v3: n = normalize(Cross(p1 - p0, p2 - p0)) of the world
// vertices, flipped by ReverseOrientation XOR handedness swap; with shading
// normals the geometric normal faces them instead.
TEST(Triangles, NormalOrientation) {
    std::vector<Point3> P = {Point3(0, 0, 0), Point3(1, 0, 0), Point3(0, 1, 0)};
    for (int ro = 0; ro < 2; ++ro)
        for (int mirror = 0; mirror < 2; ++mirror)
            for (int withN = 0; withN < 2; ++withN) {
                Transform w = mirror ? Scale(-1, 1, 1) : Transform();
                std::vector<Normal3> N;
                if (withN) N.assign(3, Normal3(0, 0, -1));
                auto mesh = TriangleMesh::Create(w, ro, P, {0, 1, 2}, N, {}, {}, FileLoc());
                Vec3 cross = Normalize(Cross(mesh->p[1] - mesh->p[0], mesh->p[2] - mesh->p[0]));
                Vec3 expected = withN ? Vec3(0, 0, ro ? 1 : -1) : cross * ((ro ^ mirror) ? -1 : 1);
                SurfaceInteraction si;
                mesh->interaction(0, 0.2, 0.3, Vec3(0, 0, 1), &si);
                EXPECT_GT(Dot(si.n, expected), 0.999) << ro << mirror << withN;
                Triangle tri(mesh, 0);
                Float pdf;
                EXPECT_GT(Dot(tri.sampleArea(Point2(0.3, 0.4), &pdf).n, expected), 0.999);
                Float t;
                Interaction hit;
                ASSERT_TRUE(tri.intersectP(Ray(Point3(mirror ? -0.2 : 0.2, 0.2, 1), Vec3(0, 0, -1)), &t, &hit));
                EXPECT_GT(Dot(hit.n, expected), 0.999);
            }
}

TEST(Triangles, NonFiniteVerticesRejectedWithLocation) {
    FileLoc loc;
    loc.file = std::make_shared<const std::string>("scene.pbrt");
    loc.line = 12;
    std::vector<Point3> P = {Point3(0, 0, 0), Point3(NAN, 0, 0), Point3(0, 1, 0)};
    try {
        TriangleMesh::Create(Transform(), false, P, {0, 1, 2}, {}, {}, {}, loc);
        FAIL() << "NaN vertex accepted";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("scene.pbrt:12"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("vertex 1"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace gradus
