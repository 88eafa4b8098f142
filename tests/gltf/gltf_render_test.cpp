// glTF scenes after BuildScene (these need the "gltfpbr" material): the punctual
// lights of the built scene against KHR_lights_punctual, .glb = .gltf bit for
// bit, and the Cornell box loaded from glTF against its pbrt twin
// (cornell-gltfpbr.pbrt, the same materials) in expectation.
#include <gtest/gtest.h>

#include "common/render_test_util.h"
#include "conformance/agreement.h"
#include "gltf_test_util.h"

namespace gradus::gltftest {
namespace {

TEST(GltfBuiltScene, PunctualLightsMatchTheExtension) {
    SceneDesc d = Load("lights.gltf");
    std::unique_ptr<Scene> scene = BuildScene(d, Point2i{16, 16});
    std::vector<const Light *> lights;
    for (const auto &l : scene->lights)
        if (!(l->flags & LIGHT_AREA)) lights.push_back(l.get());
    CheckPunctualLights(lights);
}

// One render of `d` at 32x32 (or `res`) with the path integrator.
Image RenderDesc(const SceneDesc &d, int spp, uint64_t seed, int res = 32) {
    BuildOptions bo;
    bo.integratorOverride = "path";
    bo.sppOverride = spp;
    bo.seed = seed;
    bo.resolution = Point2i{res, res};
    bo.quiet = true;
    RenderJob job = BuildRenderJob(d, bo);
    RenderOptions ro;
    ro.spp = spp;
    ro.nthreads = 2;
    ro.quiet = true;
    return RenderJobImage(job, ro).image;
}

TEST(GltfRender, GlbEqualsGltfBitForBit) {
    Image a = RenderDesc(Load("cornell.gltf"), 4, 11, 16);
    Image b = RenderDesc(Load("cornell.glb"), 4, 11, 16);
    EXPECT_EQ(conformance::BitwiseDifference(a, b), "");
    EXPECT_GT(test::BlockMean(a, 0, 0, 16, 16), 0.01);  // lit, not black
}

// Welch tests (tests/conformance/agreement.h) of the glTF runs against the pbrt
// runs on the image mean, 8 row and 8 column bands and 64 blocks of 4x4 pixels,
// at a false-positive rate of 1e-4 for the whole comparison (Bonferroni over
// the families and their sets). K runs of S spp per side, disjoint seeds.
// Power: the ceiling light is the only emitter, so scaling its emission by
// 1.05 scales the image by 1.05 (checked on one render at the same seed); the
// glTF runs scaled by 1.05 and 1/1.05 must be rejected.
TEST(GltfRender, CornellAgreesWithItsPbrtTwin) {
    constexpr int kRuns = 8, kSpp = 32;
    const SceneDesc gltf = Load("cornell.gltf", "", false);  // the twin has no environment
    const SceneDesc pbrt = ParseFile(Data("cornell-gltfpbr.pbrt"));
    std::vector<conformance::Reduced> g, p;
    Image first;
    for (int k = 0; k < kRuns; ++k) {
        Image img = RenderDesc(gltf, kSpp, 100 + k);
        g.push_back(conformance::Reduce(img, ""));
        if (k == 0) first = img;
        p.push_back(conformance::Reduce(RenderDesc(pbrt, kSpp, 200 + k), ""));
    }
    const auto null = conformance::Evaluate(g, p, 1, conformance::kAgreementAlpha);
    // describe() calls the reference "bdpt"; here it is the pbrt twin.
    std::cout << "[ agree ] cornell.gltf vs cornell-gltfpbr.pbrt: max |t|/crit " << null.margin << "\n          "
              << null.describe() << "\n";
    EXPECT_FALSE(null.reject) << null.describe() << null.table;

    SceneDesc brighter = gltf;
    int n = 0;
    for (auto &al : brighter.areaLights)
        for (Param q : al.params.all())
            if (q.name == "L") {
                for (double &v : q.numbers) v *= conformance::kPowerScale;
                al.params.add(q);
                ++n;
            }
    ASSERT_EQ(n, 1);
    const double ratio = test::BlockMean(RenderDesc(brighter, kSpp, 100), 0, 0, 32, 32) /
                         test::BlockMean(first, 0, 0, 32, 32);
    EXPECT_NEAR(ratio, conformance::kPowerScale, 1e-4) << "the image is not linear in the light's emission";
    const auto up = conformance::Evaluate(g, p, conformance::kPowerScale, conformance::kAgreementAlpha);
    const auto down = conformance::Evaluate(g, p, 1 / conformance::kPowerScale, conformance::kAgreementAlpha);
    EXPECT_TRUE(up.reject) << "emission x1.05 not detected: " << up.describe();
    EXPECT_TRUE(down.reject) << "emission x1/1.05 not detected: " << down.describe();
}

}  // namespace
}  // namespace gradus::gltftest
