// Slow tier: Gradus against the pbrt-v3 references in ../shared/references
// (skipped when absent). relMSE must fall like unbiased noise and the image
// mean must agree with the reference.
#include <gtest/gtest.h>

#include <filesystem>

#include "image/metrics.h"
#include "render_util.h"

using namespace gradus;
using namespace gradus::test;

namespace {
std::string RefDir(const std::string &scene) {
    return std::string(GRADUS_SOURCE_DIR) + "/../shared/references/" + scene;
}
}  // namespace

TEST(PbrtReference, CornellBoxPathUnbiased) {
    std::string dir = RefDir("cornell-box");
    if (!std::filesystem::exists(dir + "/ref.exr")) GTEST_SKIP() << "no shared references";
    Image ref = ReadImage(dir + "/ref.exr");
    double prev = 0;
    for (int spp : {16, 64}) {
        RenderResult r = RenderSceneFile(dir + "/ref.pbrt", spp, 1, "path");
        ImageMetrics m = CompareImages(r.image, ref);
        std::printf("cornell-box path %d spp: relMSE %.5g, mean rel diff %.3g%%\n", spp, m.relmse,
                    100 * m.meanRelDiff);
        EXPECT_LT(std::abs(m.meanRelDiff), 0.005);
        if (prev > 0) {
            EXPECT_LT(m.relmse, prev / 2.5);
        }
        prev = m.relmse;
    }
}
