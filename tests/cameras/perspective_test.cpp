// Perspective camera against an independent pinhole / thin-lens model (pbrt-v3's
// LookAt frame and screen window, written here without Transform): generated
// rays, the world -> raster projection, focus, and the importance light
// tracing uses. pbrt-v3 normalises We so that, from any lens point, the
// integral of We cos(theta) over directions is 1 / lens area (1 for a pinhole)
// and pdfWe's direction pdf integrates to 1; both are checked by a quadrature
// over the sphere that knows nothing of the image plane.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "cameras/camera.h"
#include "common/chi2_test.h"
#include "parser/scene_desc.h"
#include "samplers/rng.h"

namespace gradus {
namespace {

struct Config {
    Vec3 eye, target, up;
    Point2i res;
    std::string params;  // after Camera "perspective"
    double sw[4];        // the screen window pbrt-v3 gives these parameters
    double fovDeg;       // on the window's [-1, 1] axis
    double lensRadius = 0, focalDistance = 1e6;
};

// Landscape (fov on y), portrait (fov on x), an explicit off-centre window, and
// the glTF "yfov" (vertical whatever the aspect ratio).
Config Landscape() { return {{1, 2, 3}, {0.5, -1, 0.2}, {0, 1, 0}, {40, 30}, "\"float fov\" [50]", {-4. / 3, 4. / 3, -1, 1}, 50}; }
Config Portrait() {
    return {{-2, 0.5, 1}, {3, 1, -2}, {0.2, 1, 0.1}, {30, 40}, "\"float fov\" [70]", {-1, 1, -4. / 3, 4. / 3}, 70};
}
Config Window() {
    return {{1, 2, 3}, {0.5, -1, 0.2}, {0, 1, 0}, {32, 24}, "\"float fov\" [60] \"float screenwindow\" [-0.5 1.5 -1 0.7]",
            {-0.5, 1.5, -1, 0.7}, 60};
}
Config YFov() { return {{0, 1, -1}, {0.3, 1.2, 2}, {0, 1, 0}, {30, 40}, "\"float yfov\" [40]", {-0.75, 0.75, -1, 1}, 40}; }
Config ThinLens() {
    Config c = Landscape();
    c.params += " \"float lensradius\" [0.25] \"float focaldistance\" [3.5]";
    c.lensRadius = 0.25;
    c.focalDistance = 3.5;
    return c;
}

std::string Str(const Vec3 &v) {
    char b[128];
    std::snprintf(b, sizeof b, "%.17g %.17g %.17g ", v.x, v.y, v.z);
    return b;
}

std::unique_ptr<Camera> MakeCamera(const Config &c) {
    SceneDesc d = ParseString("LookAt " + Str(c.eye) + Str(c.target) + Str(c.up) + "\nCamera \"perspective\" " +
                                  c.params + "\nWorldBegin\nWorldEnd\n",
                              "test.pbrt");
    return CreateCamera(d.camera, c.res, &d);
}

// The analytic model of a configuration.
struct Model {
    Vec3 eye, x, y, z;  // camera frame in world space (x right, y up, z view)
    Point2i res;
    double sw[4], tanHalf, R, fd;
    explicit Model(const Config &c) : eye(c.eye), res(c.res), R(c.lensRadius), fd(c.focalDistance) {
        z = Normalize(c.target - c.eye);
        x = Normalize(Cross(Normalize(c.up), z));
        y = Cross(z, x);
        for (int i = 0; i < 4; ++i) sw[i] = c.sw[i];
        tanHalf = std::tan(c.fovDeg * M_PI / 360);
    }
    Vec3 toWorld(double cx, double cy, double cz) const { return eye + x * cx + y * cy + z * cz; }
    Vec3 toCamera(const Vec3 &p) const { return {Dot(p - eye, x), Dot(p - eye, y), Dot(p - eye, z)}; }
    // Camera-space point on the plane at depth 1 seen at raster r.
    Vec3 planePoint(Point2 r) const {
        const double sx = sw[0] + r.x / res.x * (sw[1] - sw[0]), sy = sw[3] - r.y / res.y * (sw[3] - sw[2]);
        return {sx * tanHalf, sy * tanHalf, 1};
    }
    // Unit world direction of the pinhole ray through raster r (also beyond the image).
    Vec3 dir(Point2 r) const {
        const Vec3 p = planePoint(r);
        return Normalize(x * p.x + y * p.y + z * p.z);
    }
    // Raster position of a world point seen through the lens centre; false behind it.
    bool raster(const Vec3 &p, Point2 *r) const {
        const Vec3 c = toCamera(p);
        if (c.z <= 0) return false;
        const double sx = c.x / c.z / tanHalf, sy = c.y / c.z / tanHalf;
        *r = Point2((sx - sw[0]) / (sw[1] - sw[0]) * res.x, (sw[3] - sy) / (sw[3] - sw[2]) * res.y);
        return true;
    }
    bool inside(Point2 r) const { return r.x >= 0 && r.x < res.x && r.y >= 0 && r.y < res.y; }
    // Distance of a raster point to the image border (negative outside).
    double margin(Point2 r) const { return std::min({r.x, res.x - r.x, r.y, res.y - r.y}); }
    // Area of the image on the plane at depth 1; the lens area (1 for a pinhole).
    double area() const { return std::abs((sw[1] - sw[0]) * (sw[3] - sw[2])) * tanHalf * tanHalf; }
    double lensArea() const { return R > 0 ? M_PI * R * R : 1; }
    // Raster position of the ray from lens point pl (world) towards p: where it
    // crosses the plane of focus, projected through the lens centre.
    bool rasterThroughLens(const Vec3 &pl, const Vec3 &p, Point2 *r) const {
        const Vec3 d = p - pl;
        const double dz = Dot(d, z);
        if (dz <= 0) return false;
        const double depth = R > 0 ? fd : 1;
        return raster(pl + d * ((depth - Dot(pl - eye, z)) / dz), r);
    }
    // We of pbrt-v3's perspective camera for a ray leaving the lens at cos(theta) to the view axis.
    double We(double cosTheta) const { return 1 / (area() * lensArea() * std::pow(cosTheta, 4)); }
};

double Dist(const Vec3 &a, const Vec3 &b) { return (a - b).length(); }

TEST(Perspective, RaysAreThePinholeProjection) {
    for (const Config &c : {Landscape(), Portrait(), Window(), YFov()}) {
        SCOPED_TRACE(c.params);
        auto cam = MakeCamera(c);
        const Model m(c);
        ASSERT_TRUE(cam->hasImportance());
        EXPECT_LT(Dist(cam->lensNormal(), m.z), 1e-12);
        RNG rng(11);
        for (int k = 0; k < 300; ++k) {
            const Point2 pr(rng.uniform() * c.res.x, rng.uniform() * c.res.y);
            Ray r;
            ASSERT_EQ(cam->generateRay(CameraSample{pr, Point2(rng.uniform(), rng.uniform())}, &r), 1);
            EXPECT_LT(Dist(r.o, m.eye), 1e-12);
            EXPECT_LT(Dist(r.d, m.dir(pr)), 1e-12) << pr.x << " " << pr.y;
            // rayThrough holds a given lens point (the pinhole for this camera).
            Ray rt;
            ASSERT_TRUE(cam->rayThrough(m.eye, pr, &rt));
            EXPECT_LT(Dist(rt.d, m.dir(pr)), 1e-12);
        }
    }
}

// World point -> raster by the model, then back: the camera's ray through that
// raster position passes through the point, and We reports the same raster
// position for the ray from the eye to the point (zero importance outside).
TEST(Perspective, WorldPointsRoundTripThroughTheRaster) {
    for (const Config &c : {Landscape(), Portrait(), Window(), YFov()}) {
        SCOPED_TRACE(c.params);
        auto cam = MakeCamera(c);
        const Model m(c);
        RNG rng(12);
        int inside = 0, outside = 0;
        for (int k = 0; k < 1000; ++k) {
            const double cz = 0.3 + 20 * rng.uniform();
            const Vec3 p = m.toWorld((4 * rng.uniform() - 2) * cz * m.tanHalf, (4 * rng.uniform() - 2) * cz * m.tanHalf, cz);
            Point2 pr;
            ASSERT_TRUE(m.raster(p, &pr));
            Point2 got;
            const Spectrum We = cam->We(Ray(m.eye, Normalize(p - m.eye)), &got);
            EXPECT_NEAR(got.x, pr.x, 1e-9 * c.res.x);
            EXPECT_NEAR(got.y, pr.y, 1e-9 * c.res.y);
            if (std::abs(m.margin(pr)) < 1e-6) continue;
            EXPECT_EQ(We[0] > 0, m.inside(pr)) << pr.x << " " << pr.y;
            if (!m.inside(pr)) {
                ++outside;
                continue;
            }
            ++inside;
            Ray r;
            cam->generateRay(CameraSample{pr, Point2(0.5, 0.5)}, &r);
            const Vec3 v = p - r.o;
            EXPECT_LT((v - r.d * Dot(v, r.d)).length(), 1e-10 * v.length());  // p on the ray
            EXPECT_GT(Dot(v, r.d), 0);
        }
        EXPECT_GT(inside, 100);
        EXPECT_GT(outside, 100);
    }
}

// Thin lens: rays from every lens point through one film point meet on the
// plane of focus where the pinhole ray of that film point meets it.
TEST(Perspective, ThinLensRaysMeetOnThePlaneOfFocus) {
    const Config c = ThinLens();
    auto cam = MakeCamera(c);
    const Model m(c);
    RNG rng(13);
    double maxR = 0;
    for (int k = 0; k < 100; ++k) {
        const Point2 pr(rng.uniform() * c.res.x, rng.uniform() * c.res.y);
        const Vec3 d0 = m.dir(pr);
        const Vec3 focus = m.eye + d0 * (m.fd / Dot(d0, m.z));
        for (int j = 0; j < 20; ++j) {
            const Point2 u = j == 0 ? Point2(0.5, 0.5) : Point2(rng.uniform(), rng.uniform());
            Ray r;
            ASSERT_EQ(cam->generateRay(CameraSample{pr, u}, &r), 1);
            EXPECT_NEAR(r.d.length(), 1, 1e-12);
            const Vec3 o = m.toCamera(r.o);
            EXPECT_NEAR(o.z, 0, 1e-12);  // on the lens plane
            const double rl = std::hypot(o.x, o.y);
            EXPECT_LE(rl, m.R * (1 + 1e-12));
            maxR = std::max(maxR, rl);
            if (j == 0) {
                EXPECT_LT(rl, 1e-12);  // the lens centre: the pinhole ray
            }
            const Vec3 q = r.o + r.d * ((m.fd - o.z) / Dot(r.d, m.z));
            EXPECT_LT(Dist(q, focus), 1e-10 * m.fd) << pr.x << " " << pr.y << " lens " << o.x << " " << o.y;
            Ray rt;
            ASSERT_TRUE(cam->rayThrough(r.o, pr, &rt));
            EXPECT_LT(Dist(rt.d, r.d), 1e-10);
        }
    }
    EXPECT_GT(maxR, 0.95 * m.R);  // the whole lens is used
}

// pdfWe's direction pdf is the density of generateRay's directions for a
// uniform raster position, given the lens point: 1 / (pixels * |dw / dA_raster|),
// with the solid-angle Jacobian taken by central differences of the camera's
// own rays (relative error ~h^2). The light-tracing weight We cos / (pdfPos
// pdfDir) of a camera ray is 1, as generateRay's weight is.
TEST(Perspective, DirectionPdfIsTheDensityOfGeneratedRays) {
    for (const Config &c : {Landscape(), Window(), ThinLens()}) {
        SCOPED_TRACE(c.params);
        auto cam = MakeCamera(c);
        const Model m(c);
        RNG rng(14);
        for (int k = 0; k < 200; ++k) {
            const Point2 pr(1 + rng.uniform() * (c.res.x - 2), 1 + rng.uniform() * (c.res.y - 2));
            const Point2 u(rng.uniform(), rng.uniform());
            auto ray = [&](double dx, double dy) {
                Ray r;
                cam->generateRay(CameraSample{Point2(pr.x + dx, pr.y + dy), u}, &r);
                return r;
            };
            const double h = 1e-3;
            const Ray r = ray(0, 0);
            const Vec3 ddx = (ray(h, 0).d - ray(-h, 0).d) / (2 * h), ddy = (ray(0, h).d - ray(0, -h).d) / (2 * h);
            const double jac = Cross(ddx, ddy).length();  // solid angle per raster area
            Float pdfPos, pdfDir;
            cam->pdfWe(r, &pdfPos, &pdfDir);
            EXPECT_NEAR(pdfDir * jac * c.res.x * c.res.y, 1, 1e-6);
            EXPECT_NEAR(pdfPos * m.lensArea(), 1, 1e-12);
            const double cosTheta = Dot(r.d, m.z);
            const Spectrum We = cam->We(r, nullptr);
            EXPECT_NEAR(We[0] / m.We(cosTheta), 1, 1e-9);
            EXPECT_NEAR(We[0] * cosTheta / (pdfPos * pdfDir), 1, 1e-9);
        }
    }
}

// Midpoint rule over directions around the view axis in (cos theta, phi), so
// dw = dcos dphi: integral of f(world direction) over the cone cos >= mu0.
template <typename F>
double IntegrateDirections(const Model &m, double mu0, int n, F f) {
    double sum = 0;
    const double dmu = (1 - mu0) / n, dphi = 2 * M_PI / n;
    for (int i = 0; i < n; ++i) {
        const double mu = mu0 + (i + 0.5) * dmu, s = std::sqrt(1 - mu * mu);
        for (int j = 0; j < n; ++j) {
            const double phi = (j + 0.5) * dphi;
            sum += f(m.x * (s * std::cos(phi)) + m.y * (s * std::sin(phi)) + m.z * mu);
        }
    }
    return sum * dmu * dphi;
}

// pbrt-v3's normalisation: from a lens point, the integral of We cos(theta)
// over directions is 1 / lens area, and that of pdfDir is 1. The quadrature's
// error comes from the cells the image border cuts (~1e-4 at n = 700); a
// cos^3 for cos^4 in We, or the image area of the wrong plane, are off by
// several percent.
TEST(Perspective, ImportanceIntegratesToOneOverTheLens) {
    struct Case {
        Config c;
        double lx, ly;  // lens point, camera space
    };
    const Config tl = ThinLens();
    for (const Case &k : {Case{Landscape(), 0, 0}, Case{Window(), 0, 0}, Case{tl, 0, 0},
                          Case{tl, 0.6 * tl.lensRadius, -0.3 * tl.lensRadius}, Case{tl, -0.1 * tl.lensRadius, 0.95 * tl.lensRadius}}) {
        SCOPED_TRACE(k.c.params + " lens " + std::to_string(k.lx) + " " + std::to_string(k.ly));
        auto cam = MakeCamera(k.c);
        const Model m(k.c);
        const Vec3 o = m.toWorld(k.lx, k.ly, 0);
        // The cone holding every direction with importance: through the image's
        // corners on the plane of focus (depth 1 for a pinhole), plus a margin.
        const double depth = m.R > 0 ? m.fd : 1;
        double mu0 = 1;
        for (Point2 corner : {Point2(0, 0), Point2(m.res.x, 0), Point2(0, m.res.y), Point2(m.res.x, m.res.y)}) {
            const Vec3 q = m.planePoint(corner) * depth - Vec3(k.lx, k.ly, 0);
            mu0 = std::min(mu0, q.z / q.length());
        }
        mu0 -= 0.02;
        double sumWe = 0, sumPdf = 0;
        const int n = 700;
        sumWe = IntegrateDirections(m, mu0, n, [&](const Vec3 &w) {
            const Ray r(o, w);
            Float pdfPos, pdfDir;
            cam->pdfWe(r, &pdfPos, &pdfDir);
            sumPdf += pdfDir;
            if (pdfDir > 0) {
                EXPECT_NEAR(pdfPos * m.lensArea(), 1, 1e-12);
            }
            return cam->We(r, nullptr)[0] * Dot(w, m.z);
        });
        sumPdf *= (1 - mu0) / n * (2 * M_PI / n);
        EXPECT_NEAR(sumWe * m.lensArea(), 1, 1e-3);
        EXPECT_NEAR(sumPdf, 1, 1e-3);
        // Nothing outside the cone.
        const double outside = IntegrateDirections(m, mu0 - 0.2, 60, [&](const Vec3 &w) {
            return Dot(w, m.z) < mu0 ? cam->We(Ray(o, w), nullptr)[0] : 0.0;
        });
        EXPECT_EQ(outside, 0);
    }
}

// sampleWi from points in space against the model: the lens point lies on the
// lens, wi points to it, the pdf is the uniform lens density in solid angle
// (dist^2 / (cos * lens area)), We and the raster position are those of the
// ray from the lens point through the reference point (projected from the
// plane of focus), and We equals the camera's We along the reversed ray. The
// lens points are checked to be uniform on the disc by a chi-square test of
// (r^2 / R^2, phi / 2 pi) on 8 x 8 equal-area cells: 2e5 samples, alpha 1e-3.
// Power: the same test on the same samples thinned to a density off by +-3%
// (radially, or in phi) rejects: noncentrality ~60, expected statistic ~123
// against the critical value 103 for 63 degrees of freedom (seen: 139, 129).
TEST(Perspective, SampleWiMatchesTheLensDensityAndImportance) {
    for (const Config &c : {Landscape(), ThinLens()}) {
        SCOPED_TRACE(c.params);
        auto cam = MakeCamera(c);
        const Model m(c);
        RNG rng(15);
        int accepted = 0, rejected = 0;
        for (int k = 0; k < 3000; ++k) {
            const double cz = (k % 10 == 0 ? -1 : 1) * (0.5 + 10 * rng.uniform());
            const Vec3 p = m.toWorld((3 * rng.uniform() - 1.5) * std::abs(cz) * m.tanHalf * 1.4,
                                     (3 * rng.uniform() - 1.5) * std::abs(cz) * m.tanHalf, cz);
            const Interaction ref(p, Normal3(0, 0, 0), Vec3(0, 0, 0));
            CameraWiSample s;
            const bool ok = cam->sampleWi(ref, Point2(rng.uniform(), rng.uniform()), &s);
            const Vec3 pl = m.toCamera(s.pLens.p);
            EXPECT_NEAR(pl.z, 0, 1e-12);
            EXPECT_LE(std::hypot(pl.x, pl.y), m.R * (1 + 1e-12) + 1e-12);
            Point2 pr;
            const bool front = m.rasterThroughLens(s.pLens.p, p, &pr);
            if (front && std::abs(m.margin(pr)) < 1e-6) continue;
            const bool expect = front && m.inside(pr);
            EXPECT_EQ(ok, expect) << "ref camera " << m.toCamera(p) << " raster " << pr.x << " " << pr.y;
            if (!ok || !expect) {
                ++rejected;
                continue;
            }
            ++accepted;
            const Vec3 toLens = s.pLens.p - p;
            const double dist = toLens.length(), cosL = std::abs(Dot(toLens, m.z)) / dist;
            EXPECT_LT(Dist(s.wi, toLens / dist), 1e-12);
            EXPECT_LT(Dist(s.pLens.n, m.z), 1e-12);
            EXPECT_NEAR(s.pdf / (dist * dist / (cosL * m.lensArea())), 1, 1e-10);
            EXPECT_NEAR(s.We[0] / m.We(cosL), 1, 1e-9);
            EXPECT_NEAR(s.pRaster.x, pr.x, 1e-9 * c.res.x);
            EXPECT_NEAR(s.pRaster.y, pr.y, 1e-9 * c.res.y);
            EXPECT_EQ(s.We[0], cam->We(Ray(s.pLens.p, -s.wi), nullptr)[0]);
        }
        EXPECT_GT(accepted, 500);
        EXPECT_GT(rejected, 500);
    }

    // Uniformity of the lens points (a reference point on the axis beyond the
    // plane of focus: every lens point sees it inside the image).
    const Config c = ThinLens();
    auto cam = MakeCamera(c);
    const Model m(c);
    const Interaction ref(m.toWorld(0.1, -0.05, 7), Normal3(0, 0, 0), Vec3(0, 0, 0));
    auto lensSample = [&](RNG &rng, Point2 *q) {
        CameraWiSample s;
        if (!cam->sampleWi(ref, Point2(rng.uniform(), rng.uniform()), &s)) return false;
        const Vec3 pl = m.toCamera(s.pLens.p);
        double phi = std::atan2(pl.y, pl.x);
        if (phi < 0) phi += 2 * M_PI;
        *q = Point2(std::min((pl.x * pl.x + pl.y * pl.y) / (m.R * m.R), 1 - 1e-12), std::min(phi / (2 * M_PI), 1 - 1e-12));
        return true;
    };
    chi2::Options o;
    o.xBins = o.yBins = 8;
    o.samples = 200000;
    o.alpha = 1e-3;
    o.seed = 16;
    const auto uniform = [](Point2) { return 1.0; };
    const chi2::Result r = chi2::PlanarTest(lensSample, uniform, o);
    EXPECT_TRUE(r.pass) << r.message;
    // Power: densities (1 - 0.06 t) / 0.97 in t = r^2 / R^2 or phi / 2 pi (+-3%),
    // by thinning the camera's samples.
    for (int axis = 0; axis < 2; ++axis) {
        RNG thin(17 + axis);
        auto biased = [&](RNG &rng, Point2 *q) {
            for (;;) {
                if (!lensSample(rng, q)) return false;
                if (thin.uniform() < 1 - 0.06 * (axis == 0 ? q->x : q->y)) return true;
            }
        };
        const chi2::Result rb = chi2::PlanarTest(biased, uniform, o);
        EXPECT_FALSE(rb.pass) << "a 3% bias went unseen: " << rb.message;
    }
}

// No importance for directions whose image lies outside the raster (just
// beyond each border), behind the camera or across it; just inside, some.
TEST(Perspective, NoImportanceOutsideTheImage) {
    for (const Config &c : {Window(), ThinLens()}) {
        SCOPED_TRACE(c.params);
        auto cam = MakeCamera(c);
        const Model m(c);
        RNG rng(18);
        for (int k = 0; k < 200; ++k) {
            const double t = rng.uniform(), e = 1e-4;
            const Point2 border[4][2] = {{Point2(e, t * c.res.y), Point2(-e, t * c.res.y)},
                                         {Point2(c.res.x - e, t * c.res.y), Point2(c.res.x + e, t * c.res.y)},
                                         {Point2(t * c.res.x, e), Point2(t * c.res.x, -e)},
                                         {Point2(t * c.res.x, c.res.y - e), Point2(t * c.res.x, c.res.y + e)}};
            // A lens point (the centre for the pinhole) and the plane-of-focus point of each raster position.
            const double a = 2 * M_PI * rng.uniform(), rl = m.R * std::sqrt(rng.uniform());
            const Vec3 o = m.toWorld(rl * std::cos(a), rl * std::sin(a), 0);
            const double depth = m.R > 0 ? m.fd : 1;
            for (const auto &b : border)
                for (int side = 0; side < 2; ++side) {
                    const Vec3 pc = m.planePoint(b[side]) * depth;
                    const Vec3 w = Normalize(m.toWorld(pc.x, pc.y, pc.z) - o);
                    Point2 got;
                    const double We = cam->We(Ray(o, w), &got)[0];
                    Float pdfPos, pdfDir;
                    cam->pdfWe(Ray(o, w), &pdfPos, &pdfDir);
                    EXPECT_NEAR(got.x, b[side].x, 1e-8);
                    EXPECT_NEAR(got.y, b[side].y, 1e-8);
                    EXPECT_EQ(We > 0, side == 0) << b[side].x << " " << b[side].y;
                    EXPECT_EQ(pdfDir > 0, side == 0);
                    EXPECT_EQ(pdfPos > 0, side == 0);
                    // Reversed and sideways rays.
                    EXPECT_EQ(cam->We(Ray(o, -w), nullptr)[0], 0);
                    cam->pdfWe(Ray(o, -w), &pdfPos, &pdfDir);
                    EXPECT_EQ(pdfPos + pdfDir, 0);
                }
            EXPECT_EQ(cam->We(Ray(o, m.x), nullptr)[0], 0);
        }
    }
}

}  // namespace
}  // namespace gradus
