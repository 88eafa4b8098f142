// Path tracer against closed-form answers, determinism across thread counts,
// and convergence of the project's Cornell box.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <algorithm>
#include <sstream>

#include "image/metrics.h"
#include "render_util.h"

using namespace gradus;
using namespace gradus::test;

namespace {

// Camera at the centre of an emitting, diffusely reflecting sphere seen from
// inside: every path has radiance Le * sum_{k=0..D} rho^k (maxdepth D).
std::string FurnaceScene(double rho, double Le, int maxDepth, const std::string &sampler) {
    std::ostringstream s;
    s << "LookAt 0 0 0  0 0 1  0 1 0\n"
      << "Camera \"perspective\" \"float fov\" [60]\n"
      << "Sampler \"" << sampler << "\" \"integer pixelsamples\" [4]\n"
      << "Film \"image\" \"integer xresolution\" [24] \"integer yresolution\" [24]\n"
      << "Integrator \"path\" \"integer maxdepth\" [" << maxDepth << "]\n"
      << "WorldBegin\n"
      << "AttributeBegin\n"
      << "  ReverseOrientation\n"
      << "  AreaLightSource \"diffuse\" \"rgb L\" [" << Le << " " << Le << " " << Le << "]\n"
      << "  Material \"matte\" \"rgb Kd\" [" << rho << " " << rho << " " << rho << "]\n"
      << "  Shape \"sphere\" \"float radius\" [3]\n"
      << "AttributeEnd\n"
      << "WorldEnd\n";
    return s.str();
}

}  // namespace

// z-test, two-sided, |z| < 4.4: false-positive rate 1e-5 per check.
TEST(PathTracer, FurnaceSphereMatchesClosedForm) {
    for (int depth : {0, 1, 3, 6}) {
        for (double rho : {0.3, 0.8}) {
            const double Le = 0.5;
            double expected = 0;
            for (int k = 0; k <= depth; ++k) expected += Le * std::pow(rho, k);
            RenderResult r = RenderSceneText(FurnaceScene(rho, Le, depth, "random"), 8, 7);
            double mean, se;
            PixelMeanAndStdErr(r.image, 1, &mean, &se);
            // Float32 film storage adds a rounding floor of ~1e-7 relative.
            EXPECT_LT(std::abs(mean - expected), 4.4 * se + 1e-6 * expected)
                << "depth " << depth << " rho " << rho << " mean " << mean << " expected " << expected
                << " stderr " << se;
        }
    }
}

TEST(PathTracer, DirectLightingOnlyIsExactWithoutNoiseInFurnace) {
    // Depth 0 sees only emission: exactly Le at every pixel.
    RenderResult r = RenderSceneText(FurnaceScene(0.5, 2.0, 0, "sobol"), 4);
    for (int y = 0; y < r.image.height(); ++y)
        for (int x = 0; x < r.image.width(); ++x) ASSERT_NEAR(r.image.at(x, y, 0), 2.0f, 1e-5);
}

TEST(PathTracer, ImageIndependentOfThreadCount) {
    std::string scene = std::string(GRADUS_SOURCE_DIR) + "/scenes/cornell-box.pbrt";
    std::ifstream in(scene);
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    // Smaller film for speed.
    size_t p = text.find("[ 256 ] \"integer yresolution\" [ 256 ]");
    ASSERT_NE(p, std::string::npos);
    text.replace(p, std::string("[ 256 ] \"integer yresolution\" [ 256 ]").size(),
                 "[ 40 ] \"integer yresolution\" [ 40 ]");
    for (const char *sampler : {"random", "sobol", "halton", "stratified"}) {
        std::string t = text;
        size_t q = t.find("Sampler \"sobol\" \"integer pixelsamples\" [ 16 ]");
        ASSERT_NE(q, std::string::npos);
        t.replace(q, std::string("Sampler \"sobol\" \"integer pixelsamples\" [ 16 ]").size(),
                  std::string("Sampler \"") + sampler + "\"");
        RenderResult a = RenderSceneText(t, 4, 3, 1);
        RenderResult b = RenderSceneText(t, 4, 3, 2);
        ASSERT_EQ(a.image.data().size(), b.image.data().size());
        EXPECT_TRUE(a.image.data() == b.image.data()) << "sampler " << sampler;
        RenderResult c = RenderSceneText(t, 4, 4, 2);
        EXPECT_FALSE(a.image.data() == c.image.data()) << "seed must change the image (" << sampler << ")";
    }
}

// The project's Cornell box at 64x64 against a committed reference rendered by
// Gradus at high spp (scenes/references/). relMSE must fall roughly as 1/spp.
TEST(PathTracer, CornellBoxErrorFallsWithSamples) {
    std::string dir = std::string(GRADUS_SOURCE_DIR) + "/scenes";
    Image ref = ReadImage(dir + "/references/cornell-box-64.exr");
    std::ifstream in(dir + "/cornell-box.pbrt");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    size_t p = text.find("[ 256 ] \"integer yresolution\" [ 256 ]");
    ASSERT_NE(p, std::string::npos);
    text.replace(p, std::string("[ 256 ] \"integer yresolution\" [ 256 ]").size(),
                 "[ 64 ] \"integer yresolution\" [ 64 ]");
    double prev = 0;
    for (int spp : {4, 16, 64}) {
        RenderResult r = RenderSceneText(text, spp, 11, 0, "", dir);
        ImageMetrics m = CompareImages(r.image, ref);
        if (prev > 0) {
            // 4x the samples: expect ~4x lower error; accept anything better than 2.5x
            // (noise in the estimate of relMSE itself is a few percent at these sizes).
            EXPECT_LT(m.relmse, prev / 2.5) << "spp " << spp;
        }
        EXPECT_LT(std::abs(m.meanRelDiff), 0.02) << "spp " << spp;
        prev = m.relmse;
    }
}

// The three light-selection strategies estimate the same image: z-test of the
// image means (two-sided, |z| < 4.4, false-positive rate 1e-5 per comparison).
TEST(PathTracer, LightStrategiesAgree) {
    auto scene = [](const std::string &strategy) {
        std::ostringstream s;
        s << "LookAt 0 3 6  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\n"
          << "Sampler \"random\"\nFilm \"image\" \"integer xresolution\" [32] \"integer yresolution\" [24]\n"
          << "Integrator \"path\" \"integer maxdepth\" [3] \"string lightsamplestrategy\" \"" << strategy << "\"\n"
          << "WorldBegin\n"
          << "Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]\n"
          << "Shape \"trianglemesh\" \"point P\" [-5 0 -5 5 0 -5 5 0 5 -5 0 5] \"integer indices\" [0 2 1 0 3 2]\n"
          << "Shape \"sphere\" \"float radius\" [0.7]\n"
          << "AttributeBegin\nTranslate -3 2 0\nAreaLightSource \"diffuse\" \"rgb L\" [2000 2000 2000]\n"
          << "Shape \"sphere\" \"float radius\" [0.05]\nAttributeEnd\n"
          << "AttributeBegin\nTranslate 2.5 1.2 1\nAreaLightSource \"diffuse\" \"rgb L\" [0.5 0.5 2]\n"
          << "Shape \"sphere\" \"float radius\" [1]\nAttributeEnd\n"
          << "LightSource \"point\" \"point from\" [0 3 -2] \"rgb I\" [3 2 1]\n"
          << "WorldEnd\n";
        return s.str();
    };
    // Paired test per 8x8-pixel block and channel (see MaxPairedBlockZ). 12 blocks x
    // 3 channels x 3 pairs at |z| < 4.4: family-wise false-positive rate ~1e-3.
    const char *names[3] = {"uniform", "power", "spatial"};
    Image img[3];
    for (int i = 0; i < 3; ++i) img[i] = RenderSceneText(scene(names[i]), 128, 100 + i).image;
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j) EXPECT_LT(MaxPairedBlockZ(img[i], img[j], 8), 4.4) << names[i] << " vs " << names[j];
}

// Russian roulette in BDPT's subpaths keeps the estimate unbiased: rrdepth 0
// (roulette from the first bounce) against no roulette, paired block z-test
// (48 block-channels at |z| < 4.4: false-positive rate ~5e-4).
TEST(BDPT, RussianRouletteUnbiased) {
    auto scene = [](int rr) {
        std::ostringstream s;
        s << "LookAt 0 1 3.6  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
          << "Sampler \"random\"\nFilm \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n"
          << "Integrator \"bdpt\" \"integer maxdepth\" [8] \"integer rrdepth\" [" << rr << "]\n"
          << "WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.7 0.7 0.7]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 -1 0 1 1 0 1 1 0 -1]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 2 -1 1 2 -1 1 2 1 -1 2 1]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 1 0 -1 1 2 -1 -1 2 -1]\n"
          << "Material \"matte\" \"rgb Kd\" [0.6 0.1 0.1]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 -1 2 -1 -1 2 1 -1 0 1]\n"
          << "Material \"matte\" \"rgb Kd\" [0.1 0.5 0.1]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [1 0 -1 1 0 1 1 2 1 1 2 -1]\n"
          << "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [10 10 10]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
          << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.3 1.99 -0.3 0.3 1.99 -0.3 0.3 1.99 0.3 -0.3 1.99 0.3]\n"
          << "AttributeEnd\nWorldEnd\n";
        return s.str();
    };
    Image noRR = RenderSceneText(scene(-1), 256, 1).image;
    Image rr = RenderSceneText(scene(0), 256, 2).image;
    EXPECT_LT(MaxPairedBlockZ(noRR, rr, 8), 4.4);
}

// With visualizeweights, the MIS-weighted strategy layers (light tracing t = 1
// included, through per-layer splats) add up to the main image (box filter:
// both are per-pixel averages). Exact up to float rounding. bdpt, and mbdpt
// with its matrix strategies (and M_{1,t} in the paper's configuration).
static void CheckWeightedLayersSum(const std::string &integrator, const std::string &params) {
    SCOPED_TRACE(integrator + " " + params);
    std::string scene =
        "LookAt 0 1 3.6  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
        "Sampler \"random\"\nPixelFilter \"box\"\nFilm \"image\" \"integer xresolution\" [16] \"integer yresolution\" [16]\n"
        "Integrator \"" + integrator + "\" \"integer maxdepth\" [3] \"bool visualizeweights\" \"true\" " + params + "\n"
        "WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.7 0.7 0.7]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 -1 0 1 1 0 1 1 0 -1]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 1 0 -1 1 2 -1 -1 2 -1]\n"
        "LightSource \"point\" \"point from\" [0 1.5 0.5] \"rgb I\" [2 2 2]\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.3 1.9 -0.3 0.3 1.9 -0.3 0.3 1.9 0.3 -0.3 1.9 0.3]\n"
        "AttributeEnd\nWorldEnd\n";
    Image img = RenderSceneText(scene, 16, 3).image;
    const std::string prefix = integrator + "_s";
    std::vector<std::string> layers;
    for (const auto &l : img.layers())
        if (l.rfind(prefix, 0) == 0) layers.push_back(l);
    ASSERT_TRUE(std::find(layers.begin(), layers.end(), integrator + "_s2_t1") != layers.end());
    ASSERT_TRUE(std::find(layers.begin(), layers.end(), integrator + "_s4_t1") != layers.end());
    Image main = img.layerRGB("");
    double t1Energy = 0;
    for (int y = 0; y < main.height(); ++y)
        for (int x = 0; x < main.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (const auto &l : layers) {
                    Image li = img.layerRGB(l);
                    sum += li.at(x, y, c);
                    if (l.find("_t1") != std::string::npos) t1Energy += li.at(x, y, c);
                }
                EXPECT_NEAR(sum, main.at(x, y, c), 1e-4 * (1 + main.at(x, y, c))) << x << "," << y << "," << c;
            }
    EXPECT_GT(t1Energy, 0);  // light tracing contributes and is visualised
}

TEST(BDPT, WeightedStrategyLayersSumToImage) {
    CheckWeightedLayersSum("bdpt", "");
    CheckWeightedLayersSum("mbdpt", "");
    CheckWeightedLayersSum("mbdpt", "\"string configuration\" \"paper\"");
}

// Gradient integrators write every layer (light-tracing splats included)
// through the film's ordered tile merge: identical for 1 and 2 threads.
TEST(GradientIntegrators, IndependentOfThreadCount) {
    std::string scene =
        "LookAt 0 1 3.6  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
        "Sampler \"random\"\nFilm \"image\" \"integer xresolution\" [24] \"integer yresolution\" [20]\n"
        "WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.7 0.7 0.7]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 -1 0 1 1 0 1 1 0 -1]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-1 0 -1 1 0 -1 1 2 -1 -1 2 -1]\n"
        "AttributeBegin\nMaterial \"glass\"\nTranslate 0.2 0.5 0\nShape \"sphere\" \"float radius\" [0.3]\nAttributeEnd\n"
        "LightSource \"point\" \"point from\" [0 1.5 0.5] \"rgb I\" [2 2 2]\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.3 1.9 -0.3 0.3 1.9 -0.3 0.3 1.9 0.3 -0.3 1.9 0.3]\n"
        "AttributeEnd\nWorldEnd\n";
    for (const char *integrator : {"gpt", "gbdpt", "bdpt", "mbdpt"}) {
        Image a = RenderSceneText(scene, 4, 9, 1, integrator).image;
        Image b = RenderSceneText(scene, 4, 9, 2, integrator).image;
        ASSERT_EQ(a.channelNames(), b.channelNames()) << integrator;
        EXPECT_TRUE(a.data() == b.data()) << integrator;
    }
}
