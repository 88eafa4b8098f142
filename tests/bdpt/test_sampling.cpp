// bdpt gives the camera subpath, the light subpath and every strategy's
// connection numbers fixed blocks of sampler dimensions (BidirDimensions), so a
// strategy's numbers keep the sampler's stratification over a pixel's samples
// whatever the subpaths' lengths. Consumed one after the other, they started
// wherever the camera subpath's random walk had ended, which varies from
// sample to sample, and lost it.
//
// Test: the unweighted next-event strategy (s = 1, t = 2; layer bdpt_s1_t2)
// of a box lit by a ceiling light, open towards the camera, with Russian
// roulette from the first bounce (rrdepth 0), so that the camera subpath's
// length varies from sample to sample. Per-pixel variance over K = 16
// independent renders at 16 spp, pooled over the 16x16 pixels, with the
// "sobol" sampler against the "random" one. Without stratification the ratio
// is 1 up to its sampling error (256 pixels x 15 degrees of freedom per side:
// about +-0.04 for one standard error, pixels treated as independent); the
// test asks for < 0.7. Measured: 0.28; 1.07 with the dimensions consumed in
// sequence, as before (the test then fails).
#include <gtest/gtest.h>

#include "bdpt_test_util.h"

namespace gradus::bdpt_test {
namespace {

double PooledPixelVariance(const std::string &scene, int runs, uint64_t seed0) {
    const int res = 16;
    std::vector<double> sum(res * res, 0), sum2(res * res, 0);
    for (int r = 0; r < runs; ++r) {
        Image img = Render(scene, "bdpt", 16, seed0 + uint64_t(r));
        for (int y = 0; y < res; ++y)
            for (int x = 0; x < res; ++x) {
                const double v = BlockMean(img, x, y, x + 1, y + 1, "bdpt_s1_t2");
                sum[size_t(y * res + x)] += v;
                sum2[size_t(y * res + x)] += v * v;
            }
    }
    double pooled = 0;
    for (size_t i = 0; i < sum.size(); ++i) {
        const double mean = sum[i] / runs;
        pooled += (sum2[i] - runs * mean * mean) / (runs - 1);
    }
    return pooled / double(sum.size());
}

TEST(BDPTSampling, NextEventStrategyKeepsTheSamplersStratification) {
    std::string scene = BoxScene("bdpt", CeilingLight(0.5, 10), "", 16);
    const std::string depth = "\"integer maxdepth\" [4]";
    scene.insert(scene.find(depth) + depth.size(), " \"integer rrdepth\" [0] \"bool visualizestrategies\" \"true\"");
    const std::string randomLine = "Sampler \"random\" \"integer pixelsamples\" [4]";
    ASSERT_NE(scene.find(randomLine), std::string::npos);
    std::string sobol = scene;
    sobol.replace(sobol.find(randomLine), randomLine.size(), "Sampler \"sobol\" \"integer pixelsamples\" [16]");
    const int runs = 16;
    const double vRandom = PooledPixelVariance(scene, runs, 100);
    const double vSobol = PooledPixelVariance(sobol, runs, 200);
    ASSERT_GT(vRandom, 0);
    std::cout << "[ sampling ] s1_t2 pooled pixel variance: sobol " << vSobol << ", random " << vRandom << " (ratio "
              << vSobol / vRandom << ")\n";
    EXPECT_LT(vSobol / vRandom, 0.7);
}

}  // namespace
}  // namespace gradus::bdpt_test
