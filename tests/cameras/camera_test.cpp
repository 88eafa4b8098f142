// Orthographic, environment and realistic cameras: rays against the analytic
// projections (pbrt-v3's screen window, the lat-long formula), the realistic
// camera against a thin lens and a thick lens of known focal length (lensmaker's
// equation), its pbrt-v3 weighting (both modes) rendered by path and bdpt against
// a closed form, lens-file errors, refusals, and orthographic renders by path and
// bdpt (bdpt without light tracing) against a closed-form image.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <fstream>

#include "cameras/environment.h"
#include "cameras/orthographic.h"
#include "cameras/realistic.h"
#include "common/render_test_util.h"
#include "core/error.h"
#include "samplers/rng.h"

namespace gradus {
namespace {

// pbrt-v3's LookAt camera frame, built independently of Transform: camera x
// (right), y (up) and z (view) axes in world space.
struct Frame {
    Vec3 eye, x, y, z;
};
Frame LookAtFrame(Vec3 eye, Vec3 target, Vec3 up) {
    Frame f;
    f.eye = eye;
    f.z = Normalize(target - eye);
    f.x = Normalize(Cross(Normalize(up), f.z));
    f.y = Cross(f.z, f.x);
    return f;
}

SceneDesc Parse(const std::string &camera, const std::string &lookAt = "1 2 3  0.5 -1 0.2  0 1 0") {
    return ParseString("LookAt " + lookAt + "\n" + camera + "\nWorldBegin\nWorldEnd\n", "test.pbrt");
}

TEST(Orthographic, RaysAreTheAnalyticProjection) {
    const Point2i res{40, 30};
    const Frame f = LookAtFrame(Vec3(1, 2, 3), Vec3(0.5, -1, 0.2), Vec3(0, 1, 0));
    const float sw[4] = {-3.2f, 2.0f, -1.5f, 2.4f};
    SceneDesc d = Parse("Camera \"orthographic\" \"float screenwindow\" [-3.2 2.0 -1.5 2.4]");
    auto cam = CreateCamera(d.camera, res, &d);
    EXPECT_FALSE(cam->hasImportance());
    RNG rng(5);
    for (int k = 0; k < 200; ++k) {
        CameraSample cs{Point2(rng.uniform() * res.x, rng.uniform() * res.y), Point2(rng.uniform(), rng.uniform())};
        Ray r;
        ASSERT_EQ(cam->generateRay(cs, &r), 1);
        const double sx = sw[0] + cs.pFilm.x / res.x * (sw[1] - sw[0]);
        const double sy = sw[3] - cs.pFilm.y / res.y * (sw[3] - sw[2]);
        const Vec3 o = f.eye + f.x * sx + f.y * sy;
        EXPECT_NEAR(r.o.x, o.x, 1e-6);
        EXPECT_NEAR(r.o.y, o.y, 1e-6);
        EXPECT_NEAR(r.o.z, o.z, 1e-6);
        EXPECT_NEAR(Dot(r.d, f.z), 1, 1e-12);
        // pdfPos is the uniform density over the screen window's area; none outside the image.
        Float pdfPos, pdfDir;
        cam->pdfWe(r, &pdfPos, &pdfDir);
        EXPECT_NEAR(pdfPos * std::abs((sw[1] - sw[0]) * (sw[3] - sw[2])), 1, 1e-5);
        EXPECT_EQ(pdfDir, 0);
        cam->pdfWe(Ray(r.o + f.x * 10, r.d), &pdfPos, &pdfDir);
        EXPECT_EQ(pdfPos, 0);
    }
}

TEST(Orthographic, DefaultWindowFollowsTheAspectRatio) {
    // 2:1 film: the window is [-2,2] x [-1,1] (pbrt-v3); the corner pixel's ray starts at (-2, 1).
    SceneDesc d = Parse("Camera \"orthographic\"", "0 0 0  0 0 1  0 1 0");
    auto cam = CreateCamera(d.camera, Point2i{20, 10}, &d);
    Ray r;
    cam->generateRay(CameraSample{Point2(0, 0), Point2(0.5, 0.5)}, &r);
    EXPECT_NEAR(r.o.x, -2, 1e-9);
    EXPECT_NEAR(r.o.y, 1, 1e-9);
    EXPECT_NEAR(r.o.z, 0, 1e-9);
}

// Thin lens: rays of one film point start uniformly on the lens disc around
// the pinhole ray and all meet it on the plane of focus. E[r^2] = R^2 / 2 for
// a uniform disc: z-test at |z| < 4 (false-positive rate 6e-5), and 20000
// samples put 4 standard errors below a 5% error in R^2.
TEST(Orthographic, ThinLensFocusesOnThePlaneOfFocus) {
    const double R = 0.3, fd = 4;
    SceneDesc d = Parse("Camera \"orthographic\" \"float lensradius\" 0.3 \"float focaldistance\" 4",
                        "0 0 0  0 0 1  0 1 0");
    auto cam = CreateCamera(d.camera, Point2i{20, 20}, &d);
    RNG rng(9);
    const int n = 20000;
    double sum = 0, sum2 = 0;
    for (int k = 0; k < n; ++k) {
        CameraSample cs{Point2(13.3, 4.1), Point2(rng.uniform(), rng.uniform())};
        Ray r;
        cam->generateRay(cs, &r);
        const double px = -1 + 2 * 13.3 / 20, py = 1 - 2 * 4.1 / 20;  // the pinhole ray's origin
        const double t = (fd - r.o.z) / r.d.z;
        EXPECT_NEAR(r.o.x + t * r.d.x, px, 1e-9);
        EXPECT_NEAR(r.o.y + t * r.d.y, py, 1e-9);
        const double r2 = (r.o.x - px) * (r.o.x - px) + (r.o.y - py) * (r.o.y - py);
        EXPECT_LE(r2, R * R * (1 + 1e-9));
        sum += r2;
        sum2 += r2 * r2;
        // The same ray through rayThrough, holding its lens point.
        Ray r2ray;
        ASSERT_TRUE(cam->rayThrough(r.o, cs.pFilm, &r2ray));
        EXPECT_NEAR(Dot(r2ray.d, r.d), 1, 1e-9);
    }
    const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_LT(std::abs(mean - R * R / 2) / se, 4) << mean;
    EXPECT_LT(4 * se, 0.05 * R * R / 2);  // power: a 5% error would be seen
}

TEST(Environment, DirectionsAreTheLatLongFormula) {
    const Point2i res{64, 32};
    const Frame f = LookAtFrame(Vec3(1, 2, 3), Vec3(0.5, -1, 0.2), Vec3(0, 1, 0));
    SceneDesc d = Parse("Camera \"environment\"");
    auto cam = CreateCamera(d.camera, res, &d);
    EXPECT_FALSE(cam->hasImportance());
    RNG rng(3);
    for (int k = 0; k < 500; ++k) {
        CameraSample cs{Point2(rng.uniform() * res.x, rng.uniform() * res.y), Point2(0.5, 0.5)};
        Ray r;
        ASSERT_EQ(cam->generateRay(cs, &r), 1);
        EXPECT_NEAR(r.o.x, f.eye.x, 1e-9);
        EXPECT_NEAR(r.o.y, f.eye.y, 1e-9);
        EXPECT_NEAR(r.o.z, f.eye.z, 1e-9);
        // Back to camera-space spherical angles: theta from +y, phi from +x towards +z.
        const double cx = Dot(r.d, f.x), cy = Dot(r.d, f.y), cz = Dot(r.d, f.z);
        const double theta = std::acos(std::clamp(cy, -1.0, 1.0));
        double phi = std::atan2(cz, cx);
        if (phi < 0) phi += 2 * M_PI;
        EXPECT_NEAR(theta, M_PI * cs.pFilm.y / res.y, 1e-6);
        EXPECT_NEAR(phi, 2 * M_PI * cs.pFilm.x / res.x, 1e-6);
    }
}

// Refusal: integrators that need the camera's importance name the camera.
TEST(Cameras, BidirectionalIntegratorsRefuseCamerasWithoutImportance) {
    for (const char *cam : {"orthographic", "environment"})
        for (const char *integ : {"vcm", "mbdpt", "mlt"}) {
            const std::string text = std::string("LookAt 0 0 0 0 0 1 0 1 0\nCamera \"") + cam +
                                     "\"\nFilm \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                                     "Integrator \"" + integ + "\"\nWorldBegin\nLightSource \"infinite\"\nWorldEnd\n";
            BuildOptions bo;
            bo.quiet = true;
            bo.checkOutput = false;
            try {
                BuildRenderJob(ParseString(text, "test.pbrt"), bo);
                ADD_FAILURE() << integ << " accepted " << cam;
            } catch (const Error &e) {
                const std::string m = e.what();
                EXPECT_NE(m.find("test.pbrt:4:1"), std::string::npos) << m;
                EXPECT_NE(m.find(integ), std::string::npos) << m;
                EXPECT_NE(m.find(cam), std::string::npos) << m;
            }
        }
}

// A diffuse plane y = 0 (albedo 0.5) lit by a point light of intensity 1 at
// height 1, seen from above through a 16 x 16 orthographic window [-1,1]^2:
// pixel radiance (0.5 / pi) h / d^3 averaged over the pixel (box filter),
// computed by an 8 x 8 midpoint rule. Only length-2 paths exist: bdpt's NEE
// (s = 1, t = 2) must carry all of it with light tracing out of play; left in
// its MIS sums, the image would be about half as bright.
void ExpectOrthoPointLightImage(const std::string &integrator) {
    const Vec3 light(0.3, 1, 0.2);
    const std::string text =
        "LookAt 0 3 0  0 0 0  0 0 1\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
        "Sampler \"random\" \"integer pixelsamples\" 16\nPixelFilter \"box\"\n"
        "Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\nIntegrator \"" + integrator +
        "\"\nWorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1] \"point from\" [0.3 1 0.2]\n"
        "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-5 0 -5  -5 0 5  5 0 5  5 0 -5]\n"
        "WorldEnd\n";
    test::TestRender r = test::RenderTestDesc(ParseString(text, "test.pbrt"), 16, 7);
    double sumRes = 0, sumRes2 = 0, sumExact = 0;
    const int n = 16 * 16;
    for (int py = 0; py < 16; ++py)
        for (int px = 0; px < 16; ++px) {
            double exact = 0;
            for (int a = 0; a < 8; ++a)
                for (int b = 0; b < 8; ++b) {
                    // Screen (sx, sy) is world (sx, 0, sy) for this LookAt.
                    const double sx = -1 + 2 * (px + (a + 0.5) / 8) / 16, sy = 1 - 2 * (py + (b + 0.5) / 8) / 16;
                    const Vec3 d = light - Vec3(sx, 0, sy);
                    const double dist = d.length();
                    exact += 0.5 / M_PI * light.y / (dist * dist * dist) / 64;
                }
            const double v = r.image.at(px, py, 1), res = v - exact;
            sumRes += res, sumRes2 += res * res, sumExact += exact;
        }
    const double meanRes = sumRes / n, se = std::sqrt(std::max(0.0, sumRes2 / n - meanRes * meanRes) / n);
    const double meanExact = sumExact / n;
    // |z| < 4 (false-positive rate 6e-5), with a floor of 0.2% for the quadrature.
    EXPECT_LT(std::abs(meanRes), std::max(4 * se, 2e-3 * meanExact)) << integrator << " mean " << meanExact + meanRes
                                                                       << " exact " << meanExact;
    EXPECT_LT(4 * se, 0.01 * meanExact) << "power: a 1% error must be detectable";
}

TEST(Orthographic, PathRendersTheClosedFormImage) { ExpectOrthoPointLightImage("path"); }
TEST(Orthographic, BdptWithoutLightTracingRendersTheClosedFormImage) { ExpectOrthoPointLightImage("bdpt"); }

// ---------------------------------------------------------------- realistic
constexpr int kPupilSamples = 1 << 12;  // enough for these simple lenses, quick to build

// Biconvex lens R1 = -R2 = 50 mm, n = 1.5, 0.1 mm thick (the least that keeps a
// 2 mm aperture's edge positive): near the thin-lens limit f = R / (2 (n - 1))
// = 50 mm (lensmaker's equation, Hecht, Optics, Eq. 5.16); the thickness term
// changes f by 3.3e-4 and moves the principal planes by ~0.03 mm.
std::vector<LensElement> ThinLens() { return {{50, 0.1, 1.5, 2}, {-50, 0, 1, 2}}; }

TEST(Realistic, ThinLensLimitFocalLengthAndImageDistance) {
    const double D = 1;  // focus distance (m), from the film
    RealisticCamera cam(Transform(), Point2i{32, 32}, ThinLens(), 1, D, 35, true, 1, FileLoc(), kPupilSamples);
    const double f = 0.05;
    EXPECT_NEAR(cam.focalLength(), f, 5e-4 * f);
    // Thin lens: s_o + s_i = D and 1/s_o + 1/s_i = 1/f.
    const double si = (D - std::sqrt(D * D - 4 * f * D)) / 2, so = D - si;
    EXPECT_NEAR(cam.rearZ(), si, 3e-5);
    // Every ray from a film point near the axis passes (nearly: aberrations at
    // f/25) through its conjugate point on the plane of focus, -so/si times the film point.
    RNG rng(1);
    double worst = 0;
    for (Point2 raster : {Point2(16, 16), Point2(16.6, 15.7)}) {
        const Point2 pf = cam.filmPoint(raster);
        const double X = -pf.x * so / si, Y = -pf.y * so / si;
        int hits = 0;
        for (int k = 0; k < 400; ++k) {
            Ray r;
            if (cam.generateRay(CameraSample{raster, Point2(rng.uniform(), rng.uniform())}, &r) == 0) continue;
            ++hits;
            const double t = (D - r.o.z) / r.d.z;
            worst = std::max(worst, std::hypot(r.o.x + t * r.d.x - X, r.o.y + t * r.d.y - Y));
        }
        EXPECT_GT(hits, 100);
    }
    // A 1% error in the film distance moves the plane of focus by (so/si)^2 *
    // 0.01 si = 0.17 m, a blur of radius ~0.18 mm there; the measured spread
    // (aberrations) is 0.025 mm.
    EXPECT_LT(worst, 5e-5) << worst;
}

// A thick biconvex lens: R1 = 40 mm, R2 = -60 mm, 8 mm of n = 1.6. Lensmaker's
// equation with thickness: 1/f = (n-1) (1/R1 - 1/R2 + (n-1) d / (n R1 R2)),
// back focal distance f (1 - (n-1) d / (n R1)) (Hecht, Optics, Eqs. 6.2, 6.3).
TEST(Realistic, ThickLensFocusedAtInfinityImagesParallelRaysOnTheFilm) {
    const double R1 = 40, R2 = -60, d = 8, n = 1.6;
    const double f = 1e-3 / ((n - 1) * (1 / R1 - 1 / R2 + (n - 1) * d / (n * R1 * R2)));
    const double bfd = f * (1 - (n - 1) * d / (n * R1));
    std::vector<LensElement> lens = {{R1, d, n, 20}, {R2, 0, 1, 20}};
    RealisticCamera cam(Transform(), Point2i{32, 32}, lens, 1, 1e7, 35, true, 1, FileLoc(), kPupilSamples);
    EXPECT_NEAR(cam.focalLength(), f, 1e-5 * f);
    EXPECT_NEAR(cam.rearZ(), bfd, 1e-7);  // focused at 1e7 m: the film on the back focal plane
    // Paraxial parallel rays from the scene converge on the film (z = 0).
    for (double h : {0.0001, 0.0002, -0.00015}) {
        Ray out;
        ASSERT_TRUE(cam.traceFromScene(Ray(Point3(h, 0.3 * h, cam.frontZ() + 0.01), Vec3(0, 0, -1)), &out));
        const double t = -out.o.z / out.d.z;
        EXPECT_LT(std::hypot(out.o.x + t * out.d.x, out.o.y + t * out.d.y), 1e-4 * std::abs(h)) << h;
    }
}

TEST(Realistic, CentreWeightIsOneAndFallsOffOutwards) {
    RealisticCamera cam(Transform(), Point2i{32, 32}, ThinLens(), 1, 1, 35, true, 1, FileLoc(), kPupilSamples);
    RNG rng(2);
    double centre = 0, corner = 0;
    int nc = 0, nk = 0;
    for (int k = 0; k < 2000; ++k) {
        Ray r;
        const Float w0 = cam.generateRay(CameraSample{Point2(16, 16), Point2(rng.uniform(), rng.uniform())}, &r);
        const Float w1 = cam.generateRay(CameraSample{Point2(0.5, 0.5), Point2(rng.uniform(), rng.uniform())}, &r);
        EXPECT_TRUE(std::isfinite(w0) && std::isfinite(w1));
        if (w0 > 0) centre += w0, ++nc;
        if (w1 > 0) corner += w1, ++nk;
    }
    ASSERT_GT(nc, 0);
    ASSERT_GT(nk, 0);
    EXPECT_NEAR(centre / nc, 1, 1e-3);  // cos^4 ~ 1 on the axis, the band's own pupil
    EXPECT_LT(corner / nk, centre / nc);
}

// ctest runs the cases of this file in parallel processes: the file name carries the pid.
std::string WriteLens(const std::string &name, const std::string &text) {
    const std::string path = testing::TempDir() + std::to_string(::getpid()) + "_" + name;
    std::ofstream(path) << text;
    return path;
}

void ExpectLensError(const std::string &lensPath, const std::string &where, const std::string &what,
                     const std::string &extra = "") {
    const std::string text = "LookAt 0 0 0 0 0 1 0 1 0\nCamera \"realistic\" \"string lensfile\" \"" + lensPath +
                             "\"" + extra + "\nWorldBegin\nWorldEnd\n";
    try {
        BuildScene(ParseString(text, "test.pbrt"), Point2i{8, 8});
        ADD_FAILURE() << "no error for " << lensPath;
    } catch (const Error &e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(where), std::string::npos) << m;
        EXPECT_NE(m.find(what), std::string::npos) << m;
    }
}

// pbrt-v3's realistic-camera weighting against a closed form. Lens: a biconvex
// lens (R = +-50 mm, 3 mm of n = 1.5, 16 mm wide, 1.7 mm thick at the rim) and
// 2 mm behind it the aperture stop (4 mm) as the rear element: a ray from any
// film point passes exactly when it crosses the stop's plane within a = 2 mm of
// the axis (the lens is wide enough never to vignette: such rays meet it within
// 4 mm of the axis), so the exit pupil is that disk for every film point. The camera sits in a uniform environment of radiance L = 1. With
// pbrt-v3's GenerateRay a sample is traced from the film point p to a uniform
// point of the band's pupil bound B (area A_B) and weighs cos^4(theta) A_B / d^2
// (shutter time 1) or, with simple weighting, cos^4(theta) A_B / A_0 (A_0: the
// centre band's bound), 0 when blocked; so the pixel is the film-pixel average of
//   E[w] = (1 / d^2) int_disk cos^4 dA = pi F(r)            (simpleweighting false)
//   E[w] = (d^2 / A_0) pi F(r)                               (simpleweighting true)
// with d the stop-to-film distance, r = |p| and F the view factor from a
// differential area parallel to a coaxial disk of radius a at distance d, offset
// r: F = (1 - (d^2 + r^2 - a^2) / sqrt((d^2 + r^2 + a^2)^2 - 4 a^2 r^2)) / 2.
// Every band's bound is the same here (the same 2^20 radical-inverse points pass),
// A_0 = (bounding box of the points of [-1.5 a, 1.5 a]^2 inside the disk, grown
// by twice the square's diagonal over 2^10 on each side)^2 area, computed below.
// The film: pbrt-v3's physical extent, diagonal 35 mm split by the aspect ratio.
double RadicalInverse(int base, uint64_t i) {
    double inv = 1.0 / base, f = inv, r = 0;
    for (; i; i /= base, f *= inv) r += double(i % base) * f;
    return r;
}

double DiskViewFactor(double d, double r, double a) {
    return 0.5 * (1 - (d * d + r * r - a * a) / std::sqrt(Sqr(d * d + r * r + a * a) - 4 * a * a * r * r));
}

void ExpectRealisticWeighting(const std::string &integrator, bool simple) {
    const std::string lens = WriteLens("gradus_lens_rearstop.dat", "50 3 1.5 16\n-50 2 1 16\n0 40 0 4\n");
    const int W = 24, H = 16;
    const std::string text = "LookAt 0 0 0 0 0 1 0 1 0\nCamera \"realistic\" \"string lensfile\" \"" + lens +
                             "\" \"float aperturediameter\" 4 \"float focusdistance\" 2 \"bool simpleweighting\" \"" +
                             (simple ? "true" : "false") + "\"\nSampler \"random\" \"integer pixelsamples\" 256\n"
                             "PixelFilter \"box\"\nFilm \"image\" \"integer xresolution\" 24 \"integer yresolution\" 16 "
                             "\"float diagonal\" 35\nIntegrator \"" + integrator + "\" \"integer maxdepth\" 1\n"
                             "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nWorldEnd\n";
    const SceneDesc desc = ParseString(text, "test.pbrt");
    RenderJob job = test::MakeTestJob(desc, 256, 11);
    const auto *cam = dynamic_cast<const RealisticCamera *>(job.scene->camera.get());
    ASSERT_NE(cam, nullptr);
    const double d = cam->rearZ(), a = 2e-3, s = 1.5 * a;
    const int n = 1 << 20;
    double x0 = 1, y0 = 1, x1 = -1, y1 = -1;
    for (int i = 0; i < n; ++i) {
        const double x = -s + 2 * s * RadicalInverse(2, i), y = -s + 2 * s * RadicalInverse(3, i);
        if (x * x + y * y > a * a) continue;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
    const double grow = 2 * std::sqrt(2.0) * 2 * s / std::sqrt(double(n));
    const double A0 = (x1 - x0 + 2 * grow) * (y1 - y0 + 2 * grow);
    const double scale = simple ? d * d / A0 : 1;
    const double diag = 35e-3, fx = std::sqrt(diag * diag / (1 + Sqr(double(H) / W))), fy = fx * H / W;
    test::TestRender r = test::RenderTestJob(std::move(job), 256, 11);
    // Residuals over the image and over the outer ring (r > 0.6 of the half-diagonal).
    double sum[2] = {0, 0}, sum2[2] = {0, 0}, exactSum[2] = {0, 0};
    int count[2] = {0, 0};
    for (int py = 0; py < H; ++py)
        for (int px = 0; px < W; ++px) {
            double exact = 0, rc = 0;
            for (int i = 0; i < 8; ++i)
                for (int j = 0; j < 8; ++j) {
                    const double x = fx * ((px + (i + 0.5) / 8) / W - 0.5), y = fy * ((py + (j + 0.5) / 8) / H - 0.5);
                    exact += Pi * DiskViewFactor(d, std::hypot(x, y), a) * scale / 64;
                }
            rc = std::hypot(fx * ((px + 0.5) / W - 0.5), fy * ((py + 0.5) / H - 0.5));
            const double res = r.image.at(px, py, 1) - exact;
            for (int k = 0; k < 2; ++k) {
                if (k == 1 && rc < 0.6 * diag / 2) continue;
                sum[k] += res, sum2[k] += res * res, exactSum[k] += exact, ++count[k];
            }
        }
    for (int k = 0; k < 2; ++k) {
        const double mean = sum[k] / count[k], se = std::sqrt((sum2[k] / count[k] - mean * mean) / count[k]);
        const double meanExact = exactSum[k] / count[k];
        // |z| < 4 (false-positive rate 6e-5 per check); power: 4 se under 1.5% of the value.
        EXPECT_LT(std::abs(mean), 4 * se) << integrator << (simple ? " simple" : "") << (k ? " outer ring" : " image")
                                          << ": mean " << meanExact + mean << " exact " << meanExact;
        EXPECT_LT(4 * se, 0.015 * meanExact) << "power";
    }
}

TEST(Realistic, PathWeightsAsPbrtV3) { ExpectRealisticWeighting("path", false); }
TEST(Realistic, PathSimpleWeightingAsPbrtV3) { ExpectRealisticWeighting("path", true); }
TEST(Realistic, BdptSimpleWeightingAsPbrtV3) { ExpectRealisticWeighting("bdpt", true); }

TEST(Realistic, LensFileErrorsAreLocated) {
    const std::string good = "# thin lens\n50 0.1 1.5 2\n-50 0 1 2\n";
    const std::string ok = WriteLens("gradus_lens_ok.dat", good);
    EXPECT_NO_THROW(BuildScene(ParseString("LookAt 0 0 0 0 0 1 0 1 0\nCamera \"realistic\" \"string lensfile\" \"" +
                                               ok + "\" \"float focusdistance\" 2\nWorldBegin\nWorldEnd\n",
                                           "test.pbrt"),
                               Point2i{8, 8}));
    const std::string p3 = WriteLens("gradus_lens_row3.dat", "# thin lens\n50 0.1 1.5 2\n-50 0 1\n");
    ExpectLensError(p3, p3 + ":3:1", "4 numbers");
    const std::string pn = WriteLens("gradus_lens_nan.dat", "50 0.1 x1.5 2\n-50 0 1 2\n");
    ExpectLensError(pn, pn + ":1:8", "not a finite number");
    const std::string pe = WriteLens("gradus_lens_empty.dat", "# nothing\n");
    ExpectLensError(pe, "test.pbrt:2:", "no element");
    ExpectLensError(testing::TempDir() + "gradus_no_such_lens.dat", "test.pbrt:2:", "cannot open");
    // Focusing closer than the lens can (4 f = 0.2 m) is refused at "focusdistance".
    ExpectLensError(ok, "test.pbrt:2:", "too short", " \"float focusdistance\" 0.1");
    ExpectLensError(ok, "test.pbrt:2:", "aperturdiameter", " \"float aperturdiameter\" 2");
}

TEST(Realistic, VcmRefusesIt) {
    const std::string lens = WriteLens("gradus_lens_refuse.dat", "50 0.1 1.5 2\n-50 0 1 2\n");
    const std::string text = "LookAt 0 0 0 0 0 1 0 1 0\nCamera \"realistic\" \"string lensfile\" \"" + lens +
                             "\" \"float focusdistance\" 2\n"
                             "Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\n"
                             "Integrator \"vcm\"\nWorldBegin\nLightSource \"infinite\"\nWorldEnd\n";
    BuildOptions bo;
    bo.quiet = true;
    bo.checkOutput = false;
    try {
        BuildRenderJob(ParseString(text, "test.pbrt"), bo);
        ADD_FAILURE() << "vcm accepted the realistic camera";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("test.pbrt:4:1: Integrator \"vcm\" does not render Camera \"realistic\""),
                  std::string::npos)
            << e.what();
    }
}

}  // namespace
}  // namespace gradus
