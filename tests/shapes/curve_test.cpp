// Shape "curve" on Embree's curve primitives: cylinder hits against analytic
// ray-cylinder hits (straight curve, constant width), the swept end caps,
// tubes seen from inside, flat curves facing the ray, the offset h across the
// fibre, rebuilding a hit from its point (bidirectional vertices), pbrt-v3's
// control-point counts and bases, and located errors.
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

// A straight curve along x from -1 to 1, width 0.2 (r = 0.1).
const char *kStraight = "\"point P\" [-1 0 0 -0.3333333 0 0 0.3333333 0 0 1 0 0] \"float width\" 0.2";
constexpr Float kR = 0.1;

// Ray against the infinite cylinder y^2 + z^2 = r^2: nearest t > 0.
bool CylinderHit(const Ray &r, Float *t) {
    const Float a = r.d.y * r.d.y + r.d.z * r.d.z, b = 2 * (r.o.y * r.d.y + r.o.z * r.d.z),
                c = r.o.y * r.o.y + r.o.z * r.o.z - kR * kR;
    const Float disc = b * b - 4 * a * c;
    if (a == 0 || disc < 0) return false;
    const Float t0 = (-b - std::sqrt(disc)) / (2 * a);
    if (t0 <= 0) return false;
    *t = t0;
    return true;
}

TEST(Curve, CylinderMatchesAnalyticCylinder) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight);
    RNG rng(7);
    int hits = 0, checked = 0;
    for (int i = 0; i < 4000; ++i) {
        // Origins on a sphere of radius 3, aimed at points near the axis' middle part.
        const Float z = 1 - 2 * rng.uniform(), phi = 2 * Pi * rng.uniform();
        const Point3 o = Point3(SafeSqrt(1 - z * z) * std::cos(phi), SafeSqrt(1 - z * z) * std::sin(phi), z) * 3;
        const Point3 target(-0.6 + 1.2 * rng.uniform(), -0.15 + 0.3 * rng.uniform(), -0.15 + 0.3 * rng.uniform());
        const Ray ray(o, Normalize(target - o));
        Float tc = 0;
        const bool expect = CylinderHit(ray, &tc);
        const Point3 pc = ray(tc);
        if (expect && std::abs(pc.x) > 0.8) continue;  // near the ends: caps differ from the infinite cylinder
        // Rays grazing the silhouette (within 1e-4 r) may go either way in float.
        const Float a = ray.d.y * ray.d.y + ray.d.z * ray.d.z;
        const Float dist = std::abs(ray.o.y * ray.d.z - ray.o.z * ray.d.y) / std::sqrt(a);
        if (std::abs(dist - kR) < 1e-4 * kR) continue;
        SurfaceInteraction si;
        const bool hit = s->intersect(ray, &si);
        ASSERT_EQ(hit, expect) << "ray " << ray.o << " " << ray.d;
        ++checked;
        if (!hit) continue;
        ++hits;
        EXPECT_LT(Distance(si.p, pc), 1e-5) << si.p << " vs " << pc;
        const Normal3 nc = Normalize(Vec3(0, pc.y, pc.z));
        EXPECT_GT(Dot(si.n, nc), 1 - 1e-6);
        EXPECT_GT(Dot(si.shading.n, nc), 1 - 1e-6);
        EXPECT_NEAR(si.uv.x, (pc.x + 1) / 2, 1e-5);  // straight, evenly spaced control points: u linear in x
        // h: offset across the ray (wo x T direction) in units of r; |h| = sin of the
        // angle between the normal and the viewer, projected normal to the axis.
        const Vec3 wo = -ray.d, across = Normalize(Cross(wo, Vec3(1, 0, 0)));
        EXPECT_NEAR(2 * si.uv.y - 1, Dot(Vec3(0, pc.y, pc.z), across) / kR, 1e-4);
        EXPECT_GT(Dot(Normalize(si.dpdu), Vec3(1, 0, 0)), 1 - 1e-9);
        // Rebuilding the interaction from the point (bidirectional vertices) agrees.
        SurfaceInteraction re;
        s->geometry[si.geomId].curve->interaction(si.primId, -1, si.p, wo, &re);
        EXPECT_LT(Distance(re.p, si.p), 1e-9);
        EXPECT_NEAR(re.uv.x, si.uv.x, 1e-9);
        EXPECT_NEAR(re.uv.y, si.uv.y, 1e-9);
    }
    EXPECT_GT(hits, 500);
    EXPECT_GT(checked, 3000);
}

TEST(Curve, SweptEndsAndInside) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight);
    SurfaceInteraction si;
    // Embree 3's round Bezier curve is a sweep of circles normal to the axis with
    // open ends (no caps; pbrt-v3's ribbon has none either): the tube ends at x = 1.
    ASSERT_TRUE(s->intersect(Ray(Point3(0.99, 0.05, 5), Vec3(0, 0, -1)), &si));
    EXPECT_NEAR(si.p.z, std::sqrt(kR * kR - 0.05 * 0.05), 1e-6);
    for (Float x : {1.01, 1.05, 1.09, -1.01, -1.05})
        EXPECT_FALSE(s->intersect(Ray(Point3(x, 0.02, 5), Vec3(0, 0, -1)), &si)) << x;
    // Along the axis into the open end: the inside wall is not seen (below).
    EXPECT_FALSE(s->intersect(Ray(Point3(5, 0.01, 0.02), Vec3(-1, 0, 0)), &si));
    // From inside the tube the wall is not seen (rays leaving a fibre inwards pass through).
    EXPECT_FALSE(s->intersect(Ray(Point3(0, 0, 0), Vec3(0, 0.6, 0.8)), &si));
    EXPECT_FALSE(s->occluded(Ray(Point3(0.2, 0.01, 0), Vec3(0, 0, 1), 10)));
    // ... but it still occludes from outside, and a ray spawned inwards off a hit goes through.
    EXPECT_TRUE(s->occluded(Ray(Point3(0, 0, 2), Vec3(0, 0, -1), 10)));
    ASSERT_TRUE(s->intersect(Ray(Point3(0.1, 0.03, 3), Vec3(0, 0, -1)), &si));
    EXPECT_FALSE(s->intersect(si.spawnRay(Vec3(0, 0, -1)), &si));
}

// Shadow segments are symmetric: one ending on a tube from behind is not
// blocked by that tube's near wall (the reverse one leaves through the inside),
// while a segment through the tube to a point beyond it is blocked.
TEST(Curve, ShadowSegmentsToATubeAreSymmetric) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"cylinder\" ") + kStraight);
    SurfaceInteraction top;
    ASSERT_TRUE(s->intersect(Ray(Point3(0.1, 0.02, 3), Vec3(0, 0, -1)), &top));
    for (const Point3 &q : {Point3(0.1, 0, -2), Point3(0.5, 0.3, -1.5), Point3(-0.4, -0.2, -0.5)}) {
        const Interaction below(q, Normal3(0, 0, 0), Vec3(0, 0, 1));
        EXPECT_TRUE(s->unoccluded(below, top)) << q;
        EXPECT_TRUE(s->unoccluded(top, below)) << q;
        const Interaction beyond(top.p + (top.p - q) * 0.5, Normal3(0, 0, 0), Vec3(0, 0, 1));
        EXPECT_FALSE(s->unoccluded(below, beyond)) << q;
        EXPECT_FALSE(s->unoccluded(beyond, below)) << q;
    }
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
        const Vec3 across = Normalize(Cross(-d, Vec3(1, 0, 0)));
        const Point3 target = Point3(-0.6 + 1.2 * rng.uniform(), 0, 0) + across * off;
        const Ray ray(target - d * 3, d);
        SurfaceInteraction si;
        const bool hit = s->intersect(ray, &si);
        if (std::abs(std::abs(off) - kR) < 0.05 * kR) continue;  // tessellated edge
        ASSERT_EQ(hit, std::abs(off) < kR) << "offset " << off / kR;
        if (!hit) continue;
        ++hits;
        // The ribbon contains the axis and faces the ray: the hit is the target.
        EXPECT_LT(Distance(si.p, target), 1e-4) << si.p << " vs " << target;
        const Vec3 facing = Normalize(-d - Vec3(1, 0, 0) * Dot(-d, Vec3(1, 0, 0)));
        EXPECT_GT(Dot(si.n, facing), 1 - 1e-6);
        EXPECT_NEAR(2 * si.uv.y - 1, off / kR, 1e-3);
    }
    EXPECT_GT(hits, 1000);
}

TEST(Curve, RibbonUsesNormals) {
    auto s = Build(std::string("Shape \"curve\" \"string type\" \"ribbon\" \"normal N\" [0 0 1 0 0 1] ") + kStraight);
    SurfaceInteraction si;
    ASSERT_TRUE(s->intersect(Ray(Point3(0.2, 0.05, 2), Vec3(0, 0, -1)), &si));
    EXPECT_NEAR(si.p.z, 0, 1e-4);
    EXPECT_GT(std::abs(si.n.z), 1 - 1e-6);
    // Seen edge-on along the normal's plane there is (almost) nothing.
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
    // An area light on a curve: refused at the AreaLightSource (line 4 too).
    ExpectLocatedError("AttributeBegin AreaLightSource \"diffuse\" Shape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0] "
                       "AttributeEnd",
                       "area light on a \"curve\"");
}

}  // namespace
}  // namespace gradus
