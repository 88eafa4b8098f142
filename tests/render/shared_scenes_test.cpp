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
        if (spp == c.spp) {
            EXPECT_LT(std::abs(m.meanRelDiff), 0.01) << c.scene << " " << c.integrator << " " << spp << " spp";
        }
        if (prev > 0) {
            EXPECT_LT(m.relmse - floor, (prev - floor) / 2.5) << c.scene << " " << c.integrator;
        }
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

// The one-part close-ups of ../shared/scenes/pbrt-parts (gen.py writes them;
// references by pbrt-v3 in ../shared/references/parts-*): the image mean within
// 1% and each block of a 4 x 3 grid within 3% or 4 standard errors of the
// reference, for path and bdpt. A block's standard error comes from K = 8
// independent runs (Student's t with 7 dof: P(|t| > 4) = 0.5% per block, and a
// block fails only if it is also off by 3%, which at 8 x 8 spp is many
// standard errors for every block but the noisiest).
namespace {
struct PartCase {
    const char *part, *integrator;
};
class PartScene : public ::testing::TestWithParam<PartCase> {};
}  // namespace

TEST_P(PartScene, MeanAndBlocksMatchPbrtV3) {
    const PartCase c = GetParam();
    const std::string dir = RefDir(std::string("parts-") + c.part);
    if (!std::filesystem::exists(dir + "/ref.exr")) GTEST_SKIP() << "no shared references";
    const Image ref = ReadImage(dir + "/ref.exr");
    constexpr int K = 8, kSpp = 8, BX = 4, BY = 3;
    const int w = ref.width(), h = ref.height();
    auto blockMean = [&](const Image &img, int b) {  // b = BX * BY: the whole image
        const int x0 = b == BX * BY ? 0 : (b % BX) * w / BX, x1 = b == BX * BY ? w : (b % BX + 1) * w / BX;
        const int y0 = b == BX * BY ? 0 : (b / BX) * h / BY, y1 = b == BX * BY ? h : (b / BX + 1) * h / BY;
        double s = 0;
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) s += (img.at(x, y, 0) + img.at(x, y, 1) + img.at(x, y, 2)) / 3.0;
        return s / (double(x1 - x0) * (y1 - y0));
    };
    std::vector<std::vector<double>> runs(BX * BY + 1);
    for (int k = 0; k < K; ++k) {
        RenderResult r = RenderSceneFile(dir + "/ref.pbrt", kSpp, 100 + k, c.integrator);
        ASSERT_EQ(r.image.width(), w);
        for (int b = 0; b <= BX * BY; ++b) runs[b].push_back(blockMean(r.image, b));
    }
    for (int b = 0; b <= BX * BY; ++b) {
        double m = 0, v = 0;
        for (double x : runs[b]) m += x / K;
        for (double x : runs[b]) v += (x - m) * (x - m) / (K - 1);
        const double se = std::sqrt(v / K), r = blockMean(ref, b), rel = m / r - 1;
        std::printf("%s %s %s: %+.2f%% (%.2f standard errors)\n", c.part, c.integrator,
                    b == BX * BY ? "mean" : ("block " + std::to_string(b)).c_str(), 100 * rel, (m - r) / se);
        if (b == BX * BY) {
            EXPECT_LT(std::abs(rel), 0.01) << c.part << " " << c.integrator << " image mean";
        } else {
            EXPECT_TRUE(std::abs(rel) < 0.03 || std::abs(m - r) < 4 * se)
                << c.part << " " << c.integrator << " block " << b << ": " << 100 * rel << "%, " << (m - r) / se
                << " standard errors";
        }
    }
}

INSTANTIATE_TEST_SUITE_P(parts, PartScene,
                         ::testing::Values(PartCase{"disney", "path"}, PartCase{"disney", "bdpt"},
                                           PartCase{"surfaces", "path"}, PartCase{"surfaces", "bdpt"},
                                           PartCase{"lights", "path"}, PartCase{"lights", "bdpt"},
                                           PartCase{"realistic", "path"}, PartCase{"realistic", "bdpt"},
                                           PartCase{"hair", "path"}, PartCase{"hair", "bdpt"}),
                         [](const ::testing::TestParamInfo<PartCase> &i) {
                             return std::string(i.param.part) + "_" + i.param.integrator;
                         });
