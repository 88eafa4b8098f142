// The bidirectional integrators with participating media (medium vertices in
// the shared core, integrators/common/bidir.h):
//  - an absorbing slab (sigma_s = 0) between the camera and an emitter: the
//    images of bdpt, vcm and mbdpt against the analytic transmittance exp(-sigma_t d);
//  - (slow tier, media_agree_slow_test.cpp: bdpt, vcm, mbdpt and path agree on
//    fog-box; the conformance table's media rows do so in the default tier);
//  - mlt (media numbers from its primary samples, mlt.h): the absorbing slab,
//    and agreement with bdpt by agreement.h's Welch tests (5% power check) on
//    fog-box and on a variant whose fog is a density grid (delta and ratio
//    tracking), both with the smoke sphere's medium interface inside the fog;
//  - gvcm refuses a scene with media (gbdpt renders them: tests/gbdpt/test_media.cpp):
//    a located error and exit status 1; so do vcm's variants that cannot render
//    them (mode vm, varying kernels).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/render_test_util.h"
#include "conformance/agreement.h"
#include "conformance/conformance_util.h"

namespace gradus {
namespace {

using conformance::StudentCritical;

std::string ReadFile(const std::string &path) {
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

// ---------------------------------------------------------------- absorbing slab
// Camera at z = -5 looking along +z (fov 4: rays within 2.9 degrees of the
// axis), a material-less box z in [-0.5, 0.5] holding an absorbing medium, an
// emitter (L = 1, two-sided) at z = 2 filling the view. A pixel's expectation
// is exp(-sigma_t T / cos(theta)) with T = 1 and theta its ray's angle to the axis.
constexpr double kSigmaA[3] = {0.5, 1.0, 1.5};
constexpr int kRes = 16;
constexpr double kFovDeg = 4;

// A face of the box with its geometric normal pointing outwards (pbrt's
// triangle normal: cross(p0 - p2, p1 - p2)).
std::string Face(Vec3 c, Vec3 u, Vec3 v) {
    Vec3 p[4] = {c - u - v, c + u - v, c + u + v, c - u + v};
    const Vec3 n = Cross(p[0] - p[2], p[1] - p[2]);
    if (Dot(n, c) < 0) std::swap(p[1], p[3]);  // the box is centred at the origin: outwards = along c
    std::ostringstream o;
    o << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [";
    for (const Vec3 &q : p) o << q.x << " " << q.y << " " << q.z << " ";
    o << "]\n";
    return o.str();
}

std::string SlabScene(const std::string &integrator, const std::string &params = "") {
    std::ostringstream s;
    s << "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [" << kFovDeg << "]\n"
      << "Sampler \"random\" \"integer pixelsamples\" [16]\nPixelFilter \"box\"\n"
      << "Film \"image\" \"integer xresolution\" [" << kRes << "] \"integer yresolution\" [" << kRes
      << "] \"string filename\" [\"unused.exr\"]\n"
      << "Integrator \"" << integrator << "\" \"integer maxdepth\" [3] " << params << "\n"
      << "MakeNamedMedium \"absorber\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [" << kSigmaA[0] << " "
      << kSigmaA[1] << " " << kSigmaA[2] << "] \"rgb sigma_s\" [0 0 0]\n"
      << "WorldBegin\nAttributeBegin\nMediumInterface \"absorber\" \"\"\nMaterial \"\"\n"
      << Face(Vec3(0, 0, -0.5), Vec3(1, 0, 0), Vec3(0, 1, 0)) << Face(Vec3(0, 0, 0.5), Vec3(1, 0, 0), Vec3(0, 1, 0))
      << Face(Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0.5)) << Face(Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0.5))
      << Face(Vec3(0, -1, 0), Vec3(1, 0, 0), Vec3(0, 0, 0.5)) << Face(Vec3(0, 1, 0), Vec3(1, 0, 0), Vec3(0, 0, 0.5))
      << "AttributeEnd\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n"
      << "Material \"matte\" \"rgb Kd\" [0 0 0]\n"
      << Face(Vec3(0, 0, 2), Vec3(3, 0, 0), Vec3(0, 3, 0)) << "AttributeEnd\nWorldEnd\n";
    return s.str();
}

// Image mean of channel c expected from the pixel centres' path lengths.
double SlabExpectation(int c) {
    const double tanHalf = std::tan(kFovDeg / 2 * Pi / 180);
    double sum = 0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            const double sx = (2 * (x + 0.5) / kRes - 1) * tanHalf, sy = (2 * (y + 0.5) / kRes - 1) * tanHalf;
            const double invCos = std::sqrt(1 + sx * sx + sy * sy);
            sum += std::exp(-kSigmaA[c] * invCos);
        }
    return sum / (kRes * kRes);
}

void CheckSlab(const std::string &integrator, const std::string &params = "") {
    // K runs; per channel a t-test of the run means against the expectation.
    // False positives: alpha = 1e-4 per integrator, Bonferroni over 3 channels.
    // The per-pixel-centre expectation differs from the pixel-area average by
    // less than 1e-5 relative (second order in the pixel's 0.25-degree width).
    constexpr int K = 12, kSpp = 256;
    std::vector<double> runs[3];
    for (int k = 0; k < K; ++k) {
        const Image img = test::RenderTestDesc(ParseString(SlabScene(integrator, params)), kSpp, 1000 + k, 2).image;
        for (int c = 0; c < 3; ++c) {
            double s = 0;
            for (int y = 0; y < kRes; ++y)
                for (int x = 0; x < kRes; ++x) s += img.at(x, y, c);
            runs[c].push_back(s / (kRes * kRes));
        }
    }
    const double crit = StudentCritical(1e-4 / 3, K - 1);
    for (int c = 0; c < 3; ++c) {
        const test::RunStats st = test::Stats(runs[c]);
        const double se = std::sqrt(st.var / K), expected = SlabExpectation(c);
        std::cout << "[ slab ] " << integrator << " channel " << c << ": mean " << st.mean << " +- " << se
                  << ", exp(-sigma_t d) " << expected << ", t " << (st.mean - expected) / se << "\n";
        EXPECT_LT(std::abs(st.mean - expected), crit * se) << integrator << " channel " << c;
        // Power: an expectation 2% off is rejected.
        EXPECT_GT(std::abs(st.mean - 1.02 * expected), crit * se) << integrator << " channel " << c;
        EXPECT_GT(std::abs(st.mean - expected / 1.02), crit * se) << integrator << " channel " << c;
    }
}

TEST(MediaBidir, AbsorbingSlabBDPT) { CheckSlab("bdpt"); }
TEST(MediaBidir, AbsorbingSlabVCM) { CheckSlab("vcm"); }
TEST(MediaBidir, AbsorbingSlabMBDPT) { CheckSlab("mbdpt"); }
// mlt: 256 mutations per pixel; every path of light has depth 0 (the
// emitter is black, the slab does not scatter). The image's luminance is b,
// whose depth-0 states pass the slab or not (distance sampling in one channel):
// 65536 of them keep a 2% bias detectable.
TEST(MediaBidir, AbsorbingSlabMLT) {
    CheckSlab("mlt", "\"integer bootstrapsamples\" [65536] \"integer chains\" [64]");
}

// ---------------------------------------------------------------- mlt against bdpt
// fog-box as it is (homogeneous fog and smoke: spectral-MIS distance sampling,
// exact transmittance) and with its fog replaced by a density grid over the
// room (delta tracking in the walks, ratio tracking in the connections; zero
// voxels give empty majorant cells), sigma_t = 0.5 x density in every channel
// and a coloured albedo. Both keep the material-less smoke sphere, a medium
// interface inside the fog that walks and connections cross.
std::string FogBoxText() { return ReadFile(std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt"); }

std::string GridFogBoxText() {
    std::string text = FogBoxText();
    const std::string fog =
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
        "    \"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.35 0.3 0.25] \"float g\" [0.3]\n";
    const size_t at = text.find(fog);
    EXPECT_NE(at, std::string::npos);
    if (at == std::string::npos) return text;
    constexpr int nx = 6, ny = 4, nz = 8;
    std::ostringstream g;
    g << "MakeNamedMedium \"fog\" \"string type\" \"heterogeneous\"\n"
      << "    \"rgb sigma_a\" [0.0625 0.125 0.1875] \"rgb sigma_s\" [0.4375 0.375 0.3125] \"float g\" [0.3]\n"
      << "    \"point p0\" [-1.5 0 -3.3] \"point p1\" [1.5 2 1.5] \"integer nx\" [" << nx << "] \"integer ny\" [" << ny
      << "] \"integer nz\" [" << nz << "]\n    \"float density\" [";
    for (int z = 0; z < nz; ++z)
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) g << " " << double((7 * x + 3 * y + 5 * z) % 10) / 4;  // 0 .. 2.25
    g << "]\n";
    text.replace(at, fog.size(), g.str());
    return text;
}

// The scene with its Integrator directive replaced.
std::string WithIntegrator(std::string text, const std::string &directive) {
    const std::string line = "Integrator \"bdpt\" \"integer maxdepth\" [5]";
    const size_t at = text.find(line);
    EXPECT_NE(at, std::string::npos);
    if (at != std::string::npos) text.replace(at, line.size(), directive);
    return text;
}

// K runs of mlt and of bdpt (disjoint seeds), each reduced to agreement.h's
// pixel sets (image mean, row and column bands, 4x4 blocks), compared by
// Welch's t at alpha = 1e-4 (Bonferroni over the families and their sets);
// power: mlt's runs scaled by 1.05 and 1 / 1.05 must be rejected.
void CheckMLTAgreesWithBdpt(const std::string &text, int K, int mltSpp, int bootstrap, int bdptSpp) {
    std::ostringstream mltLine;
    mltLine << "Integrator \"mlt\" \"integer maxdepth\" [5] \"integer bootstrapsamples\" [" << bootstrap
            << "] \"integer chains\" [256]";
    const SceneDesc mlt = ParseString(WithIntegrator(text, mltLine.str()));
    const SceneDesc bdpt = ParseString(text);
    std::vector<conformance::Reduced> x, ref;
    for (int k = 0; k < K; ++k) {
        x.push_back(conformance::Reduce(test::RenderTestDesc(mlt, mltSpp, 500 + k, 2).image, ""));
        ref.push_back(conformance::Reduce(test::RenderTestDesc(bdpt, bdptSpp, 600 + k, 2).image, ""));
    }
    const double alpha = conformance::kAgreementAlpha;
    const conformance::Verdict null = conformance::Evaluate(x, ref, 1, alpha);
    const conformance::Verdict up = conformance::Evaluate(x, ref, conformance::kPowerScale, alpha);
    const conformance::Verdict down = conformance::Evaluate(x, ref, 1 / conformance::kPowerScale, alpha);
    std::cout << "[ agree ] mlt vs bdpt (K " << K << "): max |t|/crit " << null.margin << "; power x1.05: "
              << up.margin << " (global " << up.worst[conformance::kGlobal].margin << "), x1/1.05: " << down.margin
              << " (global " << down.worst[conformance::kGlobal].margin << ")\n          " << null.describe() << "\n";
    EXPECT_FALSE(null.reject) << "mlt differs from bdpt in expectation: " << null.describe() << null.table;
    EXPECT_TRUE(up.reject) << "power check: a 5% bias (x1.05) is not detected: " << up.describe();
    EXPECT_TRUE(down.reject) << "power check: a 5% bias (x1/1.05) is not detected: " << down.describe();
}

// Measured (2 shared cores, loaded): 10 s and 15 s; smallest power margin
// (|t|/critical of a 5% bias) 1.31 on fog-box (K 16), 1.74 on the grid (K 24;
// 1.21 with K 16).
TEST(MediaMLT, AgreesWithBdptOnFogBox) { CheckMLTAgreesWithBdpt(FogBoxText(), 16, 64, 20000, 32); }
TEST(MediaMLT, AgreesWithBdptOnGridFogBox) { CheckMLTAgreesWithBdpt(GridFogBoxText(), 24, 64, 20000, 32); }

// ---------------------------------------------------------------- refusal
TEST(MediaBidir, GVCMRefusesMediaWithALocatedError) {
    const std::string scene = std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt";
    const auto dir = std::filesystem::temp_directory_path() / ("gradus_media_refusal_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const conformance::ProcResult r =
        conformance::RunGradus({scene, "--integrator", "gvcm", "--spp", "1", "--outfile", "x.exr", "--quiet"}, dir);
    std::filesystem::remove_all(dir);
    EXPECT_TRUE(r.exited);
    EXPECT_EQ(r.exitCode, 1) << r.describe();
    // The Integrator directive's location (line 16 of the scene), the integrator and the medium.
    EXPECT_NE(r.err.find("fog-box.pbrt:16:1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("\"gvcm\""), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("\"fog\""), std::string::npos) << r.err;
}

// vcm's merging-only mode (merges on surfaces only) and its varying kernels
// refuse media at the Integrator directive; modes vcm and vc render them.
TEST(MediaBidir, VCMVariantsWithoutMediaRefuse) {
    const std::string text = ReadFile(std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt");
    const std::string line = "Integrator \"bdpt\" \"integer maxdepth\" [5]";
    ASSERT_NE(text.find(line), std::string::npos);
    for (const char *params : {"\"string mode\" \"vm\"", "\"string kernel\" \"adaptive\"",
                               "\"string footprint\" \"path\"", "\"string mode\" \"vc\"", "\"string mode\" \"vcm\""}) {
        std::string s = text;
        s.replace(s.find(line), line.size(), std::string("Integrator \"vcm\" ") + params);
        const bool renders = std::string(params).find("\"vc") != std::string::npos;
        std::string err;
        try {
            test::MakeTestJob(ParseString(s, "fog.pbrt", "."), 1, 0);
        } catch (const Error &e) {
            err = e.what();
        }
        if (renders) {
            EXPECT_EQ(err, "") << params;
        } else {
            EXPECT_NE(err.find("fog.pbrt:16:1"), std::string::npos) << params << ": " << err;
            EXPECT_NE(err.find("\"fog\""), std::string::npos) << params << ": " << err;
        }
    }
}

}  // namespace
}  // namespace gradus
