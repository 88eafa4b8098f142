// Separated light (gradient_film.h, reconstruction.h): light reaching the
// camera through Dirac scattering only (an emitter seen directly or in a
// mirror) takes no gradients and is added after the reconstruction, in gpt,
// gbdpt and gvcm.
//
// EmitterImagesKeepTheirLight: a small (about 0.6 x 0.45 pixel), very bright
// two-sided emitter seen directly, in a mirror floor and through a glass
// sphere, in front of a diffuse wall it lights (~1/1000 of its radiance);
// random sampler, 4 spp; gpt, gbdpt, gvcm and G-PM (gvcm mergeonly). Per
// render, at the pixels where the emitter was hit through Dirac scattering
// (primal >= 1500: a hit is worth >= 0.8 x 10000 / 4 there; the brightest
// other light, the wall's image of the emitter in the mirror, is 800 per
// hit): their separated light must be 99-100% of their primal, and the
// output, reconstructed_l1 and reconstructed_l2 must equal the primal up to 1%
// (the rest's reconstruction there is of the order of the wall, ~3 against
// >= 2000). Before the separation gpt's reconstructions moved 31% of the
// emitter's light off those pixels on average, 50-56% at worst (an offset
// that misses the emitter halves the base's gradient while the primal keeps
// the whole hit); gbdpt and gvcm kept it in this scene (a black offset falls
// back to the base's full weight). And the light in a window around each
// image (7 x 7 or 5 x 5 pixels) in the output against path: Welch's t over
// 48 independent runs each, |t| < 5 (two-sided p ~ 1e-6 per comparison at
// ~90 degrees of freedom; 12 comparisons; fixed seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/render_test_util.h"
#include "parser/scene_desc.h"
#include "reconstruction/reconstruction.h"

namespace gradus {
namespace {

constexpr int kW = 32, kH = 24;

// integrator: the Integrator line's arguments, e.g. "\"gvcm\" \"string mode\" \"mergeonly\"".
std::string Header(const std::string &lookAt, const std::string &integrator) {
    return "LookAt " + lookAt + "\nCamera \"perspective\" \"float fov\" [50]\n"
           "Sampler \"random\"\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [" + std::to_string(kW) + "] \"integer yresolution\" [" +
           std::to_string(kH) + "] \"string filename\" [\"unused.exr\"]\nIntegrator " + integrator + "\n";
}

// The emitter's image is at pixels (18..19, 12), its mirror image at (18, 18).
std::string EmitterScene(const std::string &integrator) {
    return Header("0 1 -4  0 0.6 0  0 1 0", integrator) + R"(
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [10000 10000 10000] "bool twosided" "true"
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [0.417 0.468 0  0.417 0.521 0  0.486 0.521 0  0.486 0.468 0]
AttributeEnd
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [10000 10000 10000] "bool twosided" "true"
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-0.84 0.87 0.5  -0.84 0.93 0.5  -0.77 0.93 0.5  -0.77 0.87 0.5]
AttributeEnd
AttributeBegin
  Material "glass"
  Translate -0.4 0.95 -1.75
  Shape "sphere" "float radius" [0.25]
AttributeEnd
Material "mirror" "rgb Kr" [0.8 0.8 0.8]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-3 0 -5  3 0 -5  3 0 3  -3 0 3]
Material "matte" "rgb Kd" [0.5 0.5 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-3 0 2  3 0 2  3 3 2  -3 3 2]
WorldEnd
)";
}

Image Render(const std::string &scene, int spp, uint64_t seed) {
    return test::RenderTestDesc(ParseString(scene, "separated_test.pbrt", "."), spp, seed).image;
}

// Luminance sum over the window of half-size r around (x, y).
double WindowSum(const Image &img, int x, int y, int r, const std::string &layer = "") {
    return test::BlockMean(img, x - r, y - r, x + r + 1, y + r + 1, layer) * double(2 * r + 1) * (2 * r + 1);
}

TEST(Separated, EmitterImagesKeepTheirLight) {
    const int runs = 48, spp = 4;
    struct Window {
        const char *name;
        int x, y, r;
    };
    const Window windows[3] = {{"direct", 18, 12, 3}, {"mirror", 18, 18, 2}, {"glass", 11, 9, 3}};
    const char *layers[3] = {"", "reconstructed_l1", "reconstructed_l2"};
    auto windowSums = [&](const Image &img, std::vector<double> sums[3]) {
        for (int w = 0; w < 3; ++w) sums[w].push_back(WindowSum(img, windows[w].x, windows[w].y, windows[w].r));
    };
    std::vector<double> ref[3];
    for (int k = 0; k < runs; ++k) windowSums(Render(EmitterScene("\"path\""), spp, 1000 + k), ref);
    for (int w = 0; w < 3; ++w) ASSERT_GT(test::Stats(ref[w]).mean, 300) << "the emitter is not in its window";
    for (const char *integrator : {"\"gpt\"", "\"gbdpt\"", "\"gvcm\"", "\"gvcm\" \"string mode\" \"mergeonly\""}) {
        std::vector<double> sums[3];
        double worst[3] = {0, 0, 0}, mean[3] = {0, 0, 0};
        double sepTot = 0, primalTot = 0;  // over the emitter's pixels of every run
        int hits = 0;
        for (int k = 0; k < runs; ++k) {
            const Image img = Render(EmitterScene(integrator), spp, 2000 + k);
            windowSums(img, sums);
            const Image p = img.layerRGB("primal"), sep = img.layerRGB("separated");
            for (int l = 0; l < 3; ++l) {
                const Image out = img.layerRGB(layers[l]);
                double dev = 0, tot = 0;
                for (int y = 0; y < kH; ++y)
                    for (int x = 0; x < kW; ++x)
                        if (p.at(x, y, 1) >= 1500) {
                            for (int c = 0; c < 3; ++c) {
                                dev += std::abs(out.at(x, y, c) - p.at(x, y, c));
                                tot += p.at(x, y, c);
                                if (l == 0) sepTot += sep.at(x, y, c), primalTot += p.at(x, y, c);
                            }
                            hits += l == 0;
                        }
                const double rel = tot > 0 ? dev / tot : 0;
                worst[l] = std::max(worst[l], rel);
                mean[l] += rel / runs;
            }
        }
        ASSERT_GT(hits, runs) << integrator << ": too few emitter pixels";
        // Their light is the emitter's (its material is black), all separated
        // but for the wall's share of the pixel (~3 against >= 2000).
        std::printf("%s: separated / primal at the emitter's pixels %.5f\n", integrator, sepTot / primalTot);
        EXPECT_GT(sepTot / primalTot, 0.99) << integrator;
        EXPECT_LE(sepTot / primalTot, 1.0) << integrator;
        for (int l = 0; l < 3; ++l) {
            const char *name = *layers[l] ? layers[l] : "output";
            std::printf("%s %s: emitter pixels |out - primal| / primal: mean %.4f, worst %.4f\n", integrator, name,
                        mean[l], worst[l]);
            EXPECT_LT(worst[l], 0.01) << integrator << ", " << name;
        }
        for (int w = 0; w < 3; ++w) {
            const double t = test::WelchT(sums[w], ref[w]);
            std::printf("%s %s window: %.1f vs path %.1f (t = %.2f)\n", integrator, windows[w].name,
                        test::Stats(sums[w]).mean, test::Stats(ref[w]).mean, t);
            EXPECT_LT(std::abs(t), 5) << integrator << ", " << windows[w].name << " window";
        }
    }
}

// A diffuse scene (floor, wall, sphere) lit by a point light and an area
// light above the camera's view (no Dirac scattering anywhere, no emitter in
// view): nothing is separated, and the output is the reconstruction of
// primal, dx and dy alone, bit for bit.
TEST(Separated, NothingSeparatedWithoutSpecularChains) {
    const std::string matte = "Material \"matte\" \"rgb Kd\" [0.6 0.55 0.5]";
    std::string scene = Header("0 1 -3.5  0 0.9 0  0 1 0", "\"gpt\"") + "WorldBegin\n" +
                        "LightSource \"point\" \"point from\" [0.3 1.7 -0.2] \"rgb I\" [2 2 2]\n" +
                        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [3 3 3]\n" +
                        test::Quad("Material \"matte\" \"rgb Kd\" [0 0 0]",
                                   "-0.5 3.2 -0.5  0.5 3.2 -0.5  0.5 3.2 0.5  -0.5 3.2 0.5") +
                        "AttributeEnd\n" + test::Quad(matte, "-3 0 -4  3 0 -4  3 0 1.5  -3 0 1.5") +
                        test::Quad(matte, "-3 0 1.5  3 0 1.5  3 4 1.5  -3 4 1.5") +
                        "AttributeBegin\n" + matte + "\nTranslate 0.3 0.4 0\nShape \"sphere\" \"float radius\" [0.4]\n" +
                        "AttributeEnd\nWorldEnd\n";
    for (const char *integrator : {"gpt", "gbdpt", "gvcm"}) {
        const std::string s = std::string(scene).replace(scene.find("Integrator \"gpt\""), 16,
                                                         std::string("Integrator \"") + integrator + "\"");
        const Image img = Render(s, 4, 7);
        ASSERT_GE(img.channelIndex("separated.R"), 0) << integrator;
        const Image sep = img.layerRGB("separated");
        for (float v : sep.data()) ASSERT_EQ(v, 0.f) << integrator;
        GradientImages g = GradientImagesFromImage(img);
        g.separated.clear();
        const Image hybrid = ResultToImage(Reconstruct(g, ReconstructionOptions::Hybrid()));
        EXPECT_EQ(img.layerRGB("").data(), hybrid.data()) << integrator;
    }
}

// "separatedsamples K" (gradient_family.h separatedWalks): K extra Dirac-only camera
// walks per sample estimate the separated light, averaged with the sample's
// own. A large two-sided emitter (L = 1) seen directly, in a mirror floor and
// through a glass sphere, in front of a diffuse wall it lights strongly (a
// walk going on through a diffuse lobe adds ~20%), gaussian pixel filter
// (radius 2: the walks' footprints). Per case, K = 0 against K = 8 at the
// same seed (3 seeds) must keep dx and dy bit for bit (the main sample's
// numbers are untouched) and primal - separated up to float rounding (1e-4
// relative per pixel); and the image mean of the separated layer at K = 8
// against K = 0 over independent seeds must give Welch |t| < 4.5, while the
// same data with K = 8 scaled by a planted bias must give |t| > 4.5 (power).
// Cases: gpt, gbdpt, gvcm (48 seeds, 4 spp, bias 1.03); gbdpt at maxdepth 0
// (only the directly seen emitter counts: a walk one bounce too deep adds its
// mirror image; 24 seeds, 1.10); gbdpt with pixelfilter "box" (24 seeds,
// 1.05). False-positive rate: two-sided p <= 2e-4 per comparison (>= 23
// degrees of freedom), 5 comparisons, fixed seeds.
std::string WalkScene(const std::string &integrator) {
    return "LookAt 0 1 -4  0 0.8 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\n"
           "Sampler \"random\"\nPixelFilter \"gaussian\"\n"
           "Film \"image\" \"integer xresolution\" [" + std::to_string(kW) + "] \"integer yresolution\" [" +
           std::to_string(kH) + "] \"string filename\" [\"unused.exr\"]\nIntegrator " + integrator + R"(
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [1 1 1] "bool twosided" "true"
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-0.9 0.6 1.2  -0.9 1.6 1.2  0.9 1.6 1.2  0.9 0.6 1.2]
AttributeEnd
AttributeBegin
  Material "glass"
  Translate -0.3 1.0 -0.6
  Shape "sphere" "float radius" [0.45]
AttributeEnd
Material "mirror" "rgb Kr" [0.8 0.8 0.8]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-3 0 -5  3 0 -5  3 0 3  -3 0 3]
Material "matte" "rgb Kd" [0.8 0.8 0.8]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-3 0 1.5  3 0 1.5  3 3 1.5  -3 3 1.5]
WorldEnd
)";
}

TEST(Separated, WalksKeepTheSeparatedExpectation) {
    const int spp = 4;
    // integrator: the Integrator line's arguments; runs: seeds per K; bias:
    // the planted factor the comparison must see.
    auto check = [&](const std::string &integrator, int runs, double bias) {
        std::vector<double> sum0, sum8;
        const std::string withWalks = integrator + " \"integer separatedsamples\" [8]";
        for (int k = 0; k < runs; ++k) {
            const uint64_t seed = 3000 + k;
            const Image a = Render(WalkScene(integrator), spp, seed);
            const Image b = Render(WalkScene(withWalks), spp, seed + 1000);
            sum0.push_back(test::BlockMean(a, 0, 0, kW, kH, "separated"));
            sum8.push_back(test::BlockMean(b, 0, 0, kW, kH, "separated"));
            if (k < 3) {  // the same seed: only the separated light may change
                const Image c = Render(WalkScene(withWalks), spp, seed);
                for (const char *layer : {"dx", "dy"})
                    ASSERT_EQ(a.layerRGB(layer).data(), c.layerRGB(layer).data()) << integrator << " " << layer;
                const Image pa = a.layerRGB("primal"), sa = a.layerRGB("separated");
                const Image pc = c.layerRGB("primal"), sc = c.layerRGB("separated");
                for (size_t i = 0; i < pa.data().size(); ++i) {
                    const double ra = pa.data()[i] - sa.data()[i], rc = pc.data()[i] - sc.data()[i];
                    ASSERT_NEAR(rc, ra, 1e-4 * (std::abs(pa.data()[i]) + std::abs(pc.data()[i]) + 1e-3))
                        << integrator << ": primal - separated at " << i;
                }
            }
        }
        const double t = test::WelchT(sum8, sum0), tBias = test::WelchT(sum8, sum0, bias);
        const test::RunStats s0 = test::Stats(sum0), s8 = test::Stats(sum8);
        std::printf("%s separated mean: K=0 %.5f (sd %.5f), K=8 %.5f (sd %.5f); t = %.2f, with x%.2f: %.2f\n",
                    integrator.c_str(), s0.mean, std::sqrt(s0.var), s8.mean, std::sqrt(s8.var), t, bias, tBias);
        ASSERT_GT(s0.mean, 0.02) << integrator << ": the emitter is not in view";
        EXPECT_LT(std::abs(t), 4.5) << integrator;
        EXPECT_GT(std::abs(tBias), 4.5) << integrator << ": no power against the planted bias " << bias;
    };
    for (const char *integrator : {"\"gpt\"", "\"gbdpt\"", "\"gvcm\""}) check(integrator, 48, 1.03);
    // maxdepth 0: the emitter seen directly only (a walk one bounce too deep
    // would add its mirror image, ~80% more).
    check("\"gbdpt\" \"integer maxdepth\" [0]", 24, 1.10);
    // The box pixel filter (the walks' light to their own pixel only).
    check("\"gbdpt\" \"string pixelfilter\" \"box\"", 24, 1.05);
}

}  // namespace
}  // namespace gradus
