// gmlt's separated light (gmlt.h; gradient_film.h): paths through Dirac
// vertices only to the emitter take no shift, land in the "separated" layer
// and are added after the reconstruction.
//
// A small, very bright emitter (black material) seen directly, in a mirror
// floor and through a glass sphere, before a diffuse wall it lights. Per
// render, at the pixels the emitter's images cover (primal >= 1000; the wall
// there is ~3): separated / primal >= 0.99 over all runs, and the output and
// the L1 and L2 reconstructions equal the primal to 1% on average over the
// runs (the worst run ~2%: the chains' few samples of the wall beside the
// emitter; without the separation the solve spread the emitter's image:
// 30-50% off in gpt). And
// the light in a window around each image against path: Welch's t over 24
// runs each, |t| < 5 (p ~ 1e-5 per comparison at ~40 degrees of freedom, 3
// windows; fixed seeds).
#include <cmath>
#include <cstdio>

#include "gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

constexpr int kW = 32, kH = 24;

std::string EmitterScene(const std::string &integrator) {
    return "LookAt 0 1 -4  0 0.6 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\n"
           "Sampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [" + std::to_string(kW) + "] \"integer yresolution\" [" +
           std::to_string(kH) + "] \"string filename\" [\"unused.exr\"]\nIntegrator " + integrator + R"(
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

double WindowSum(const Image &img, int x0, int y0, int r) {
    return mlt_test::MeanLum(img, x0 - r, y0 - r, x0 + r + 1, y0 + r + 1) * double(2 * r + 1) * (2 * r + 1);
}

TEST(GMLTSeparated, EmitterImagesKeepTheirLight) {
    const int runs = 24;
    struct Window {
        const char *name;
        int x, y, r;
    };
    // The emitter's image, its mirror image and its image through the sphere.
    const Window windows[3] = {{"direct", 18, 12, 3}, {"mirror", 18, 18, 2}, {"glass", 11, 9, 3}};
    std::vector<double> ref[3], got[3];
    const char *layers[3] = {"", "reconstructed_l1", "reconstructed_l2"};
    double worst[3] = {0, 0, 0}, mean[3] = {0, 0, 0}, sepTot = 0, primalTot = 0;
    int hits = 0;
    for (int k = 0; k < runs; ++k) {
        const Image p = mlt_test::Render(EmitterScene("\"path\" \"integer maxdepth\" [5]"), 16, 3000 + k).image;
        const Image g = mlt_test::Render(EmitterScene("\"gmlt\" \"integer maxdepth\" [5] \"integer bootstrapsamples\" "
                                                      "[20000] \"integer chains\" [64]"),
                                         64, 4000 + k)
                            .image;
        for (int w = 0; w < 3; ++w) {
            ref[w].push_back(WindowSum(p, windows[w].x, windows[w].y, windows[w].r));
            got[w].push_back(WindowSum(g, windows[w].x, windows[w].y, windows[w].r));
        }
        const Image primal = g.layerRGB("primal"), sep = g.layerRGB("separated");
        for (int l = 0; l < 3; ++l) {
            const Image out = g.layerRGB(layers[l]);
            double dev = 0, tot = 0;
            for (int y = 0; y < kH; ++y)
                for (int x = 0; x < kW; ++x)
                    if (primal.at(x, y, 1) >= 1000) {
                        for (int c = 0; c < 3; ++c) {
                            dev += std::abs(out.at(x, y, c) - primal.at(x, y, c));
                            tot += primal.at(x, y, c);
                            if (l == 0) sepTot += sep.at(x, y, c), primalTot += primal.at(x, y, c);
                        }
                        hits += l == 0;
                    }
            worst[l] = std::max(worst[l], tot > 0 ? dev / tot : 0);
            mean[l] += (tot > 0 ? dev / tot : 0) / runs;
        }
    }
    ASSERT_GT(hits, runs) << "too few emitter pixels";
    std::printf("[ separated ] separated / primal at the emitter's pixels %.5f; |out - primal| / primal, mean (worst) "
                "over runs: output %.4f (%.4f), l1 %.4f (%.4f), l2 %.4f (%.4f)\n",
                sepTot / primalTot, mean[0], worst[0], mean[1], worst[1], mean[2], worst[2]);
    EXPECT_GT(sepTot / primalTot, 0.99);
    EXPECT_LE(sepTot / primalTot, 1.0 + 1e-6);
    for (int l = 0; l < 3; ++l) EXPECT_LT(mean[l], 0.01) << (*layers[l] ? layers[l] : "output");
    for (int w = 0; w < 3; ++w) {
        const conformance::Welch t = conformance::WelchTest(got[w], ref[w]);
        std::printf("[ separated ] %s window: gmlt %.1f +- %.1f vs path %.1f +- %.1f (t = %.2f)\n", windows[w].name,
                    t.meanA, t.seA, t.meanB, t.seB, t.t);
        EXPECT_LT(std::abs(t.t), 5) << windows[w].name << " window";
    }
}

}  // namespace
}  // namespace gradus::pmlt_test
