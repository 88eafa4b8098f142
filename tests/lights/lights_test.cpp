// Light sampling against its own pdfs: chi-square goodness of fit of
// sampleLi() directions against pdfLi() and of sampleLe() directions against
// pdfLe(), sampleLe()/pdfLe() agreement, and power() against numerical
// integrals. Significance: 1% for the whole suite (Sidak-corrected per test).
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>
#include <cstdio>
#include <cstring>

#include "common/png_test_util.h"
#include "image/image.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "parser/scene_desc.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"
#include "samplers/sampling.h"
#include "shape_cases.h"
#include "shapes/triangle.h"

namespace gradus {
namespace {

constexpr int kNumChi2Tests = 40;  // upper bound on chi-square tests in this file
const double kAlpha = chi2::SidakAlpha(0.01, kNumChi2Tests);

chi2::Options Opts(int64_t samples = 100000) {
    chi2::Options o;
    o.xBins = 16;
    o.yBins = 32;
    o.samples = samples;
    o.subdivisions = 24;
    o.alpha = kAlpha;
    return o;
}

Interaction RefAt(const Point3 &p) { return Interaction(p, Normal3(0, 0, 0), Vec3(0, 0, 0)); }

// Direction density of an area light's sampleLi(): each sample picks one
// point; hidden points of the same shape count too (rendering rejects them by
// visibility), so the density of w sums over every point of the shape on w.
Float AreaDirectionDensity(const AreaLight &l, const Interaction &ref, const Vec3 &w, bool coneSampled) {
    if (coneSampled) return l.pdfLi(ref, w);
    Float sum = 0;
    Point3 o = ref.p;
    for (int k = 0; k < 6; ++k) {
        Float t;
        Interaction h;
        if (!l.shape().intersectP(Ray(o, w), &t, &h)) break;
        Float cosL = AbsDot(h.n, w);
        // One-sided lights: samples facing away carry no radiance and are rejected.
        if (cosL > 0 && (l.twoSided() || Dot(h.n, -w) > 0))
            sum += l.shape().pdfArea(h) * DistanceSquared(ref.p, h.p) / cosL;
        o = h.p + w * (1e-9 * (1 + MaxComponent(Abs(h.p))));
    }
    return sum;
}

struct AreaCase {
    std::string name;
    std::shared_ptr<const Shape> shape;
    std::vector<Point3> refs;  // world reference points without grazing lines of sight
    bool cone = false;         // full sphere: refs[1] is outside (cone sampling)
};

std::vector<AreaCase> AreaCases() {
    std::vector<AreaCase> v;
    Transform xf = Translate(Vec3(0.2, 0.1, 0.3)) * Rotate(25, Vec3(1, 1, 0));
    auto mesh = TriangleMesh::Create(xf, false, {Point3(-1, -1, 0), Point3(1.5, -0.5, 0.2), Point3(0, 1.2, -0.1)},
                                     {0, 1, 2}, {}, {}, {}, FileLoc());
    v.push_back({"triangle", std::make_shared<Triangle>(mesh, 0), {xf.applyPoint(Point3(0.2, 0.1, 1.3)),
                                                                   xf.applyPoint(Point3(0.1, -0.2, -0.8))}});
    for (const auto &c : test::AnalyticCases()) {
        AreaCase a{c.name, c.make(xf, false), {xf.applyPoint(c.inside)}};
        if (c.name == "disk") a.refs.push_back(xf.applyPoint(Point3(0.3, -0.2, -0.9)));  // behind
        if (c.name == "sphere_full") {
            a.refs.push_back(xf.applyPoint(Point3(2.5, -1.5, 2.0)));
            a.cone = true;
        }
        v.push_back(a);
    }
    return v;
}

TEST(AreaLights, SampleLiMatchesPdfLi) {
    for (const AreaCase &ac : AreaCases())
        for (bool twoSided : {false, true}) {
            AreaLight light(ac.shape, Spectrum(1), twoSided);
            for (size_t k = 0; k < ac.refs.size(); ++k) {
                Point3 p = ac.refs[k];
                Interaction ref = RefAt(p);
                bool cone = ac.cone && k == 1;
                // Cone-sampled directions are binned in the cone's own frame.
                Frame frame = cone ? Frame(Normalize(Point3(0.2, 0.1, 0.3) - p)) : Frame();
                // A one-sided light seen only from behind: no sample may succeed.
                RNG pre(99);
                int valid = 0;
                for (int i = 0; i < 2000; ++i) {
                    LightLiSample s;
                    valid += light.sampleLi(ref, Point2(pre.uniform(), pre.uniform()), &s);
                }
                if (valid == 0) {
                    EXPECT_FALSE(twoSided) << ac.name;
                    for (int i = 0; i < 2000; ++i)
                        EXPECT_EQ(AreaDirectionDensity(light, ref, SampleUniformSphere(Point2(pre.uniform(), pre.uniform())), cone), 0);
                    continue;
                }
                auto r = test::DirectionalChi2(
                    [&](RNG &rng, Vec3 *w) {
                        LightLiSample s;
                        if (!light.sampleLi(ref, Point2(rng.uniform(), rng.uniform()), &s)) return false;
                        *w = frame.toLocal(s.wi);
                        return true;
                    },
                    [&](const Vec3 &w) { return AreaDirectionDensity(light, ref, frame.toWorld(w), cone); }, Opts());
                EXPECT_TRUE(r.pass) << ac.name << (twoSided ? " two-sided" : "") << " from " << p << ": "
                                    << r.message;
            }
        }
}

// The pdf returned with a sample equals pdfLi() for that direction whenever
// the sampled point is the first one seen along it.
TEST(AreaLights, SamplePdfEqualsPdfLi) {
    for (const AreaCase &ac : AreaCases()) {
        AreaLight light(ac.shape, Spectrum(1), true);
        Interaction ref = RefAt(ac.refs.back());
        RNG rng(3);
        int checked = 0;
        for (int i = 0; i < 2000; ++i) {
            LightLiSample s;
            if (!light.sampleLi(ref, Point2(rng.uniform(), rng.uniform()), &s)) continue;
            Float t;
            Interaction first;
            if (!ac.shape->intersectP(Ray(ref.p, s.wi), &t, &first)) continue;
            if (Distance(first.p, s.pLight.p) > 1e-7) continue;
            ++checked;
            ASSERT_NEAR(light.pdfLi(ref, s.wi), s.pdf, 1e-6 * s.pdf) << ac.name;
        }
        EXPECT_GT(checked, 500) << ac.name;
    }
}

TEST(AreaLights, SampleLeMatchesPdfLe) {
    for (const AreaCase &ac : AreaCases())
        for (bool twoSided : {false, true}) {
            AreaLight light(ac.shape, Spectrum(2), twoSided);
            RNG rng(5);
            double powerSum = 0;
            const int n = 200000;
            for (int i = 0; i < n; ++i) {
                LightLeSample s;
                if (!light.sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &s))
                    continue;
                Float pdfPos, pdfDir;
                light.pdfLe(s.ray, s.nLight, &pdfPos, &pdfDir);
                ASSERT_NEAR(pdfPos, s.pdfPos, 1e-9 * s.pdfPos) << ac.name;
                ASSERT_NEAR(pdfDir, s.pdfDir, 1e-9 * s.pdfDir) << ac.name;
                powerSum += s.L.y() * AbsDot(s.nLight, s.ray.d) / (s.pdfPos * s.pdfDir);
            }
            // Emitted power estimated from the samples equals power().
            EXPECT_NEAR(powerSum / n, light.power().y(), 1e-6 * light.power().y()) << ac.name;
            // Power against the closed form L pi A (per side).
            EXPECT_NEAR(light.power().y(), 2 * Pi * ac.shape->area() * (twoSided ? 2 : 1),
                        1e-9 * light.power().y());
        }
}

// Directions of sampleLe() for a planar light (constant normal) against pdfLe().
TEST(AreaLights, SampleLeDirectionsChiSquare) {
    Transform xf = Rotate(30, Vec3(1, 0, 0));
    for (bool twoSided : {false, true}) {
        AreaLight light(std::make_shared<Disk>(xf, false, 0, 1, 0, 360), Spectrum(1), twoSided);
        Normal3 n = Normalize(xf.applyNormal(Normal3(0, 0, 1)));
        auto r = test::DirectionalChi2(
            [&](RNG &rng, Vec3 *w) {
                LightLeSample s;
                if (!light.sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &s))
                    return false;
                *w = s.ray.d;
                return true;
            },
            [&](const Vec3 &w) {
                Float pp, pd;
                light.pdfLe(Ray(Point3(0, 0, 0), w), n, &pp, &pd);
                return pd;
            },
            Opts());
        EXPECT_TRUE(r.pass) << (twoSided ? "two-sided: " : "one-sided: ") << r.message;
    }
}

// The emitter point of sampleLe() lies on the surface (bidirectional light
// vertices and pmlt's paths use it); only the ray's origin is offset from it,
// along the normal, so that the ray leaves the surface. An emitter vertex off
// its surface made gmlt's manifold walks ending on it fail where the same
// path with the emitter hit from the camera side walked (a target that
// depended on how the path was sampled: +3.7% on scenes/glossy-box).
TEST(AreaLights, SampleLePointIsOnTheSurface) {
    Transform xf = Rotate(30, Vec3(1, 0, 0));
    AreaLight light(std::make_shared<Disk>(xf, false, 0, 1, 0, 360), Spectrum(1), true);
    const Vec3 n = Normalize(Vec3(xf.applyNormal(Normal3(0, 0, 1))));
    RNG rng(9);
    double offPlane = 0, minOffset = 1;
    for (int i = 0; i < 10000; ++i) {
        LightLeSample s;
        if (!light.sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &s)) continue;
        offPlane = std::max(offPlane, std::abs(Dot(Vec3(s.p), n)));
        const Vec3 o = s.ray.o - s.p;
        minOffset = std::min(minOffset, double(o.length()));
        EXPECT_NEAR(std::abs(Dot(o, n)), o.length(), 1e-12) << "offset not along the normal";
        EXPECT_GT(Dot(o, n) * Dot(s.ray.d, n), 0) << "offset not to the ray's side";
    }
    EXPECT_LT(offPlane, 1e-12);
    EXPECT_GT(minOffset, 0);
}

// ------------------------------------------------------------------ spot
std::shared_ptr<Light> MakeLight(const std::string &text) {
    SceneDesc d = ParseString("WorldBegin\n" + text + "\nWorldEnd\n", "test.pbrt");
    auto l = CreateLight(d.lights.at(0), d);
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    l->preprocess(b);
    return l;
}

TEST(SpotLight, SampleLeDirectionsAndPower) {
    auto l = MakeLight(
        "LightSource \"spot\" \"point from\" [0 0 0] \"point to\" [1 1 0.5] \"float coneangle\" 40 "
        "\"float conedeltaangle\" 15 \"rgb I\" [3 3 3]");
    auto r = test::DirectionalChi2(
        [&](RNG &rng, Vec3 *w) {
            LightLeSample s;
            if (!l->sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &s))
                return false;
            Float pp, pd;
            l->pdfLe(s.ray, s.nLight, &pp, &pd);
            EXPECT_NEAR(pd, s.pdfDir, 1e-9);
            *w = s.ray.d;
            return true;
        },
        [&](const Vec3 &w) {
            Float pp, pd;
            l->pdfLe(Ray(Point3(0, 0, 0), w), Normal3(0, 0, 0), &pp, &pd);
            return pd;
        },
        Opts());
    EXPECT_TRUE(r.pass) << r.message;
    // power() against a quadrature of I * falloff over the sphere (Li at unit distance).
    const int n = 2000000;
    double sum = 0;
    Vec3 axis = Normalize(Vec3(1, 1, 0.5));
    Frame f(axis);
    for (int i = 0; i < n; ++i) {
        Float c = -1 + 2 * (i + 0.5) / n;
        Vec3 w = f.toWorld(SphericalDirection(SafeSqrt(1 - c * c), c, 0.3));
        LightLiSample s;
        if (l->sampleLi(RefAt(w), Point2(0.5, 0.5), &s)) sum += s.L.y();  // I falloff / 1^2
    }
    double numeric = 2 * Pi * sum * 2.0 / n;
    EXPECT_NEAR(l->power().y(), numeric, 1e-4 * numeric);
}

TEST(PointAndDistantLights, Power) {
    auto p = MakeLight("LightSource \"point\" \"rgb I\" [2 2 2]");
    EXPECT_NEAR(p->power().y(), 4 * Pi * 2, 1e-9);
    auto d = MakeLight("LightSource \"distant\" \"rgb L\" [2 2 2]");
    EXPECT_NEAR(d->power().y(), 2 * Pi * 3, 1e-9);  // pi r^2 L with r^2 = 3 (bounds [-1,1]^3)
}

// ------------------------------------------------------------- infinite
Image TestMap() {
    // 16 x 8 map with a bright spot, a gradient and a black band (zero pdf).
    Image img = Image::RGB(16, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x) {
            float v = 0.2f + 0.1f * x + (x == 11 && y == 2 ? 20.f : 0.f);
            if (y == 6) v = 0;
            img.at(x, y, 0) = v;
            img.at(x, y, 1) = 0.5f * v;
            img.at(x, y, 2) = 0.25f * v + 0.1f * y;
        }
    return img;
}

TEST(InfiniteLight, SampleLiMatchesPdfLi) {
    Image map = TestMap();
    auto l = CreateInfiniteLight(Rotate(-90, Vec3(1, 0, 0)) * RotateZ(20), Spectrum(1), &map);
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    l->preprocess(b);
    Interaction ref = RefAt(Point3(0.1, 0.2, 0.3));
    auto r = test::DirectionalChi2(
        [&](RNG &rng, Vec3 *w) {
            LightLiSample s;
            if (!l->sampleLi(ref, Point2(rng.uniform(), rng.uniform()), &s)) return false;
            EXPECT_NEAR(l->pdfLi(ref, s.wi), s.pdf, 1e-6 * s.pdf);
            *w = s.wi;
            return true;
        },
        [&](const Vec3 &w) { return l->pdfLi(ref, w); }, Opts(200000));
    EXPECT_TRUE(r.pass) << r.message;
    // sampleLe directions (towards the scene) against pdfLe.
    auto r2 = test::DirectionalChi2(
        [&](RNG &rng, Vec3 *w) {
            LightLeSample s;
            if (!l->sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &s))
                return false;
            Float pp, pd;
            l->pdfLe(s.ray, s.nLight, &pp, &pd);
            EXPECT_NEAR(pd, s.pdfDir, 1e-4 * s.pdfDir);  // theta recomputed near the poles
            EXPECT_NEAR(pp, s.pdfPos, 1e-9 * s.pdfPos);
            *w = s.ray.d;
            return true;
        },
        [&](const Vec3 &w) {
            Float pp, pd;
            l->pdfLe(Ray(Point3(0, 0, 0), w), Normal3(0, 0, 0), &pp, &pd);
            return pd;
        },
        Opts(200000));
    EXPECT_TRUE(r2.pass) << r2.message;
}

// sampleLi and sampleLe look the map up at the sampled map coordinates, Le
// from the direction (transform, acos, atan2): the same radiance up to
// rounding. And each light's memo of the last direction's angles is its own:
// two lights with different frames queried alternately with the same
// directions give the values each gives alone.
TEST(InfiniteLight, SampledRadianceMatchesLeAndLightsKeepTheirOwnAngles) {
    Image map = TestMap();
    auto a = CreateInfiniteLight(Rotate(-90, Vec3(1, 0, 0)) * RotateZ(20), Spectrum(1), &map);
    auto b = CreateInfiniteLight(RotateZ(75), Spectrum(1), &map);
    Bounds3 bb;
    bb.expand(Point3(-1, -1, -1));
    bb.expand(Point3(1, 1, 1));
    a->preprocess(bb);
    b->preprocess(bb);
    Interaction ref = RefAt(Point3(0.1, 0.2, 0.3));
    RNG rng(77);
    std::vector<Vec3> ws;
    for (int i = 0; i < 2000; ++i) {
        LightLiSample s;
        if (!a->sampleLi(ref, Point2(rng.uniform(), rng.uniform()), &s)) continue;
        Spectrum le = a->Le(Ray(ref.p, s.wi));
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(s.L[c], le[c], 1e-9 * (1 + le[c])) << i;
        LightLeSample e;
        if (!b->sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(rng.uniform(), rng.uniform()), &e)) continue;
        Spectrum le2 = b->Le(Ray(Point3(0, 0, 0), -e.ray.d));
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(e.L[c], le2[c], 1e-9 * (1 + le2[c])) << i;
        ws.push_back(s.wi);
    }
    std::vector<Spectrum> la, lb;
    std::vector<Float> pa, pb;
    for (const Vec3 &w : ws) la.push_back(a->Le(Ray(ref.p, w))), pa.push_back(a->pdfLi(ref, w));
    for (const Vec3 &w : ws) lb.push_back(b->Le(Ray(ref.p, w))), pb.push_back(b->pdfLi(ref, w));
    int differ = 0;
    for (size_t i = 0; i < ws.size(); ++i) {
        Spectrum xb = b->Le(Ray(ref.p, ws[i]));
        Float qa = a->pdfLi(ref, ws[i]);
        Spectrum xa = a->Le(Ray(ref.p, ws[i]));
        Float qb = b->pdfLi(ref, ws[i]);
        ASSERT_EQ(xa, la[i]);
        ASSERT_EQ(xb, lb[i]);
        ASSERT_EQ(qa, pa[i]);
        ASSERT_EQ(qb, pb[i]);
        differ += !(la[i] == lb[i]);
    }
    EXPECT_GT(differ, int(ws.size()) / 2);  // the two frames do see different radiance
}

TEST(InfiniteLight, PowerMatchesQuadrature) {
    Image map = TestMap();
    auto l = CreateInfiniteLight(Transform(), Spectrum(1), &map);
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    l->preprocess(b);
    // pi r^2 * integral of L over directions. The map is looked up bilinearly;
    // power() integrates the texels, so compare with a loose tolerance plus an
    // exact check on a constant map.
    const int nc = 400, np = 800;
    double sum = 0;
    for (int i = 0; i < nc; ++i)
        for (int j = 0; j < np; ++j) {
            Float c = -1 + 2 * (i + 0.5) / nc, phi = 2 * Pi * (j + 0.5) / np;
            sum += l->Le(Ray(Point3(0, 0, 0), SphericalDirection(SafeSqrt(1 - c * c), c, phi))).y();
        }
    double numeric = Pi * 3 * sum * 4 * Pi / (double(nc) * np);
    EXPECT_NEAR(l->power().y(), numeric, 0.05 * numeric);
    auto c = CreateInfiniteLight(Transform(), Spectrum(0.5), nullptr);
    c->preprocess(b);
    EXPECT_NEAR(c->power().y(), Pi * 3 * 4 * Pi * 0.5, 1e-9);
}

// A non-finite direction (a degenerate ray in a fuzzed gbdpt scene) reached
// the texel lookup's int conversion (UBSan): it now has no radiance and no
// density, for a map and for a constant environment.
// An 8-bit PNG environment map gives its codes / 255 (pbrt-v3 reads light maps
// without sRGB decoding): at each texel centre's direction (theta from +z down
// the rows, phi = atan2(y, x) across the columns) Le is L times that texel.
TEST(InfiniteLight, PngMapValuesAsStored) {
    const unsigned char codes[4 * 2 * 3] = {10, 60, 128, 200, 255, 1, 90, 30, 140, 250, 5, 77,
                                            33, 66, 99, 120, 180, 240, 45, 135, 225, 2, 128, 254};
    const std::string path = "/tmp/gradus_lights_test_env_" + std::to_string(::getpid()) + ".png";
    ASSERT_TRUE(test::WritePngCodes(path, 4, 2, 3, codes));
    auto l = MakeLight("LightSource \"infinite\" \"rgb L\" [2 2 2] \"string mapname\" \"" + path + "\"");
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const Float theta = Pi * (y + 0.5) / 2, phi = 2 * Pi * (x + 0.5) / 4;
            const Vec3 w(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            const Spectrum Le = l->Le(Ray(Point3(0, 0, 0), w));  // a ray escaping along w
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(Le[c], 2 * codes[3 * (4 * y + x) + c] / 255.0, 1e-6) << x << " " << y;
        }
    std::remove(path.c_str());
}

TEST(InfiniteLight, NonFiniteDirectionHasNoRadiance) {
    Image map = TestMap();
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    for (const Image *m : std::vector<const Image *>{&map, nullptr}) {
        auto l = CreateInfiniteLight(Transform(), Spectrum(1), m);
        l->preprocess(b);
        for (const Vec3 &d : {Vec3(NAN, 0, 1), Vec3(0, NAN, 0), Vec3(INFINITY, 0, 0)}) {
            EXPECT_TRUE(l->Le(Ray(Point3(0, 0, 0), d)).isBlack());
            EXPECT_EQ(l->pdfLi(Interaction(), d), 0);
        }
        EXPECT_FALSE(l->Le(Ray(Point3(0, 0, 0), Vec3(0, 0, 1))).isBlack());
    }
}

// Two equal point lights at x = -0.5 and 0.5, and the box [-1, 1]^3 around them.
std::vector<std::shared_ptr<Light>> TwoPointLights() {
    return {MakeLight(R"(LightSource "point" "point from" [-0.5 0 0])"),
            MakeLight(R"(LightSource "point" "point from" [0.5 0 0])")};
}
Bounds3 UnitBox() {
    Bounds3 b;
    b.expand(Point3(-1, -1, -1));
    b.expand(Point3(1, 1, 1));
    return b;
}

// The spatial light choice at points far outside its grid (1e73 and NaN in a
// fuzzed scene: the voxel index conversion was undefined behaviour) uses the
// nearest boundary voxel, or voxel 0 for NaN, and returns a valid choice.
TEST(LightSampler, SpatialChoiceFarOutsideTheBounds) {
    std::vector<std::shared_ptr<Light>> lights = TwoPointLights();
    const Bounds3 b = UnitBox();
    LightSampler ls(lights, "spatial", FileLoc(), b);
    for (Point3 p : {Point3(1e73, 0, 0), Point3(-1e300, 3e40, -2e19), Point3(std::nan(""), 0, 0)}) {
        Float pmf = 0;
        const Light *l = ls.sample(p, 0.5, &pmf);
        ASSERT_NE(l, nullptr);
        EXPECT_GT(pmf, 0);
        EXPECT_LE(pmf, 1);
    }
}

// The spatial choice follows each light's contribution at the shading point:
// two equal point lights 1 apart; next to one (distance 0.05 against 0.95, and
// at most a voxel's width 2/64 off), the near one carries ~99.7% of the
// unoccluded contribution, so its pmf must exceed 0.95; the power and uniform
// strategies give 0.5. The pmf matches the sampled frequencies.
TEST(LightSampler, SpatialChoiceFavoursTheNearLight) {
    std::vector<std::shared_ptr<Light>> lights = TwoPointLights();
    const Bounds3 b = UnitBox();
    LightSampler ls(lights, "spatial", FileLoc(), b);
    for (int side : {0, 1}) {
        const Point3 p(side ? 0.45 : -0.45, 0.01, 0.01);
        EXPECT_GT(ls.pmf(p, lights[side].get()), 0.95) << side;
        EXPECT_NEAR(ls.pmf(p, lights[side].get()) + ls.pmf(p, lights[1 - side].get()), 1, 1e-12);
        int hits = 0;
        const int n = 1000;
        for (int i = 0; i < n; ++i) {
            Float pmf = 0;
            const Light *l = ls.sample(p, (i + 0.5) / n, &pmf);
            ASSERT_NE(l, nullptr);
            EXPECT_DOUBLE_EQ(pmf, ls.pmf(p, l));
            hits += l == lights[side].get();
        }
        EXPECT_NEAR(hits / double(n), ls.pmf(p, lights[side].get()), 1.5 / n);
    }
    EXPECT_EQ(ls.voxelsBuilt(), 2);
    LightSampler power(lights, "power", FileLoc(), b);
    EXPECT_DOUBLE_EQ(power.pmf(Point3(-0.45, 0, 0), lights[0].get()), 0.5);
}

// The power strategy over many lights: each light's pmf is its power over
// the total (computed here from the intensities: a point light's power is
// 4 pi I), a light listed twice has the pmf of one entry, a light not
// in the sampler (or null) has pmf 0, and sampling returns lights with those
// pmfs.
TEST(LightSampler, PowerPmfOfManyLights) {
    std::vector<std::shared_ptr<Light>> lights;
    std::vector<double> I;
    for (int i = 0; i < 300; ++i) {
        I.push_back(1 + (i * 37) % 11);
        lights.push_back(MakeLight("LightSource \"point\" \"rgb I\" [" + std::to_string(I.back()) + " " +
                                   std::to_string(I.back()) + " " + std::to_string(I.back()) + "] \"point from\" [" +
                                   std::to_string(i * 0.01) + " 0 0]"));
    }
    lights.push_back(lights[5]);  // listed twice
    I.push_back(I[5]);
    double total = 0;
    for (double v : I) total += v;
    LightSampler ls(lights, "power", FileLoc(), UnitBox());
    for (int i = 0; i < 300; ++i) {
        double expect = (i == 5 ? I.back() : I[i]) / total;
        EXPECT_NEAR(ls.pmf(lights[i].get()), expect, 1e-12 * expect) << i;
        EXPECT_EQ(ls.pmf(Point3(0, 0, 0), lights[i].get()), ls.pmf(lights[i].get()));
    }
    auto stranger = MakeLight(R"(LightSource "point" "point from" [0 0 0])");
    EXPECT_EQ(ls.pmf(stranger.get()), 0);
    EXPECT_EQ(ls.pmf(nullptr), 0);
    for (int k = 0; k < 1000; ++k) {
        Float pmf;
        const Light *l = ls.sample((k + 0.5) / 1000, &pmf);
        ASSERT_NE(l, nullptr);
        if (l != lights[5].get()) {
            ASSERT_EQ(pmf, ls.pmf(l));
        }
    }
    LightSampler empty(std::vector<std::shared_ptr<Light>>{}, "power", FileLoc(), UnitBox());
    EXPECT_EQ(empty.pmf(lights[0].get()), 0);
}

// ------------------------------------------------------------------ goniometric, projection
// A 4 x 2 map whose texels are all distinct, written as EXR for CreateLight.
std::string WriteTexelMap(const std::string &name) {
    Image img(4, 2, {"R", "G", "B"});
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = float(1 + x + 4 * y + 10 * c);
    const std::string path = "/tmp/gradus_lights_test_" + name + "_" + std::to_string(::getpid()) + ".exr";
    WriteImage(path, img);
    return path;
}
Float TexelValue(int x, int y, int c) { return Float(1 + x + 4 * y + 10 * c); }

// Texel centres land where pbrt-v3's maps put them: goniometric theta from the
// light's +y pole down the rows, phi = atan2(z, x) across the columns.
TEST(GoniometricLight, MapOrientationIntensityAndPower) {
    const std::string map = WriteTexelMap("gonio");
    auto l = MakeLight("LightSource \"goniometric\" \"rgb I\" [2 2 2] \"string mapname\" \"" + map + "\"");
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const Float theta = Pi * (y + 0.5) / 2, phi = 2 * Pi * (x + 0.5) / 4;
            const Vec3 wl(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
            // A receiver at distance 2 along wl sees I S / d^2.
            Interaction ref(Point3(0, 0, 0) + wl * 2, Normal3(0, 0, 0), Vec3(0, 0, 1));
            LightLiSample ls;
            ASSERT_TRUE(l->sampleLi(ref, Point2(0.5, 0.5), &ls));
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(ls.L[c], 2 * TexelValue(x, y, c) / 4, 1e-9) << x << " " << y;
        }
    // Power: Monte Carlo integral of I S over the sphere (z-test at 4.4 sigma).
    RNG rng(3);
    double s = 0, s2 = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        LightLeSample le;
        ASSERT_TRUE(l->sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(0.5, 0.5), &le));
        Float pp, pd;
        l->pdfLe(le.ray, le.nLight, &pp, &pd);
        ASSERT_NEAR(pd, le.pdfDir, 1e-12);
        const double v = le.L.g / le.pdfDir;
        s += v;
        s2 += v * v;
    }
    const double mean = s / n, se = std::sqrt((s2 / n - mean * mean) / n);
    EXPECT_LT(std::abs(mean - l->power().g), 4.4 * se) << mean << " vs " << l->power().g;
    std::remove(map.c_str());
}

// The projector's screen: texel (x, y) at screen point (-sx + 2 sx (x + 1/2) / w,
// -sy + 2 sy (y + 1/2) / h) times tan(fov / 2), row 0 at the light's -y side;
// nothing outside the screen or behind the projector.
TEST(ProjectionLight, ScreenMappingSupportAndSampling) {
    const std::string map = WriteTexelMap("proj");
    auto l = MakeLight("LightSource \"projection\" \"float fov\" [30] \"rgb I\" [1 1 1] \"string mapname\" \"" + map + "\"");
    const Float t = std::tan(Radians(15.0)), sx = 2, sy = 1;  // aspect 4/2: the screen is [-2, 2] x [-1, 1]
    auto Li = [&](const Vec3 &wl) {
        Interaction ref(Point3(0, 0, 0) + Normalize(wl) * 3, Normal3(0, 0, 0), Vec3(0, 0, 1));
        LightLiSample ls;
        return l->sampleLi(ref, Point2(0.5, 0.5), &ls) ? ls.L * 9 : Spectrum(0);
    };
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            const Vec3 wl((-sx + 2 * sx * (x + 0.5) / 4) * t, (-sy + 2 * sy * (y + 0.5) / 2) * t, 1);
            const Spectrum L = Li(wl);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(L[c], TexelValue(x, y, c), 1e-9) << x << " " << y;
        }
    EXPECT_EQ(Li(Vec3(2.05 * t, 0, 1)).maxComponent(), 0);
    EXPECT_EQ(Li(Vec3(0, 1.05 * t, 1)).maxComponent(), 0);
    EXPECT_EQ(Li(Vec3(0, 0, -1)).maxComponent(), 0);
    // Emission sampling covers the screen: MC power against power().
    RNG rng(5);
    double s = 0, s2 = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        LightLeSample le;
        double v = 0;
        if (l->sampleLe(Point2(rng.uniform(), rng.uniform()), Point2(0.5, 0.5), &le)) v = le.L.r / le.pdfDir;
        s += v;
        s2 += v * v;
    }
    const double mean = s / n, se = std::sqrt((s2 / n - mean * mean) / n);
    EXPECT_LT(std::abs(mean - l->power().r), 4.4 * se + 2e-3 * mean) << mean << " vs " << l->power().r;
    // Bad input.
    EXPECT_THROW(MakeLight("LightSource \"projection\" \"float fov\" [180]"), Error);
    EXPECT_THROW(MakeLight("LightSource \"goniometric\" \"string mapname\" \"/nonexistent/map.exr\""), Error);
    std::remove(map.c_str());
}

}  // namespace
}  // namespace gradus
