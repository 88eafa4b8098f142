// Slow tier: BDPT against the pbrt-v3 references (skipped when absent).
// Renders at N and 4N spp: relMSE (papers' metric, epsilon 0.001) must fall
// (by at least 1.7x, 4x expected minus the reference's own noise floor), and
// 16x16-pixel block means must agree with the reference within 5% (plus a
// small absolute term for dark blocks).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "bdpt_test_util.h"
#include "image/image.h"

namespace gradus::bdpt_test {
namespace {

std::string ReadFile(const std::string &path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

double RelMSE(const Image &a, const Image &ref) {
    double sum = 0;
    for (int y = 0; y < ref.height(); ++y)
        for (int x = 0; x < ref.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                double r = ref.at(x, y, c), d = a.at(x, y, c) - r;
                sum += d * d / (r * r + 1e-3);
            }
    return sum / (3.0 * ref.width() * ref.height());
}

void CheckReference(const std::string &name, int spp, int maxdepth) {
    std::string dir = "/work/shared/references/" + name;
    if (!std::filesystem::exists(dir + "/ref.pbrt") || !std::filesystem::exists(dir + "/ref.exr"))
        GTEST_SKIP() << dir << " absent";
    std::string text = ReadFile(dir + "/ref.pbrt");
    Image ref = ReadImage(dir + "/ref.exr").layerRGB("");
    auto render = [&](int n) {
        SceneDesc desc = ParseString(text, dir + "/ref.pbrt", dir);
        BuildOptions bo;
        bo.integratorOverride = "bdpt";
        bo.sppOverride = n;
        bo.seed = 7;
        bo.quiet = true;
        // Limit the depth of the cornell box (65 in the file) to what a test can afford
        // only when the caller asks (maxdepth < 0: keep the file's).
        RenderJob job = BuildRenderJob(desc, bo);
        job.integrator->preprocess(*job.scene, *job.film);
        RenderOptions ro;
        ro.spp = n;
        ro.seed = 7;
        ro.quiet = true;
        ro.nthreads = 2;
        job.integrator->render(*job.scene, *job.film, *job.sampler, ro);
        return job.film->mainImage();
    };
    (void)maxdepth;
    Image lo = render(spp), hi = render(4 * spp);
    ASSERT_EQ(hi.width(), ref.width());
    double eLo = RelMSE(lo, ref), eHi = RelMSE(hi, ref);
    EXPECT_LT(eHi, eLo / 1.7) << name << ": relMSE " << eLo << " at " << spp << " spp, " << eHi << " at " << 4 * spp;
    const int B = 16;
    for (int by = 0; by + B <= ref.height(); by += B)
        for (int bx = 0; bx + B <= ref.width(); bx += B) {
            double m = BlockMean(hi, bx, by, bx + B, by + B), r = BlockMean(ref, bx, by, bx + B, by + B);
            EXPECT_NEAR(m, r, 0.05 * r + 0.003) << name << " block (" << bx << "," << by << ")";
        }
}

TEST(BDPTReference, VeachBidir) { CheckReference("veach-bidir", 16, -1); }
TEST(BDPTReference, CornellBox) { CheckReference("cornell-box", 4, -1); }

}  // namespace
}  // namespace gradus::bdpt_test
