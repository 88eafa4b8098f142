// BDPT and path tracing agree within statistical error.
//
// Each integrator renders R = 16 independent runs (seeds 1..16) of a 16x16
// image; for the four 8x8 quadrants the luminance means of the runs give a
// Welch z statistic. Under the null hypothesis (both unbiased), with 12 runs
// each block mean is close to normal and |z| > 5 has probability about 4e-4
// (Student t, 11 dof), so a scene (4 blocks + whole image) fails by chance
// with probability about 2e-3. Runs are seeded, so the outcome is deterministic.
// Each test also checks its power: a 10% bias of the whole BDPT image would
// exceed the threshold (the standard error is small enough to see it).
#include <gtest/gtest.h>

#include "bdpt_test_util.h"

namespace gradus::bdpt_test {
namespace {

constexpr int kRuns = 12;
constexpr double kZ = 5;

void ExpectAgreement(const std::string &scene, int sppPath, int sppBdpt) {
    std::vector<std::vector<double>> path(5), bdpt(5);
    for (int r = 0; r < kRuns; ++r) {
        Image a = Render(scene, "path", sppPath, 1000 + r);
        Image b = Render(scene, "bdpt", sppBdpt, 2000 + r);
        for (int q = 0; q < 4; ++q) {
            int x0 = (q % 2) * 8, y0 = (q / 2) * 8;
            path[q].push_back(BlockMean(a, x0, y0, x0 + 8, y0 + 8));
            bdpt[q].push_back(BlockMean(b, x0, y0, x0 + 8, y0 + 8));
        }
        path[4].push_back(BlockMean(a, 0, 0, 16, 16));
        bdpt[4].push_back(BlockMean(b, 0, 0, 16, 16));
    }
    for (int q = 0; q < 5; ++q) {
        RunStats sp = Stats(path[q]), sb = Stats(bdpt[q]);
        double z = ZScore(sb, sp);
        EXPECT_LT(std::abs(z), kZ) << "quadrant " << q << ": bdpt " << sb.mean << " path " << sp.mean;
        if (q == 4) {
            // Power: a 10% bias of the image must be detectable.
            RunStats biased = sb;
            biased.mean *= 1.1;
            biased.var *= 1.1 * 1.1;
            EXPECT_GT(std::abs(ZScore(biased, sp)), kZ) << "too noisy to detect a 10% bias";
        }
    }
}

TEST(BDPTAgreement, CornellBoxWithShadingNormals) {
    std::string s = BoxScene("path", CeilingLight(0.3, 12),
                             Sphere("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.3]", 0.35, 0.45, 0.1, 0.45),
                             16, "Camera \"perspective\" \"float fov\" [40]", /*floorNormals=*/true);
    ExpectAgreement(s, 32, 8);
}

// Regression for pbrt-v3 #73 and pbrt-v4 #526: light subpaths through
// interpolated shading normals need the adjoint BSDF correction (Veach 1997,
// Eq. 5.17), or bdpt disagrees with path tracing. Shading normals tilted by up
// to 50 degrees across the floor. Without the correction (ShadingCorrection
// returning 1) quadrant 3 gives 0.193 against path's 0.151, z = 31; the older
// CornellBoxWithShadingNormals (20 degrees) sees it only at z = 5.3.
TEST(BDPTAgreement, ShadingNormalAdjointCorrection) {
    std::string s = BoxScene("path", CeilingLight(0.3, 12),
                             Sphere("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.3]", 0.35, 0.45, 0.1, 0.45), 16,
                             "Camera \"perspective\" \"float fov\" [40]", /*floorNormals=*/true,
                             "Material \"matte\" \"rgb Kd\" [0.8 0.8 0.8]",
                             "1.2 1 0.4  -0.3 1 1.1  -1.2 1 -0.5  0.6 1 -1.2");
    ExpectAgreement(s, 64, 16);
}

TEST(BDPTAgreement, GlossyAndSpecular) {
    std::string objects = Sphere("Material \"plastic\" \"rgb Kd\" [0.2 0.3 0.5] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.05]",
                                 -0.4, 0.5, -0.2, 0.5) +
                          Sphere("Material \"mirror\"", 0.5, 0.35, 0.3, 0.35);
    std::string s = BoxScene("path", CeilingLight(0.45, 6), objects, 16, "Camera \"perspective\" \"float fov\" [40]",
                             false, "Material \"metal\" \"float roughness\" [0.15]");
    ExpectAgreement(s, 32, 8);
}

TEST(BDPTAgreement, PointAndSpotLights) {
    std::string lights =
        "LightSource \"point\" \"point from\" [0 1.7 0.2] \"rgb I\" [1.5 1.5 1.5]\n"
        "LightSource \"spot\" \"point from\" [0.8 1.8 0.8] \"point to\" [-0.3 0 -0.3] \"float coneangle\" [25] "
        "\"float conedeltaangle\" [8] \"rgb I\" [6 5 4]\n";
    std::string s = BoxScene("path", lights, Sphere("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]", 0, 0.4, 0, 0.4));
    ExpectAgreement(s, 32, 8);
}

TEST(BDPTAgreement, EnvironmentAndDistantLight) {
    std::string s =
        "Integrator \"path\" \"integer maxdepth\" [4]\nSampler \"random\" \"integer pixelsamples\" [4]\n"
        "PixelFilter \"box\"\nFilm \"image\" \"integer xresolution\" [16] \"integer yresolution\" [16] "
        "\"string filename\" [\"unused.exr\"]\n"
        "LookAt 0 1.5 4  0 0.4 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\nWorldBegin\n"
        "LightSource \"infinite\" \"rgb L\" [0.4 0.5 0.7]\n"
        "LightSource \"distant\" \"point from\" [1 3 1] \"point to\" [0 0 0] \"rgb L\" [1.5 1.4 1.2]\n" +
        Quad("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]", "-3 0 -3  -3 0 3  3 0 3  3 0 -3") +
        Sphere("Material \"matte\" \"rgb Kd\" [0.7 0.3 0.3]", -0.5, 0.5, 0, 0.5) +
        Sphere("Material \"plastic\" \"rgb Kd\" [0.2 0.5 0.2] \"rgb Ks\" [0.4 0.4 0.4] \"float roughness\" [0.1]",
               0.6, 0.4, 0.3, 0.4) + "WorldEnd\n";
    ExpectAgreement(s, 32, 8);
}

TEST(BDPTAgreement, ThinLensCamera) {
    std::string s = BoxScene("path", CeilingLight(0.3, 12),
                             Sphere("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.3]", 0.35, 0.45, 0.5, 0.45), 16,
                             "Camera \"perspective\" \"float fov\" [40] \"float lensradius\" [0.15] "
                             "\"float focaldistance\" [2.5]");
    ExpectAgreement(s, 32, 8);
}

}  // namespace
}  // namespace gradus::bdpt_test
