// pbrt-v3's whitted, directlighting and ambientocclusion integrators against
// closed forms, evaluated here without any renderer code:
//   ambient occlusion of a floor point in front of a wall of height h,
//   direct lighting of a diffuse floor by a sphere light and a point light,
//   whitted through a mirror equal to the mirrored scene, and through a
//   glass slab equal to T^2 (1 + R^2) times the radiance behind it.
// Statistical checks are t-tests over groups of pixels with one expectation
// (fixed seeds, threshold |t| < 5: false-positive rate below 1e-4 per test;
// each also asserts that a 3% error of the expected value is rejected).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "image/image.h"
#include "render/render_util.h"

using namespace gradus;
using namespace gradus::test;

namespace {

constexpr double kPi = 3.14159265358979323846;

// An orthographic camera at height 5 looking straight down at the floor y = 0,
// image up = +z: it sees x in [-1, 1], z in [z0, z0 + 2]. Box filter, random sampler.
std::string TopView(int w, int h, double z0, const std::string &integrator) {
    std::ostringstream s;
    s << "LookAt 0 5 " << z0 + 1 << "  0 0 " << z0 + 1 << "  0 0 1\n"
      << "Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
      << "Film \"image\" \"integer xresolution\" [" << w << "] \"integer yresolution\" [" << h
      << "] \"string filename\" \"out.exr\"\n"
      << "PixelFilter \"box\"\nSampler \"random\"\n"
      << integrator << "\nWorldBegin\n";
    return s.str();
}

const char *kFloor =
    "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-50 0 -50  50 0 -50  50 0 50  -50 0 50]\n";

// World point (x, z) on the floor at the centre of a sub-pixel position (u, v in [0, 1)) of pixel (px, py).
void FloorPoint(int px, int py, double u, double v, int w, int h, double z0, double *x, double *z) {
    *x = -1 + 2 * (px + u) / w;           // raster x grows with world x or against it: the tests' closed
    *z = z0 + 2 - 2 * (py + v) / h;       // forms are even in x; raster y = 0 is the top, +z
}

// The mean of f over pixel (px, py)'s footprint on the floor (midpoint rule, 8 x 8).
double PixelAverage(int px, int py, int w, int h, double z0, const std::function<double(double, double)> &f) {
    double s = 0;
    for (int j = 0; j < 8; ++j)
        for (int i = 0; i < 8; ++i) {
            double x, z;
            FloorPoint(px, py, (i + 0.5) / 8, (j + 0.5) / 8, w, h, z0, &x, &z);
            s += f(x, z);
        }
    return s / 64;
}

// One-sample t statistic of the residuals value - expected over a group of pixels.
struct GroupT {
    double sum = 0, sum2 = 0;
    int n = 0;
    void add(double r) { sum += r, sum2 += r * r, ++n; }
    double t(double shift = 0) const {  // t of (residual - shift)
        const double m = sum / n - shift;
        const double var = std::max(1e-30, (sum2 - sum * sum / n) / (n - 1));
        return m / std::sqrt(var / n);
    }
};

// Checks every group: |t| < 5 for the residuals, and a 3% error of the group's
// mean expectation is seen (|t| > 5 for the shifted residuals).
void CheckGroups(const std::vector<GroupT> &groups, const std::vector<double> &expectedMean, const std::string &what) {
    for (size_t g = 0; g < groups.size(); ++g) {
        EXPECT_LT(std::abs(groups[g].t()), 5) << what << ": group " << g << " mean residual " << groups[g].sum / groups[g].n
                                              << " (expected mean " << expectedMean[g] << ")";
        EXPECT_GT(std::abs(groups[g].t(0.03 * expectedMean[g])), 5) << what << ": group " << g << " lacks power";
    }
}

// Ambient occlusion at distance d in front of an infinitely wide wall of height
// h on an infinite floor: pi minus the occluded part of the integral of cos over
// the hemisphere. At azimuth phi from the wall's normal the wall hides
// elevations e < E(phi), tan E = h cos(phi) / d; integral of sin(e) cos(e) de over
// [0, E] is sin^2(E) / 2 (Simpson's rule over phi).
double AOFrontOfWall(double d, double h) {
    const int n = 2000;
    auto g = [&](double phi) {
        const double t = h * std::cos(phi) / d;
        return 0.5 * t * t / (1 + t * t);
    };
    double s = g(-kPi / 2) + g(kPi / 2);
    for (int i = 1; i < n; ++i) s += g(-kPi / 2 + kPi * i / n) * (i % 2 ? 4 : 2);
    return kPi - s * (kPi / n) / 3;
}

}  // namespace

TEST(AmbientOcclusion, FloorInFrontOfAWallMatchesClosedForm) {
    const double h = 0.6, z0 = -2.0;  // the wall stands at z = 0, the view covers z in [-2, 0]
    const int w = 64, hgt = 16;
    for (const char *cos : {"true", "false"}) {
        SCOPED_TRACE(std::string("cossample ") + cos);
        std::string scene = TopView(w, hgt, z0,
                                    std::string("Integrator \"ambientocclusion\" \"integer nsamples\" [64] \"bool cossample\" ") +
                                        cos) +
                            kFloor +
                            "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                            "[-500 0 0  500 0 0  500 " + std::to_string(h) + " 0  -500 " + std::to_string(h) + " 0]\n"
                            "WorldEnd\n";
        RenderResult r = RenderSceneText(scene, 48, 7);
        ASSERT_EQ(r.image.width(), w);
        // Each image row has one expectation (the wall is infinitely wide).
        std::vector<GroupT> rows(hgt);
        std::vector<double> expected(hgt);
        for (int py = 0; py < hgt; ++py) {
            expected[py] = PixelAverage(0, py, w, hgt, z0, [&](double, double z) { return AOFrontOfWall(-z, h); });
            for (int px = 0; px < w; ++px) rows[py].add(r.image.at(px, py, 0) - expected[py]);
        }
        EXPECT_LT(expected[0], 0.7 * kPi);  // the rows near the wall are well occluded
        EXPECT_GT(expected[hgt - 1], 0.9 * kPi);
        CheckGroups(rows, expected, "ambient occlusion");
    }
}

// A point with nothing above it: pi (pbrt-v3's scale), exactly with cosine
// sampling (every unoccluded direction adds cos / pdf = pi).
TEST(AmbientOcclusion, OpenFloorIsPi) {
    std::string scene = TopView(8, 8, -1, "Integrator \"ambientocclusion\" \"integer nsamples\" [4]") + kFloor +
                        "WorldEnd\n";
    RenderResult r = RenderSceneText(scene, 2, 3);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) EXPECT_NEAR(r.image.at(x, y, 1), kPi, 1e-4);
}

// Direct lighting of a diffuse floor (Kd 0.5) by a sphere light (radius r,
// radiance Le, wholly above the floor's horizon: outgoing radiance
// Kd Le (r / D)^2 cos(beta), D the distance to the centre, beta its angle from
// the normal) and a point light (Kd / pi I cos / d^2).
namespace {
const double kKd = 0.5, kR = 0.5, kLe = 10, kI = 3;
const double kC[3] = {0.3, 1.5, 2.5};   // sphere centre: outside the view (z in [-2, 0])
const double kP[3] = {-0.4, 1.2, -1.0};  // point light: above the view
double SphereTerm(double x, double z) {
    const double dx = kC[0] - x, dy = kC[1], dz = kC[2] - z, D2 = dx * dx + dy * dy + dz * dz;
    return kKd * kLe * kR * kR / D2 * (dy / std::sqrt(D2));
}
double PointTerm(double x, double z) {
    const double dx = kP[0] - x, dy = kP[1], dz = kP[2] - z, d2 = dx * dx + dy * dy + dz * dz;
    return kKd / kPi * kI * (dy / std::sqrt(d2)) / d2;
}
std::string LitFloor(const std::string &integrator, bool pointLight, int samples = 1) {
    std::ostringstream s;
    s << TopView(32, 32, -2, integrator);
    if (pointLight)
        s << "LightSource \"point\" \"point from\" [" << kP[0] << " " << kP[1] << " " << kP[2] << "] \"rgb I\" [" << kI
          << " " << kI << " " << kI << "]\n";
    s << "AttributeBegin\n  Translate " << kC[0] << " " << kC[1] << " " << kC[2] << "\n"
      << "  AreaLightSource \"diffuse\" \"rgb L\" [" << kLe << " " << kLe << " " << kLe << "] \"integer samples\" ["
      << samples << "]\n  Shape \"sphere\" \"float radius\" [" << kR << "]\nAttributeEnd\n"
      << kFloor << "WorldEnd\n";
    return s.str();
}
// 4 x 4 blocks of 8 x 8 pixels, residuals against the closed form per pixel.
void CheckLitFloor(const Image &img, bool pointLight, const std::string &what) {
    std::vector<GroupT> blocks(16);
    std::vector<double> expected(16, 0);
    for (int py = 0; py < 32; ++py)
        for (int px = 0; px < 32; ++px) {
            const double e = PixelAverage(px, py, 32, 32, -2, [&](double x, double z) {
                return SphereTerm(x, z) + (pointLight ? PointTerm(x, z) : 0);
            });
            const int b = (py / 8) * 4 + px / 8;
            blocks[b].add(img.at(px, py, 0) - e);
            expected[b] += e / 64;
        }
    CheckGroups(blocks, expected, what);
}
}  // namespace

TEST(DirectLighting, DiffuseFloorUnderASphereAndAPointLight) {
    for (const char *strategy : {"all", "one"}) {
        SCOPED_TRACE(strategy);
        const std::string integ = std::string("Integrator \"directlighting\" \"string strategy\" \"") + strategy + "\"";
        // "one" picks one of the two lights per hit: more noise, more samples.
        const int spp = std::string(strategy) == "one" ? 1024 : 16;
        CheckLitFloor(RenderSceneText(LitFloor(integ, true), spp, 11).image, true, std::string("directlighting ") + strategy);
    }
    // The sphere light's "samples" (4 per hit with strategy all): same expectation.
    CheckLitFloor(RenderSceneText(LitFloor("Integrator \"directlighting\"", false, 4), 16, 12).image, false,
                  "directlighting, samples 4");
    // whitted: one light sample per light, no MIS; same expectation.
    CheckLitFloor(RenderSceneText(LitFloor("Integrator \"whitted\"", true), 16, 13).image, true, "whitted");
}

// whitted through a mirror (Kr 1) equals the mirrored scene seen directly:
// a diffuse quad behind the camera lit by a point light, seen in a mirror at
// z = 2, against the quad and the light reflected through that plane. A point
// light and a pinhole camera leave nothing random: equal within rounding.
TEST(Whitted, MirrorEqualsTheMirroredScene) {
    auto scene = [](bool mirror) {
        const double qz = mirror ? -3 : 7, lz = mirror ? -1 : 5;  // reflected through z = 2
        std::ostringstream s;
        s << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
          << "Film \"image\" \"integer xresolution\" [24] \"integer yresolution\" [24] \"string filename\" \"o.exr\"\n"
          << "PixelFilter \"box\"\nSampler \"random\"\nIntegrator \"whitted\"\nWorldBegin\n"
          << "LightSource \"point\" \"point from\" [0.4 0.8 " << lz << "] \"rgb I\" [2 2 2]\n"
          << "Material \"matte\" \"rgb Kd\" [0.6 0.4 0.3]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-4 -4 " << qz << "  4 -4 " << qz
          << "  4 4 " << qz << "  -4 4 " << qz << "]\n";
        if (mirror)
            s << "Material \"mirror\" \"rgb Kr\" [1 1 1]\n"
              << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-9 -9 2  9 -9 2  9 9 2  -9 9 2]\n";
        s << "WorldEnd\n";
        return s.str();
    };
    const Image a = RenderSceneText(scene(true), 2, 5).image, b = RenderSceneText(scene(false), 2, 5).image;
    double sum = 0;
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 24; ++x)
            for (int c = 0; c < 3; ++c) {
                sum += b.at(x, y, c);
                EXPECT_NEAR(a.at(x, y, c), b.at(x, y, c), 1e-4 * b.at(x, y, c) + 1e-7) << x << "," << y << "," << c;
            }
    EXPECT_GT(sum, 1);  // the quad is lit
}

// whitted through a glass slab (IOR 1.5, faces at z = 1 and z = 1.2) seen head
// on by an orthographic camera: every pixel sees the lit quad behind it times
// T^2 (1 + R^2), R = (0.5 / 2.5)^2 at normal incidence, T = 1 - R; R^2 is the
// one internal round trip that maxdepth 5 allows (recursion at depths 0..3).
// Both lobes of the glass are traced (pbrt-v3's reflect + transmit), so the
// image has no noise: every pixel within 1e-4.
TEST(Whitted, GlassSlabTransmitsTSquaredOnePlusRSquared) {
    auto scene = [](bool slab) {
        std::ostringstream s;
        s << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
          << "Film \"image\" \"integer xresolution\" [16] \"integer yresolution\" [16] \"string filename\" \"o.exr\"\n"
          << "PixelFilter \"box\"\nSampler \"random\"\nIntegrator \"whitted\" \"integer maxdepth\" [5]\nWorldBegin\n"
          << "LightSource \"point\" \"point from\" [0.5 0.3 2] \"rgb I\" [2 2 2]\n"
          << "Material \"matte\" \"rgb Kd\" [0.6 0.4 0.3]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-4 -4 3  4 -4 3  4 4 3  -4 4 3]\n";
        if (slab)
            s << "Material \"glass\" \"float index\" [1.5]\n"
              << "Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2  4 5 6  4 6 7] \"point P\" "
                 "[-3 -3 1  3 -3 1  3 3 1  -3 3 1   -3 -3 1.2  3 -3 1.2  3 3 1.2  -3 3 1.2]\n";
        s << "WorldEnd\n";
        return s.str();
    };
    const double R = 0.04, T = 1 - R, factor = T * T * (1 + R * R);
    const Image a = RenderSceneText(scene(true), 1, 5).image, b = RenderSceneText(scene(false), 1, 5).image;
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) {
            ASSERT_GT(b.at(x, y, 0), 0.01);
            EXPECT_NEAR(a.at(x, y, 0) / b.at(x, y, 0), factor, 1e-4) << x << "," << y;
        }
}

// A scene in an exporter's style: the integrator directlighting (several
// exporters' default), Includes of named materials and geometry, uber and
// glass, an image texture, a lat-long environment map and a distant light.
// It renders with the integrator its file names, and whitted (one light
// sample per light, no MIS) and directlighting (MIS of light and BSDF
// samples) compute the same transport with different estimators: their
// image means and 4 x 4 blocks agree by Welch's t (K = 12 runs each,
// |t| < 5.5: false-positive rate below 1e-3 over the 17 statistics), and a
// 5% scaling of one side is detected.
namespace {
struct Runs {
    std::vector<std::vector<double>> sets;  // per statistic, the run values
};
void AddRun(Runs *runs, const Image &img) {
    const int w = img.width(), h = img.height();
    std::vector<double> v(17, 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double l = (img.at(x, y, 0) + img.at(x, y, 1) + img.at(x, y, 2)) / 3;
            v[0] += l / (w * h);
            v[1 + (y * 4 / h) * 4 + x * 4 / w] += l * 16 / (w * h);
        }
    if (runs->sets.empty()) runs->sets.resize(17);
    for (int i = 0; i < 17; ++i) runs->sets[i].push_back(v[i]);
}
}  // namespace

TEST(DirectLighting, ExporterStyleSceneRendersAndAgreesWithWhitted) {
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("gradus_exporter_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    // A sky: bright towards +y, a warm band near the horizon (lat-long, 64 x 32).
    Image env(64, 32, {"R", "G", "B"});
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 64; ++x) {
            const double up = std::cos(kPi * (y + 0.5) / 32);
            env.at(x, y, 0) = float(0.4 + 0.8 * std::max(0.0, up) + (std::abs(up) < 0.2 ? 1.5 : 0));
            env.at(x, y, 1) = float(0.5 + 0.9 * std::max(0.0, up) + (std::abs(up) < 0.2 ? 0.8 : 0));
            env.at(x, y, 2) = float(0.7 + 1.2 * std::max(0.0, up));
        }
    WriteImage((dir / "sky.exr").string(), env);
    Image tex(8, 8, {"R", "G", "B"});
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (int c = 0; c < 3; ++c) tex.at(x, y, c) = ((x + y) % 2) ? 0.8f : 0.2f + 0.1f * c;
    WriteImage((dir / "wood.png").string(), tex);
    auto put = [&](const char *name, const std::string &text) { std::ofstream(dir / name) << text; };
    put("materials.pbrt",
        "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.png\" \"float uscale\" [4] "
        "\"float vscale\" [4]\n"
        "MakeNamedMaterial \"Floor\" \"string type\" \"uber\" \"texture Kd\" \"wood\" \"rgb Ks\" [0.2 0.2 0.2] "
        "\"float roughness\" [0.05]\n"
        "MakeNamedMaterial \"Glass\" \"string type\" \"glass\" \"float index\" [1.5]\n"
        "MakeNamedMaterial \"Paint\" \"string type\" \"uber\" \"rgb Kd\" [0.6 0.2 0.1] \"rgb Ks\" [0.3 0.3 0.3] "
        "\"float roughness\" [0.2] \"rgb Kr\" [0.1 0.1 0.1]\n");
    put("geometry.pbrt",
        "AttributeBegin\n NamedMaterial \"Floor\"\n Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] "
        "\"point P\" [-4 0 -4  4 0 -4  4 0 4  -4 0 4] \"float uv\" [0 0 1 0 1 1 0 1]\nAttributeEnd\n"
        "AttributeBegin\n NamedMaterial \"Glass\"\n Translate -0.5 0.5 0\n Shape \"sphere\" \"float radius\" [0.5]\n"
        "AttributeEnd\n"
        "AttributeBegin\n NamedMaterial \"Paint\"\n Translate 0.7 0.4 0.3\n Shape \"sphere\" \"float radius\" [0.4]\n"
        "AttributeEnd\n");
    auto scene = [&](const std::string &integrator) {
        return "Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [24] \"string filename\" \"e.exr\"\n"
               "Sampler \"halton\" \"integer pixelsamples\" [8]\nPixelFilter \"gaussian\"\n" +
               integrator +
               "\nLookAt 0 1.2 -3.5  0 0.4 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\nWorldBegin\n"
               "AttributeBegin\n Rotate -90 1 0 0\n LightSource \"infinite\" \"string mapname\" \"sky.exr\" "
               "\"integer samples\" [2]\nAttributeEnd\n"
               "LightSource \"distant\" \"point from\" [1 3 -1] \"point to\" [0 0 0] \"rgb L\" [2 1.9 1.7]\n"
               "Include \"materials.pbrt\"\nInclude \"geometry.pbrt\"\nWorldEnd\n";
    };
    put("dl.pbrt", scene("Integrator \"directlighting\" \"integer maxdepth\" [4]"));
    put("wh.pbrt", scene("Integrator \"whitted\" \"integer maxdepth\" [4]"));
    Runs dl, wh;
    for (int k = 0; k < 12; ++k) {
        RenderResult a = RenderSceneFile((dir / "dl.pbrt").string(), 8, 100 + k);
        RenderResult b = RenderSceneFile((dir / "wh.pbrt").string(), 8, 200 + k);
        for (const Image *img : {&a.image, &b.image})
            for (float v : img->data()) ASSERT_TRUE(std::isfinite(v));
        AddRun(&dl, a.image);
        AddRun(&wh, b.image);
    }
    EXPECT_GT(dl.sets[0][0], 0.05);  // lit
    for (int i = 0; i < 17; ++i) {
        const double t = WelchT(dl.sets[i], wh.sets[i], 1);
        std::printf("statistic %d: directlighting %.5f, whitted %.5f, t %.2f, with 5%% off: %.1f / %.1f\n", i,
                    dl.sets[i][0], wh.sets[i][0], t, WelchT(dl.sets[i], wh.sets[i], 1.05),
                    WelchT(dl.sets[i], wh.sets[i], 1 / 1.05));
        EXPECT_LT(std::abs(t), 5.5) << "statistic " << i;
        if (i == 0) {  // the power check on the image mean
            EXPECT_GT(std::abs(WelchT(dl.sets[i], wh.sets[i], 1.05)), 5.5);
            EXPECT_GT(std::abs(WelchT(dl.sets[i], wh.sets[i], 1 / 1.05)), 5.5);
        }
    }
    fs::remove_all(dir);
}
