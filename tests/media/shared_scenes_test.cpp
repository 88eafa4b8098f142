// The media and subsurface scenes of ../shared (skipped when absent) against
// their pbrt-v3 references: the image mean within 1% (the bound; at
// these spp the mean's own standard error is below 0.1%, so a correct
// renderer fails it with negligible probability) and relMSE falling with the
// sample count as unbiased noise does (at least 2.5x from 16 to 64 spp,
// after subtracting the reference's own noise floor, ref.noise).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "image/metrics.h"
#include "render_util.h"

using namespace gradus;
using namespace gradus::test;

namespace {

struct Case {
    const char *scene, *integrator;
};

std::string RefDir(const std::string &scene) {
    return std::string(GRADUS_SOURCE_DIR) + "/../shared/references/" + scene;
}

class SharedMediaScene : public ::testing::TestWithParam<Case> {};

}  // namespace

TEST_P(SharedMediaScene, MeanWithinOnePercentAndErrorFalls) {
    const Case c = GetParam();
    const std::string dir = RefDir(c.scene);
    if (!std::filesystem::exists(dir + "/ref.exr")) GTEST_SKIP() << "no shared references";
    const Image ref = ReadImage(dir + "/ref.exr");
    double floor = 0;
    std::ifstream(dir + "/ref.noise") >> floor;
    double prev = 0;
    for (int spp : {16, 64}) {
        RenderResult r = RenderSceneFile(dir + "/ref.pbrt", spp, 5, c.integrator);
        const ImageMetrics m = CompareImages(r.image, ref);
        std::printf("%s %s %d spp: relMSE %.5g (floor %.2g), mean rel diff %+.3f%%\n", c.scene, c.integrator, spp,
                    m.relmse, floor, 100 * m.meanRelDiff);
        EXPECT_LT(std::abs(m.meanRelDiff), 0.01) << c.scene << " " << c.integrator << " " << spp << " spp";
        if (prev > 0) EXPECT_LT(m.relmse - floor, (prev - floor) / 2.5) << c.scene << " " << c.integrator;
        prev = m.relmse;
    }
}

INSTANTIATE_TEST_SUITE_P(media, SharedMediaScene,
                         ::testing::Values(Case{"smoke-grid", "path"}, Case{"subsurface-trio", "path"}),
                         [](const ::testing::TestParamInfo<Case> &i) {
                             std::string n = std::string(i.param.scene) + "_" + i.param.integrator;
                             for (char &ch : n)
                                 if (ch == '-') ch = '_';
                             return n;
                         });
