// Environment lighting from the command line (gradus --envmap, job/environment.h):
// the radiance a diffuse plane reflects under a lat-long map against the
// closed-form irradiance, the map's orientation (pole, phi, rotation; +z up
// for pbrt scenes, +y for glTF), Radiance .hdr files through stb_image, and
// the command line's errors, provenance and checkpoint identity.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/transform.h"
#include "image/image.h"
#include "job/environment.h"
#include "job/render_route.h"
#include "lights/light.h"
#include "render/cli_fixture.h"

namespace fs = std::filesystem;
using namespace gradus;

namespace {

// A w x h map whose texel (x, y) is f(u, v) at its centre.
Image MakeMap(int w, int h, const std::function<Spectrum(double u, double v)> &f) {
    Image img = Image::RGB(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const Spectrum s = f((x + 0.5) / w, (y + 0.5) / h);
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = float(s[c]);
        }
    return img;
}

// A Radiance RGBE file of one colour, written flat (not run-length encoded).
void WriteRGBE(const std::string &path, int w, int h, const unsigned char rgbe[4]) {
    std::ofstream out(path, std::ios::binary);
    out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " << h << " +X " << w << "\n";
    for (int i = 0; i < w * h; ++i) out.write(reinterpret_cast<const char *>(rgbe), 4);
}

// A diffuse square (Kd) through the origin facing n, seen head-on from 5 n by
// a camera whose view it fills (half-width 1.34 at the square); random sampler
// (independent pixels), box filter, direct lighting only (maxdepth 1); no
// light but the environment. (Kept small: shadow rays leaving a tilted square
// of side 200 hit Embree's float copy of it, 1e-5 off the plane, past the
// spawn offset of 1e-6, and lose a third of the light.)
std::string PlaneScene(Vec3 n, double kd) {
    const Frame f(Normalize(n));
    const Vec3 up = std::abs(f.n.z) < 0.9 ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
    auto p = [&](double a, double b) {
        const Vec3 q = f.s * a + f.t * b;
        char buf[96];
        std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g ", q.x, q.y, q.z);
        return std::string(buf);
    };
    char look[160];
    std::snprintf(look, sizeof look, "LookAt %.9g %.9g %.9g  0 0 0  %g %g %g\n", 5 * f.n.x, 5 * f.n.y, 5 * f.n.z,
                  up.x, up.y, up.z);
    return std::string(look) +
           "Camera \"perspective\" \"float fov\" [30]\n"
           "Sampler \"random\" \"integer pixelsamples\" [16]\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32] \"string filename\" [\"p.exr\"]\n"
           "Integrator \"path\" \"integer maxdepth\" [1]\nWorldBegin\n"
           "Material \"matte\" \"rgb Kd\" [" + std::to_string(kd) + " " + std::to_string(kd) + " " + std::to_string(kd) +
           "]\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [" + p(-2, -2) + p(2, -2) + p(2, 2) + p(-2, 2) + "]\nWorldEnd\n";
}

class EnvmapTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("gradus_envmap_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string &name) const { return (dir_ / name).string(); }

    // Renders PlaneScene(n, kd) lit by the map through the command line's route.
    Image Render(const std::string &map, Vec3 n, double kd, double scale = 1, double rotate = 0, uint64_t seed = 7) {
        const std::string scene = path("plane.pbrt");
        std::ofstream(scene) << PlaneScene(n, kd);
        BuildOptions bo;
        bo.quiet = true;
        bo.checkOutput = false;
        bo.seed = seed;
        bo.environment.map = map;
        bo.environment.scale = scale;
        bo.environment.rotateDegrees = rotate;
        LoadEnvironmentMap(&bo.environment);
        double seconds;
        RenderJob job = LoadRenderJob(scene, GltfOptions(), bo, &seconds);
        RenderOptions ro;
        ResolveSampleCount(job, bo, &ro);
        ro.quiet = true;
        return RenderJobImage(job, ro).image;
    }
    fs::path dir_;
};

// The plane's radiance Kd E / pi against `expected` per channel: a z-test of
// the mean of the 1024 independent pixel estimates (random sampler, box
// filter) with their sample standard deviation. |z| < 4.56 for each of the
// file's at most 30 channel checks: a false-positive rate below 1e-4 for all
// of them (Bonferroni, normal tails).
constexpr double kZ = 4.56;
void ExpectRadiance(const Image &img, Spectrum expected, const char *what) {
    for (int c = 0; c < 3; ++c) {
        double sum = 0, sq = 0;
        const int n = img.width() * img.height();
        for (int y = 0; y < img.height(); ++y)
            for (int x = 0; x < img.width(); ++x) {
                const double v = img.at(x, y, c);
                sum += v;
                sq += v * v;
            }
        const double mean = sum / n, var = (sq - n * mean * mean) / (n - 1);
        const double se = std::sqrt(std::max(var, 0.0) / n);
        // A noiseless estimate (se 0) must be exact up to float rounding.
        const double z = (mean - expected[c]) / std::max(se, 1e-6 * expected[c]);
        EXPECT_LT(std::abs(z), kZ) << what << " channel " << c << ": mean " << mean << ", expected " << expected[c]
                                   << ", standard error " << se;
    }
}

}  // namespace

// A constant map c (times --envmap-scale k) gives the irradiance E = pi k c on
// any plane: radiance Kd k c. EXR and Radiance .hdr (stb_image's reader) alike.
TEST_F(EnvmapTest, ConstantMapGivesKdTimesRadiance) {
    const Spectrum c(0.5, 1, 2);
    WriteImage(path("c.exr"), MakeMap(8, 4, [&](double, double) { return c; }));
    const unsigned char rgbe[4] = {32, 64, 128, 130};  // (0.5, 1, 2): m * 2^(e - 136)
    WriteRGBE(path("c.hdr"), 8, 4, rgbe);
    const double kd = 0.5, k = 3;
    ExpectRadiance(Render(path("c.exr"), Vec3(0, 0, 1), kd, k), c * (kd * k), "exr, plane facing +z");
    ExpectRadiance(Render(path("c.hdr"), Vec3(1, 2, -0.5), kd, k), c * (kd * k), "hdr, tilted plane");
}

// Rows above the map's middle (theta < pi/2) are radiance A, the others B: a
// plane facing +z (pbrt's up, the top row) sees A only, one facing -z B only,
// one facing +x half of each: E = pi (A + B) / 2. (512 rows: the bilinear
// blur at the equator changes E by about 1e-5 relative.)
TEST_F(EnvmapTest, TopRowIsPbrtsUpAxis) {
    const Spectrum A(1, 0.25, 0.5), B(0.1, 2, 0.3);
    WriteImage(path("tb.exr"), MakeMap(4, 512, [&](double, double v) { return v < 0.5 ? A : B; }));
    const double kd = 0.8;
    ExpectRadiance(Render(path("tb.exr"), Vec3(0, 0, 1), kd), A * kd, "facing +z");
    ExpectRadiance(Render(path("tb.exr"), Vec3(0, 0, -1), kd), B * kd, "facing -z");
    ExpectRadiance(Render(path("tb.exr"), Vec3(1, 0, 0), kd), (A + B) * (kd / 2), "facing +x");
}

// Columns u < 1/2 (phi in [0, pi): the half-space y > 0) are A, the others B.
// --envmap-rotate 90 turns the map counterclockwise about +z: +y goes to -x.
TEST_F(EnvmapTest, PhiRunsFromXTowardsYAndRotateTurnsIt) {
    const Spectrum A(2, 1, 0.5), B(0.2, 0.1, 0.05);
    WriteImage(path("lr.exr"), MakeMap(512, 2, [&](double u, double) { return u < 0.5 ? A : B; }));
    const double kd = 0.5;
    ExpectRadiance(Render(path("lr.exr"), Vec3(0, 1, 0), kd), A * kd, "facing +y");
    ExpectRadiance(Render(path("lr.exr"), Vec3(0, -1, 0), kd), B * kd, "facing -y");
    ExpectRadiance(Render(path("lr.exr"), Vec3(-1, 0, 0), kd, 1, 90), A * kd, "rotated 90, facing -x");
    ExpectRadiance(Render(path("lr.exr"), Vec3(0, 1, 0), kd, 1, 90), (A + B) * (kd / 2), "rotated 90, facing +y");
}

// The light's mapping of directions to texels: pbrt scenes +z up, glTF scenes
// +y up (the pole), phi turned right-handed about the up axis by the rotation.
TEST_F(EnvmapTest, UpAxisOfPbrtAndGltfScenes) {
    // Four quadrants of u (phi) in the upper rows, dark below.
    const Spectrum q[4] = {Spectrum(1, 0, 0), Spectrum(0, 1, 0), Spectrum(0, 0, 1), Spectrum(1, 1, 0)};
    WriteImage(path("q.exr"), MakeMap(256, 256, [&](double u, double v) {
                   return v < 0.5 ? q[std::min(3, int(u * 4))] : Spectrum(0.01);
               }));
    auto Le = [&](bool gltf, double rotate, Vec3 d) {
        EnvironmentOptions env;
        env.map = path("q.exr");
        env.rotateDegrees = rotate;
        LoadEnvironmentMap(&env);
        SceneDesc desc;
        AddEnvironmentLight(env, gltf, &desc);
        EXPECT_EQ(desc.lights.size(), 1u);
        auto light = CreateLight(desc.lights.at(0), desc);
        return light->Le(Ray(Point3(0, 0, 0), Normalize(d)));
    };
    auto near = [](Spectrum a, Spectrum b) { return std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b) < 1e-6; };
    // Directions at phi = 45, 135, 225, 315 degrees, 45 degrees above the horizon.
    const double s = std::sqrt(0.5) / std::sqrt(2.0), h = std::sqrt(0.5);
    const Vec3 pbrtDirs[4] = {Vec3(s, s, h), Vec3(-s, s, h), Vec3(-s, -s, h), Vec3(s, -s, h)};
    for (int k = 0; k < 4; ++k) {
        EXPECT_TRUE(near(Le(false, 0, pbrtDirs[k]), q[k])) << "pbrt quadrant " << k;
        EXPECT_TRUE(near(Le(false, 90, pbrtDirs[(k + 1) % 4]), q[k])) << "pbrt rotated, quadrant " << k;
    }
    EXPECT_TRUE(near(Le(false, 0, Vec3(0.3, 0.1, -1)), Spectrum(0.01)));
    // glTF: +y up; light +x stays +x, light +y goes to -z (Rotate -90 about x).
    const Vec3 gltfDirs[4] = {Vec3(s, h, -s), Vec3(-s, h, -s), Vec3(-s, h, s), Vec3(s, h, s)};
    for (int k = 0; k < 4; ++k) {
        EXPECT_TRUE(near(Le(true, 0, gltfDirs[k]), q[k])) << "glTF quadrant " << k;
        EXPECT_TRUE(near(Le(true, 90, gltfDirs[(k + 1) % 4]), q[k])) << "glTF rotated, quadrant " << k;
    }
    EXPECT_TRUE(near(Le(true, 0, Vec3(0.3, -1, 0.1)), Spectrum(0.01)));
}

// Bad maps are located errors naming the file, raised by LoadEnvironmentMap
// (before any scene is read).
TEST_F(EnvmapTest, BadMapsAreLocatedErrors) {
    auto error = [&](EnvironmentOptions env) {
        try {
            LoadEnvironmentMap(&env);
        } catch (const Error &e) {
            EXPECT_NE(e.location(), nullptr);
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EnvironmentOptions env;
    env.map = path("missing.exr");
    EXPECT_NE(error(env).find("<command line --envmap>:1:1: " + path("missing.exr") + ": cannot open"), std::string::npos)
        << error(env);
    Image neg = MakeMap(4, 2, [](double, double) { return Spectrum(1); });
    neg.at(3, 1, 2) = -1;
    WriteImage(path("neg.exr"), neg);
    env.map = path("neg.exr");
    EXPECT_NE(error(env).find("neg.exr: texel (3, 1) has the value -1"), std::string::npos) << error(env);
    std::ofstream(path("junk.hdr")) << "not an image";
    env.map = path("junk.hdr");
    EXPECT_NE(error(env).find("junk.hdr: "), std::string::npos) << error(env);
    env.map = path("sky.png");
    EXPECT_NE(error(env).find("expected a lat-long HDR image"), std::string::npos) << error(env);
    env = EnvironmentOptions();
    env.map = "none";
    env.scale = 2;
    EXPECT_NE(error(env).find("need --envmap FILE"), std::string::npos) << error(env);
}

// ---------------------------------------------------------------- the command line

using CliTest = gradus::test::GradusCliTest;

namespace {
const char *kLitPlane =
    "LookAt 0 0 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [30]\n"
    "Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8] \"string filename\" [\"out.exr\"]\n"
    "WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-9 -9 0 9 -9 0 9 9 0 -9 9 0]\n"
    "WorldEnd\n";
}  // namespace

// A missing map fails before the scene (here a broken one) is read.
TEST_F(CliTest, EnvmapIsCheckedBeforeTheScene) {
    write("broken.pbrt", "WorldBegin\nShape \"nonsense\"\n");
    gradus::test::RunResult r = run("broken.pbrt --envmap nothere.exr --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("<command line --envmap>:1:1: nothere.exr: cannot open file for reading"), std::string::npos)
        << r.err;
    r = run("broken.pbrt --envmap-scale 2 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("--envmap-scale needs --envmap FILE"), std::string::npos) << r.err;
}

// The map is recorded: metadata "environment", an input file of the scene
// hash, and part of the checkpoint identity (a resume at another scale is refused).
TEST_F(CliTest, EnvmapProvenanceAndCheckpointIdentity) {
    write("plane.pbrt", kLitPlane);
    WriteImage((dir_ / "sky.exr").string(), MakeMap(8, 4, [](double, double) { return Spectrum(0.5); }));
    gradus::test::RunResult r = run("plane.pbrt --envmap sky.exr --envmap-scale 2 --envmap-rotate 30 --spp 2 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    Image img = ReadImage((dir_ / "out.exr").string());
    EXPECT_EQ(img.metadata["environment"].str(), "\"sky.exr\" scale 2 rotate 30");
    EXPECT_EQ(img.metadata["scene_files"].str(), "2");
    EXPECT_GT(img.at(4, 4, 0), 0.2f);  // lit (matte 0.5 under radiance 1: 0.5)
    r = run("plane.pbrt --envmap sky.exr --spp 2 --passes 0:1 --checkpoint c.ckpt --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    r = run("plane.pbrt --envmap sky.exr --envmap-scale 2 --spp 2 --resume c.ckpt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("environment: map scale 1 rotate 0"), std::string::npos) << r.err;
    r = run("plane.pbrt --envmap sky.exr --spp 2 --resume c.ckpt --quiet");
    EXPECT_EQ(r.status, 0) << r.err;
}

// A glTF file without punctual lights gets the default environment even with
// emissive surfaces (a note says so); --envmap none turns it off.
TEST_F(CliTest, GltfDefaultEnvironmentAndNone) {
    const std::string glb = std::string(GRADUS_SOURCE_DIR) + "/scenes/cornell-box.glb";
    gradus::test::RunResult on = run("'" + glb + "' --resolution 16x16 --spp 4 --outfile on.exr --quiet");
    ASSERT_EQ(on.status, 0) << on.err;
    EXPECT_NE(on.err.find("uniform white environment lights the scene besides its emissive surfaces"),
              std::string::npos) << on.err;
    gradus::test::RunResult off =
        run("'" + glb + "' --resolution 16x16 --spp 4 --outfile off.exr --quiet --envmap none");
    ASSERT_EQ(off.status, 0) << off.err;
    EXPECT_EQ(off.err.find("uniform white environment"), std::string::npos) << off.err;
    Image a = ReadImage((dir_ / "on.exr").string()), b = ReadImage((dir_ / "off.exr").string());
    EXPECT_EQ(b.metadata["environment"].str(), "none");
    EXPECT_EQ(a.metadata.count("environment"), 0u);
    double sa = 0, sb = 0;
    for (float v : a.data()) sa += v;
    for (float v : b.data()) sb += v;
    EXPECT_GT(sa, sb * 1.05);  // the box's open front lets the environment in
}
