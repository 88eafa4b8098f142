// Shape "curve" with pbrt-v3's intersection semantics (shapes/curve.h): hits of
// a straight, evenly parameterised curve against the closed form of pbrt-v3's
// ribbon (the nearest approach of ray and axis), v's side, pbrt-v3's normals for
// cylinder and flat curves, the narrowing where the Bezier parameter is uneven,
// the ends, rays leaving 2 widths off a hit, rebuilding a hit from its point
// (bidirectional vertices), pbrt-v3's control-point counts and bases, and
// located errors.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "samplers/rng.h"
#include "shapes/curve.h"

namespace gradus {
namespace {

std::unique_ptr<Scene> Build(const std::string &world) {
    std::string text = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" + world + "\nWorldEnd\n";
    return BuildScene(ParseString(text, "test.pbrt"), Point2i{8, 8});
}

// A straight curve along x from -1 to 1, width 0.2 (r = 0.1), evenly spaced
// control points: the Bezier parameter is x's, c(w) the nearest axis point.
const char *kStraight = "\"point P\" [-1 0 0 -0.3333333333333333 0 0 0.3333333333333333 0 0 1 0 0] \"float width\" 0.2";
constexpr Float kR = 0.1;

// pbrt-v3's ribbon for that curve, from its definition: a ray hits where it
// passes within r of the axis (between the perpendiculars at x = +-1), at the
// depth of the axis point c nearest to it; v = 1/2 + s dist / (2 r) with s = +1
// when the ray passes on the d x T side; the normal is dpdu x dpdv with dpdv
// = e (d x T normalised) turned about T by -90 (2 v - 1) degrees:
// n = cos(a) d_perp + sin(a) e, a = 90 (2 v - 1) degrees, d_perp the part of d
// normal to T (away from the viewer at v = 1/2).
struct Ribbon {
    bool hit = false;
    Point3 p;
    Float u = 0, v = 0;
    Vec3 n;
};
Ribbon StraightRibbon(const Ray &ray) {
    const Vec3 T(1, 0, 0), d = Normalize(ray.d);
    const Vec3 cr = Cross(d, T);
    Ribbon r;
    if (cr.lengthSquared() < 1e-12) return r;
    const Vec3 e = Normalize(cr);
    // Nearest approach of the lines o + t d and (x, 0, 0): solve for x and t.
    const Vec3 w0 = ray.o - Point3(0, 0, 0);
    const Float b = Dot(d, T), dd = Dot(d, w0), de = Dot(T, w0);
    const Float x = (de - b * dd) / (1 - b * b), t = (b * de - dd) / (1 - b * b);
    const Point3 c(x, 0, 0), q = ray.o + d * t;
    const Float dist = Distance(q, c);
    if (dist > kR || std::abs(x) > 1) return r;
    const Float tc = Dot(c - ray.o, d);  // depth of the axis point
    if (tc < 0) return r;
    r.hit = true;
    r.p = ray.o + d * tc;
    r.u = (x + 1) / 2;
    r.v = 0.5 + (Dot(q - c, e) > 0 ? 1 : -1) * dist / (2 * kR);
    const Float a = Radians(90 * (2 * r.v - 1));
    const Vec3 dPerp = Normalize(d - T * Dot(d, T));
    r.n = dPerp * std::cos(a) + e * std::sin(a);
    return r;
}

TEST(Curve, CylinderIsPbrtV3sRibbon) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight);
    RNG rng(7);
    int hits = 0, checked = 0;
    for (int i = 0; i < 4000; ++i) {
        // Origins on a sphere of radius 3, aimed at points near the axis' middle part.
        const Float z = 1 - 2 * rng.uniform(), phi = 2 * Pi * rng.uniform();
        const Point3 o = Point3(SafeSqrt(1 - z * z) * std::cos(phi), SafeSqrt(1 - z * z) * std::sin(phi), z) * 3;
        const Point3 target(-0.6 + 1.2 * rng.uniform(), -0.15 + 0.3 * rng.uniform(), -0.15 + 0.3 * rng.uniform());
        const Ray ray(o, Normalize(target - o));
        const Ribbon expect = StraightRibbon(ray);
        // Rays grazing the edge (within 1e-6 r) may go either way.
        const Vec3 T(1, 0, 0);
        const Float gap = std::abs(Dot(ray.o, Normalize(Cross(ray.d, T))));
        if (std::abs(gap - kR) < 1e-6 * kR || Cross(ray.d, T).lengthSquared() < 1e-6) continue;
        SurfaceInteraction si;
        const bool hit = s->intersect(ray, &si);
        ASSERT_EQ(hit, expect.hit) << "ray " << ray.o << " " << ray.d;
        ++checked;
        if (!hit) continue;
        ++hits;
        EXPECT_LT(Distance(si.p, expect.p), 1e-5) << si.p << " vs " << expect.p;
        EXPECT_NEAR(si.uv.x, expect.u, 1e-6);
        EXPECT_NEAR(si.uv.y, expect.v, 1e-5);
        EXPECT_GT(std::abs(Dot(si.n, expect.n)), 1 - 1e-6) << si.n << " vs " << expect.n;
        EXPECT_GT(std::abs(Dot(si.shading.n, expect.n)), 1 - 1e-6);
        EXPECT_GT(Dot(Normalize(si.dpdu), T), 1 - 1e-9);
        EXPECT_NEAR(si.dpdv.length(), 2 * kR, 1e-9);
        // Rebuilding the interaction from the point (bidirectional vertices) agrees.
        SurfaceInteraction re;
        s->geometry[si.geomId].curve->interaction(si.primId, si.p, si.wo, &re);
        EXPECT_NEAR(re.uv.x, si.uv.x, 1e-6);
        EXPECT_NEAR(re.uv.y, si.uv.y, 1e-5);
        EXPECT_GT(Dot(re.n, si.n), 1 - 1e-9);
    }
    EXPECT_GT(hits, 500);
    EXPECT_GT(checked, 3000);
}

// Where the Bezier parameter is uneven along the curve, pbrt-v3 tests the point
// c(w) at the parameter w of the ray's projection on each piece's chord, not the
// nearest point: the curve x(u) = Bezier(-1, 0.2, 0.6, 1) on the x axis, width
// 0.2, in pbrt-v3's 8 pieces (splitdepth 3; each flat enough for no refinement:
// L0 = 0.8 / 64, log2(1.41421356 * 6 * L0 / (8 * 0.01)) < 1). A ray along -z at
// (x0, y0) meets piece k with x(k/8) <= x0 <= x((k+1)/8) at w = (x0 - x(k/8)) /
// (x((k+1)/8) - x(k/8)) and hits iff (x(u) - x0)^2 + y0^2 <= r^2, u = (k + w)/8;
// v > 1/2 for y0 < 0 (the side of d x T). A tube of radius r (or a ribbon
// tested at the nearest point) would be hit wherever |y0| <= r.
TEST(Curve, UnevenParameterNarrowsTheFibre) {
    auto s = Build("Shape \"curve\" \"string type\" \"cylinder\" \"point P\" [-1 0 0 0.2 0 0 0.6 0 0 1 0 0] "
                   "\"float width\" 0.2");
    auto X = [](Float u) {
        const Float a = 1 - u;
        return -1 * a * a * a + 0.2 * 3 * u * a * a + 0.6 * 3 * u * u * a + u * u * u;
    };
    int narrowed = 0, checked = 0;
    for (int i = 0; i < 199; ++i)
        for (int j = 0; j < 21; ++j) {
            const Float x0 = -0.99 + 1.98 * i / 198, y0 = kR * (-1 + 2 * j / 20.0) * 0.999;
            int k = 0;
            while (k < 7 && X((k + 1) / 8.0) < x0) ++k;
            const Float w = (x0 - X(k / 8.0)) / (X((k + 1) / 8.0) - X(k / 8.0)), u = (k + w) / 8;
            const Float d2 = Sqr(X(u) - x0) + y0 * y0;
            if (std::abs(d2 - kR * kR) < 1e-9) continue;
            const bool expect = d2 <= kR * kR;
            SurfaceInteraction si;
            const bool hit = s->intersect(Ray(Point3(x0, y0, 5), Vec3(0, 0, -1)), &si);
            ASSERT_EQ(hit, expect) << x0 << " " << y0;
            ++checked;
            if (!expect) ++narrowed;  // within r of the axis (|y0| < r) but missed
            if (!hit) continue;
            EXPECT_NEAR(si.uv.x, u, 1e-6);  // u, v travel from the ray tracer as floats
            EXPECT_NEAR(si.uv.y, 0.5 + (y0 < 0 ? 1 : -1) * std::sqrt(d2) / (2 * kR), 1e-6);
            EXPECT_NEAR(si.p.z, 0, 1e-9);
        }
    EXPECT_GT(checked, 4000);
    EXPECT_GT(narrowed, 100);  // the narrowing is real here (154 of the grid's rays)
}

TEST(Curve, EndsAreCutAtThePerpendicular) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight);
    SurfaceInteraction si;
    EXPECT_TRUE(s->intersect(Ray(Point3(0.99, 0.05, 5), Vec3(0, 0, -1)), &si));
    EXPECT_NEAR(si.p.z, 0, 1e-9);
    for (Float x : {1.01, 1.05, 1.09, -1.01, -1.05})
        EXPECT_FALSE(s->intersect(Ray(Point3(x, 0.02, 5), Vec3(0, 0, -1)), &si)) << x;
    EXPECT_TRUE(s->occluded(Ray(Point3(0, 0, 2), Vec3(0, 0, -1), 10)));
    EXPECT_FALSE(s->occluded(Ray(Point3(0, 0, 2), Vec3(0, 0, -1), 0.5)));  // ends before the axis' depth
}

// pbrt-v3 bounds a curve hit's error by 2 widths in every axis: rays leaving it
// start sum_i |n_i| 2 w off the hit along +-n, and pass over a fibre that near.
TEST(Curve, RaysLeaveTwoWidthsOff) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight +
                   "\nShape \"curve\" \"string type\" \"cylinder\" "
                   "\"point P\" [-1 0 -0.3 -0.3333333333333333 0 -0.3 0.3333333333333333 0 -0.3 1 0 -0.3] "
                   "\"float width\" 0.2");
    SurfaceInteraction si;
    ASSERT_TRUE(s->intersect(Ray(Point3(0.1, 0.03, 3), Vec3(0, 0, -1)), &si));
    const Vec3 n = si.n;
    const Float off = 2 * (2 * kR) * (std::abs(n.x) + std::abs(n.y) + std::abs(n.z));
    for (const Vec3 &w : {Vec3(0, 0, -1), Vec3(0, 0.6, 0.8), Vec3(0.3, -0.5, -0.8)}) {
        const Ray r = si.spawnRay(Normalize(w));
        EXPECT_NEAR(Distance(r.o, si.p), off, 1e-9);
        EXPECT_GT(std::abs(Dot(Normalize(r.o - si.p), n)), 1 - 1e-9);
        EXPECT_GT(Dot(r.o - si.p, Normalize(w)), 0);
    }
    // The second fibre, 0.3 behind (1.5 widths): the ray straight through passes over it.
    EXPECT_FALSE(s->intersect(si.spawnRay(Vec3(0, 0, -1)), &si));
}

TEST(Curve, FlatFacesTheRay) {
    auto s = Build(std::string("Shape \"curve\" ") + kStraight);  // pbrt-v3's default type: flat
    RNG rng(3);
    int hits = 0;
    for (int i = 0; i < 2000; ++i) {
        // Directions not too close to the axis; targets near the axis' middle.
        Vec3 d;
        do {
            const Float z = 1 - 2 * rng.uniform(), phi = 2 * Pi * rng.uniform();
            d = Vec3(SafeSqrt(1 - z * z) * std::cos(phi), SafeSqrt(1 - z * z) * std::sin(phi), z);
        } while (std::abs(d.x) > 0.7);
        const Float off = (-1.3 + 2.6 * rng.uniform()) * kR;  // across the ribbon, beyond it too
        const Vec3 e = Normalize(Cross(d, Vec3(1, 0, 0)));
        const Point3 target = Point3(-0.6 + 1.2 * rng.uniform(), 0, 0) + e * off;
        const Ray ray(target - d * 3, d);
        if (std::abs(std::abs(off) - kR) < 1e-6 * kR) continue;
        SurfaceInteraction si;
        const bool hit = s->intersect(ray, &si);
        ASSERT_EQ(hit, std::abs(off) < kR) << "offset " << off / kR;
        if (!hit) continue;
        ++hits;
        // The ribbon contains the axis and faces the ray: the hit is the target,
        // the normal d's part normal to the axis, v > 1/2 on the d x T side.
        EXPECT_LT(Distance(si.p, target), 1e-6) << si.p << " vs " << target;
        const Vec3 dPerp = Normalize(d - Vec3(1, 0, 0) * d.x);
        EXPECT_GT(std::abs(Dot(si.n, dPerp)), 1 - 1e-6);
        EXPECT_NEAR(2 * si.uv.y - 1, off / kR, 1e-5);  // v travels as a float
    }
    EXPECT_GT(hits, 1000);
}

TEST(Curve, RibbonUsesNormals) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"ribbon\" \"normal N\" [0 0 1 0 0 1] ") + kStraight);
    SurfaceInteraction si;
    ASSERT_TRUE(s->intersect(Ray(Point3(0.2, 0.05, 2), Vec3(0, 0, -1)), &si));
    EXPECT_NEAR(si.p.z, 0, 1e-9);
    EXPECT_GT(std::abs(si.n.z), 1 - 1e-9);
    // Tilted 60 degrees off the normal the width halves (pbrt-v3: width |n . d|).
    const Vec3 d(0, std::sin(Radians(60)), -std::cos(Radians(60)));
    const Vec3 e = Normalize(Cross(d, Vec3(1, 0, 0)));
    for (Float off : {0.04, 0.06}) EXPECT_EQ(s->intersect(Ray(Point3(0.2, 0, 0) + e * off - d * 3, d), &si), off < 0.05) << off;
    // Seen edge-on there is nothing.
    EXPECT_FALSE(s->intersect(Ray(Point3(0.2, 2, 0.05), Vec3(0, -1, 0)), &si));
}

TEST(Curve, ControlPointCountsAndBases) {
    auto seg = [](const std::string &params) { return Build("Shape \"curve\" " + params)->features.numCurveSegments; };
    EXPECT_EQ(seg("\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0 5 0 0 6 0 0]"), 2);  // 3n + 1
    EXPECT_EQ(seg("\"integer degree\" 2 \"point P\" [0 0 0 1 1 0 2 0 0 3 1 0 4 0 0]"), 2);  // 2n + 1
    EXPECT_EQ(seg("\"string basis\" \"bspline\" \"point P\" [0 0 0 1 1 0 2 0 0 3 1 0 4 0 0]"), 2);
    EXPECT_EQ(seg("\"integer splitdepth\" 5 \"float width0\" 0.1 \"float width1\" 0 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]"),
              1);
    // A uniform cubic B-spline through collinear, evenly spaced points is the line
    // from (p0 + 4 p1 + p2)/6 to (p1 + 4 p2 + p3)/6: x from 1 to 2 here.
    auto s = Build("Shape \"curve\" \"string type\" \"cylinder\" \"string basis\" \"bspline\" "
                   "\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"float width\" 0.2");
    SurfaceInteraction si;
    EXPECT_TRUE(s->intersect(Ray(Point3(1.5, 0, 3), Vec3(0, 0, -1)), &si));
    EXPECT_FALSE(s->intersect(Ray(Point3(0.5, 0, 3), Vec3(0, 0, -1)), &si));
    EXPECT_FALSE(s->intersect(Ray(Point3(2.5, 0, 3), Vec3(0, 0, -1)), &si));
}

// The error names line 4 (the Shape directive) or the offending parameter there, and says `what`.
void ExpectLocatedError(const std::string &world, const std::string &what) {
    try {
        Build(world);
        ADD_FAILURE() << "no error for: " << world;
    } catch (const Error &e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test.pbrt:4:"), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
}

TEST(Curve, BadInputIsALocatedError) {
    ExpectLocatedError("Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]", "5 control points");
    ExpectLocatedError("Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0]", "3 control points");
    ExpectLocatedError("Shape \"curve\" \"string type\" \"ribbon\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "needs \"normal N\"");
    ExpectLocatedError("Shape \"curve\" \"string type\" \"ribbon\" \"normal N\" [0 0 1] "
                       "\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "1 normals");
    ExpectLocatedError("Shape \"curve\" \"float width\" -0.1 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "\"width\" must be >= 0");
    ExpectLocatedError("Shape \"curve\" \"float width1\" -1 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "\"width1\" must be >= 0");
    ExpectLocatedError("Shape \"curve\" \"string type\" \"tube\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "unknown curve type");
    ExpectLocatedError("Shape \"curve\" \"string basis\" \"hermite\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "unknown basis");
    ExpectLocatedError("Shape \"curve\" \"float widht\" 1 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]", "widht");
    ExpectLocatedError("Shape \"curve\" \"string type\" \"cylinder\"", "missing \"point P\"");
    ExpectLocatedError("Shape \"curve\" \"integer splitdepth\" 13 \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]",
                       "\"splitdepth\" must be in [0, 12]");
    // An area light on a curve: refused at the AreaLightSource (line 4 too).
    ExpectLocatedError("AttributeBegin AreaLightSource \"diffuse\" Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0] "
                       "AttributeEnd",
                       "area light on a \"curve\"");
}

}  // namespace
}  // namespace gradus
