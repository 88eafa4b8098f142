// The scenes of ../shared written for media, subsurface and the rest of
// pbrt-v3's parts (skipped when absent) against their pbrt-v3 references:
// the image mean within 1% at the larger spp (the bound the issues set; the
// mean's own standard error is about 0.1% there, so a correct renderer fails
// it with negligible probability) and, where the error is not heavy-tailed,
// relMSE falling with the sample count as unbiased noise does (at least 2.5x
// for 4x the samples, after subtracting the reference's own noise floor,
// ref.noise). Caustics through a glass sphere (the zoo's, fog-spotlight's
// volumetric one) make relMSE at low spp a matter of a few pixels (zoo bdpt
// 16 spp: 7.4, 64 spp: 0.06; fog bdpt 4 spp: 0.054, 16 spp: 0.075, 64 spp:
// 0.0043), not a stable statistic: there only the mean is checked. fog-spotlight is left to
// bdpt and vcm: path cannot reach its spotlight through the glass sphere.
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
    int spp;                // the mean is checked at spp, the error's fall from spp / 4
    bool errorFalls = true;
};

std::string RefDir(const std::string &scene) {
    return std::string(GRADUS_SOURCE_DIR) + "/../shared/references/" + scene;
}

class SharedScene : public ::testing::TestWithParam<Case> {};

}  // namespace

TEST_P(SharedScene, MeanWithinOnePercentAndErrorFalls) {
    const Case c = GetParam();
    const std::string dir = RefDir(c.scene);
    if (!std::filesystem::exists(dir + "/ref.exr")) GTEST_SKIP() << "no shared references";
    const Image ref = ReadImage(dir + "/ref.exr");
    double floor = 0;
    std::ifstream(dir + "/ref.noise") >> floor;
    double prev = 0;
    for (int spp : {c.spp / 4, c.spp}) {
        if (spp == c.spp / 4 && !c.errorFalls) continue;
        RenderResult r = RenderSceneFile(dir + "/ref.pbrt", spp, 5, c.integrator);
        const ImageMetrics m = CompareImages(r.image, ref);
        std::printf("%s %s %d spp: relMSE %.5g (floor %.2g), mean rel diff %+.3f%%\n", c.scene, c.integrator, spp,
                    m.relmse, floor, 100 * m.meanRelDiff);
        if (spp == c.spp) EXPECT_LT(std::abs(m.meanRelDiff), 0.01) << c.scene << " " << c.integrator << " " << spp << " spp";
        if (prev > 0) EXPECT_LT(m.relmse - floor, (prev - floor) / 2.5) << c.scene << " " << c.integrator;
        prev = m.relmse;
    }
}

INSTANTIATE_TEST_SUITE_P(shared, SharedScene,
                         ::testing::Values(Case{"smoke-grid", "path", 64}, Case{"smoke-grid", "bdpt", 64},
                                           Case{"subsurface-trio", "path", 64}, Case{"fog-spotlight", "bdpt", 16, false},
                                           Case{"fog-spotlight", "vcm", 16, false}, Case{"pbrt-zoo", "path", 64, false},
                                           Case{"pbrt-zoo", "bdpt", 64, false},
                                           Case{"pbrt-zoo-ortho", "path", 64, false},
                                           Case{"pbrt-zoo-ortho", "bdpt", 64, false}),
                         [](const ::testing::TestParamInfo<Case> &i) {
                             std::string n = std::string(i.param.scene) + "_" + i.param.integrator;
                             for (char &ch : n)
                                 if (ch == '-') ch = '_';
                             return n;
                         });
