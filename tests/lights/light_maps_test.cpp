// Goniometric and projection lights with 8-bit PNG maps against closed forms
// evaluated here, apart from the lights' code, with pbrt-v3's semantics
// (13d871fa: core/imageio.cpp ReadImagePNG, core/mipmap.h, lights/goniometric.h,
// lights/projection.cpp):
//  - the map holds the file's codes / 255 (pbrt-v3 applies no sRGB decoding to
//    light maps), looked up bilinearly with texel centres at (i + 1/2) / n,
//    wrapping (MIPMap::Lookup, width 0, repeat), t = 0 at the file's top row;
//  - goniometric: the light-space direction with y and z swapped, then
//    (s, t) = (phi / 2pi, theta / pi) of that vector;
//  - projection: screen point (x / z, y / z) / tan(fov / 2) inside the bounds
//    [-a, a] x [-1, 1] (a = width / height >= 1, else [-1, 1] x [-1/a, 1/a]),
//    (s, t) = its offset within them; nothing behind the projector.
// Each light alone above a diffuse plane (Kd = 0.5), path maxdepth 1: a plane
// point P sees L(P) = Kd / pi * I * map(w) * cos(theta) / d^2.
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <sstream>

#include "common/png_test_util.h"
#include "image/image.h"
#include "lights/light.h"
#include "parser/scene_desc.h"
#include "render/render_util.h"

namespace gradus {
namespace {

constexpr double kPi = 3.14159265358979323846;

// An 8-bit RGB map whose codes differ between neighbours and channels.
struct ByteMap {
    int w, h;
    std::vector<unsigned char> rgb;  // row 0 first (the file's top row)
    ByteMap(int w_, int h_, const std::function<int(int, int, int)> &code) : w(w_), h(h_), rgb(size_t(3) * w * h) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) rgb[size_t(3) * (y * w + x) + c] = (unsigned char)code(x, y, c);
    }
    double stored(int x, int y, int c) const { return rgb[size_t(3) * (y * w + x) + c] / 255.0; }
    // Written with libpng (not Gradus's writer), under a name unique to this process.
    std::string write(const std::string &name) const {
        const std::string path = "/tmp/gradus_light_maps_" + name + "_" + std::to_string(::getpid()) + ".png";
        if (!test::WritePngCodes(path, w, h, 3, rgb.data())) ADD_FAILURE() << path;
        return path;
    }
    // pbrt-v3's bilinear lookup with repeat wrap.
    double bilerp(double s, double t, int c) const {
        const double x = s * w - 0.5, y = t * h - 0.5;
        const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
        const double fx = x - x0, fy = y - y0;
        auto at = [&](int i, int j) { return stored(((i % w) + w) % w, ((j % h) + h) % h, c); };
        return (1 - fx) * (1 - fy) * at(x0, y0) + fx * (1 - fy) * at(x0 + 1, y0) + (1 - fx) * fy * at(x0, y0 + 1) +
               fx * fy * at(x0 + 1, y0 + 1);
    }
};

int MixedCode(int x, int y, int c) { return 20 + (53 * x + 101 * y + 149 * c + 31 * x * y) % 231; }

// A map lookup at (s, t) for channel c.
using Lookup = std::function<double(double s, double t, int c)>;

// The light of a test as a scene block and its closed form.
struct Case {
    std::string name, block;
    Point3 pos;
    double I;
    std::function<double(const Vec3 &wWorld, int c)> scale;  // map factor towards unit wWorld
};

// Goniometric at (0, 1, 0), "Rotate -90 1 0 0": light (x, y, z) is world
// (x, z, -y), so world (X, Y, Z) is light (X, -Z, Y).
Case Goniometric(Lookup map, const std::string &file) {
    Case k;
    k.name = "goniometric";
    k.pos = Point3(0, 1, 0);
    k.I = 2.5;
    k.block = "AttributeBegin\nTranslate 0 1 0\nRotate -90 1 0 0\nLightSource \"goniometric\" \"rgb I\" [2.5 2.5 2.5] "
              "\"string mapname\" \"" + file + "\"\nAttributeEnd\n";
    k.scale = [map](const Vec3 &w, int c) {
        double l[3] = {w.x, -w.z, w.y};  // light space
        std::swap(l[1], l[2]);           // pbrt-v3's swap of y and z
        const double theta = std::acos(std::max(-1.0, std::min(1.0, l[2])));
        double phi = std::atan2(l[1], l[0]);
        if (phi < 0) phi += 2 * kPi;
        return map(phi / (2 * kPi), theta / kPi, c);
    };
    return k;
}

// Projection at (0, 2, 0), "Rotate 90 1 0 0": light (x, y, z) is world
// (x, -z, y), so world (X, Y, Z) is light (X, Z, -Y): the projector looks down.
Case Projection(Lookup map, const std::string &file, double fovDeg, int fileW, int fileH) {
    Case k;
    k.name = "projection";
    k.pos = Point3(0, 2, 0);
    k.I = 4;
    std::ostringstream b;
    b << "AttributeBegin\nTranslate 0 2 0\nRotate 90 1 0 0\nLightSource \"projection\" \"rgb I\" [4 4 4] \"float fov\" ["
      << fovDeg << "] \"string mapname\" \"" << file << "\"\nAttributeEnd\n";
    k.block = b.str();
    const double aspect = double(fileW) / fileH, tanHalf = std::tan(fovDeg * kPi / 360);
    const double ax = aspect > 1 ? aspect : 1, ay = aspect > 1 ? 1 : 1 / aspect;
    k.scale = [map, ax, ay, tanHalf](const Vec3 &w, int c) {
        const double lx = w.x, ly = w.z, lz = -w.y;
        if (lz < 1e-3) return 0.0;
        const double px = lx / lz / tanHalf, py = ly / lz / tanHalf;
        if (px < -ax || px > ax || py < -ay || py > ay) return 0.0;
        return map((px + ax) / (2 * ax), (py + ay) / (2 * ay), c);
    };
    return k;
}

std::shared_ptr<Light> MakeLight(const Case &k) {
    SceneDesc d = ParseString("WorldBegin\n" + k.block + "WorldEnd\n", "test.pbrt");
    return CreateLight(d.lights.at(0), d);
}

// Radiance leaving plane point (x, 0, z) towards the camera (Kd = 0.5, normal +y).
double PlaneRadiance(const Case &k, double x, double z, int c) {
    const Vec3 d = Point3(x, 0, z) - k.pos;
    const double d2 = d.lengthSquared(), dist = std::sqrt(d2);
    const double cosTheta = k.pos.y / dist;
    return 0.5 / kPi * k.I * k.scale(d / dist, c) * cosTheta / d2;
}

// sampleLi at 13 x 13 plane points: L = I map(w) / d^2 to float precision
// (1e-5 relative; an unlit point must give 0); at least minLit of them lit and,
// if unlitToo, some dark (outside the projector's screen).
void CheckSampleLi(const Case &k, double extent, int minLit, bool unlitToo) {
    auto light = MakeLight(k);
    int lit = 0, dark = 0;
    double worst = 0, sumGot = 0, sumExpect = 0;
    for (int i = 0; i <= 12; ++i)
        for (int j = 0; j <= 12; ++j) {
            const Point3 p(-extent + 2 * extent * i / 12.0 + 0.013, 0, -extent + 2 * extent * j / 12.0 - 0.007);
            const Interaction ref(p, Normal3(0, 1, 0), Vec3(0, 1, 0));
            LightLiSample ls;
            const bool ok = light->sampleLi(ref, Point2(0.3, 0.6), &ls);
            const Vec3 d = p - k.pos;
            for (int c = 0; c < 3; ++c) {
                const double expect = k.I * k.scale(Normalize(d), c) / d.lengthSquared();
                const double got = ok ? ls.L[c] : 0;
                worst = std::max(worst, expect > 0 ? std::abs(got / expect - 1) : got != 0 ? 1e30 : 0.0);
                sumGot += got;
                sumExpect += expect;
                if (c == 0) (expect > 0 ? lit : dark) += 1;
            }
            if (ok) {
                EXPECT_EQ(ls.pdf, 1);
                EXPECT_NEAR(Dot(ls.wi, Normalize(k.pos - p)), 1, 1e-12);
            }
        }
    EXPECT_LT(worst, 1e-5) << k.name << ": sampleLi against the closed form: worst relative error " << worst
                           << ", sum ratio " << sumGot / sumExpect;
    EXPECT_GE(lit, minLit) << k.name;
    if (unlitToo) {
        EXPECT_GT(dark, 0) << k.name;
    }
}

// A 16 x 16 render of the plane square [-1, 1]^2 seen from above by an
// orthographic camera (pbrt's LookAt: camera x is world +x, camera y world +z,
// raster y downwards: pixel (i, j) covers x in [-1 + i/8, -1 + (i+1)/8],
// z in [1 - (j+1)/8, 1 - j/8]) against the pixel footprint's mean of L(P)
// (midpoint rule on 12 x 12 points). The plane's radiance is deterministic,
// so the only error is the pixel integration by 256 Sobol points and the
// float film: measured at most 0.07% relative on the correct code; allowed 0.5%.
void CheckRender(const Case &k) {
    const int n = 16;
    std::ostringstream s;
    s << "LookAt 0 5 0  0 0 0  0 0 1\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n"
      << "Sampler \"sobol\" \"integer pixelsamples\" [256]\nPixelFilter \"box\"\n"
      << "Film \"image\" \"integer xresolution\" [" << n << "] \"integer yresolution\" [" << n
      << "] \"string filename\" \"unused.exr\"\nIntegrator \"path\" \"integer maxdepth\" [1]\nWorldBegin\n"
      << k.block << "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n"
      << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-3 0 -3  -3 0 3  3 0 3  3 0 -3]\n"
      << "WorldEnd\n";
    const RenderResult r = test::RenderSceneText(s.str(), 256, 1, 1);
    ASSERT_EQ(r.image.width(), n);
    double worst = 0, sumGot = 0, sumExpect = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c) {
                double expect = 0;
                const int m = 12;
                for (int a = 0; a < m; ++a)
                    for (int b = 0; b < m; ++b)
                        expect += PlaneRadiance(k, -1 + (i + (a + 0.5) / m) / 8, 1 - (j + (b + 0.5) / m) / 8, c);
                expect /= m * m;
                const double got = r.image.at(i, j, c);
                EXPECT_GT(expect, 0) << k.name << ": pixel " << i << " " << j << " is meant to be lit";
                worst = std::max(worst, std::abs(got / expect - 1));
                sumGot += got;
                sumExpect += expect;
            }
    std::printf("%s: render/closed form: mean %.5f, worst pixel %.3g relative\n", k.name.c_str(),
                sumGot / sumExpect, worst);
    EXPECT_LT(worst, 5e-3) << k.name << ": render against the closed form: worst pixel " << worst
                           << " relative, mean ratio " << sumGot / sumExpect;
}

TEST(LightMaps, GoniometricAgainstClosedForm) {
    const ByteMap m(16, 8, MixedCode);
    const std::string file = m.write("gonio");
    const Case k = Goniometric([&m](double u, double v, int c) { return m.bilerp(u, v, c); }, file);
    CheckSampleLi(k, 1.5, 13 * 13, false);
    CheckRender(k);
    std::remove(file.c_str());
}

TEST(LightMaps, ProjectionAgainstClosedForm) {
    // 8 x 4 (aspect 2): screen [-2, 2] x [-1, 1]; with fov 60 from height 2 the
    // lit area is |x| <= 2.31, |z| <= 1.15, covering the rendered square.
    const ByteMap m(8, 4, MixedCode);
    const std::string file = m.write("proj");
    const Case k = Projection([&m](double u, double v, int c) { return m.bilerp(u, v, c); }, file, 60, m.w, m.h);
    CheckSampleLi(k, 2.6, 40, true);  // also outside the lit area
    CheckRender(k);
    std::remove(file.c_str());
}

// A map whose width is not a power of two: pbrt-v3 resamples 12 x 8 to 16 x 8
// (ResampleToPowerOfTwo, checked against the convolution in image_io_test) and
// keeps the file's aspect 1.5 for the screen (portrait 8 x 12 -> 8 x 16: 2/3).
TEST(LightMaps, ProjectionOfAMapResampledToPowersOfTwo) {
    for (const bool portrait : {false, true}) {
        const int w = portrait ? 8 : 12, h = portrait ? 12 : 8;
        const ByteMap file(w, h, MixedCode);
        Image img(w, h, {"R", "G", "B"});
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) img.at(x, y, c) = float(file.stored(x, y, c));
        const Image up = ResampleToPowerOfTwo(img);
        ASSERT_EQ(up.width() * up.height(), 128);
        const std::string path = file.write(portrait ? "resampled_p" : "resampled_l");
        // Bilinear on the resampled texels, wrapping.
        auto upLookup = [&up](double s, double t, int c) {
            const int W = up.width(), H = up.height();
            const double x = s * W - 0.5, y = t * H - 0.5;
            const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
            const double fx = x - x0, fy = y - y0;
            auto at = [&](int i, int j) { return double(up.at(((i % W) + W) % W, ((j % H) + H) % H, c)); };
            return (1 - fx) * (1 - fy) * at(x0, y0) + fx * (1 - fy) * at(x0 + 1, y0) + (1 - fx) * fy * at(x0, y0 + 1) +
                   fx * fy * at(x0 + 1, y0 + 1);
        };
        const Case k = Projection(upLookup, path, 50, w, h);
        CheckSampleLi(k, 2.0, 40, true);
        std::remove(path.c_str());
    }
}

// scenes/parts: the lights part with one light each reads its map from ../shared.
TEST(LightMaps, PartsVariantsLoadTheSharedMaps) {
    const std::string root = GRADUS_SOURCE_DIR;
    if (!std::filesystem::exists(root + "/../shared/scenes/pbrt-parts/gonio.png")) GTEST_SKIP() << "no ../shared";
    for (const std::string v : {"goniometric", "projection"}) {
        const SceneDesc d = ParseFile(root + "/scenes/parts/lights-" + v + ".pbrt");
        ASSERT_EQ(d.lights.size(), 1u) << v;
        EXPECT_EQ(d.lights[0].type, v);
        EXPECT_NO_THROW(CreateLight(d.lights[0], d)) << v;
    }
}

}  // namespace
}  // namespace gradus
