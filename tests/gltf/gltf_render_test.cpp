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
TEST(GltfRender, CornellAgreesWithItsPbrtTwin) {
    constexpr int kRuns = 10, kSpp = 32;
    const SceneDesc gltf = Load("cornell.gltf");
    const SceneDesc pbrt = ParseFile(Data("cornell-gltfpbr.pbrt"));
    // Power check: the ceiling light's emission scaled by 1.05 and 1/1.05.
    auto scaledLight = [&](double s) {
        SceneDesc d = gltf;
        int n = 0;
        for (auto &al : d.areaLights)
            for (const auto &p : al.params.all())
                if (p.name == "L") {
                    Param q = p;
                    for (double &v : q.numbers) v *= s;
                    al.params.add(q);
                    ++n;
                }
        EXPECT_EQ(n, 1);
        return d;
    };
    const SceneDesc up = scaledLight(conformance::kPowerScale), down = scaledLight(1 / conformance::kPowerScale);
    std::vector<conformance::Reduced> g, p, gu, gd;
    for (int k = 0; k < kRuns; ++k) {
        g.push_back(conformance::Reduce(RenderDesc(gltf, kSpp, 100 + k), ""));
        p.push_back(conformance::Reduce(RenderDesc(pbrt, kSpp, 200 + k), ""));
        gu.push_back(conformance::Reduce(RenderDesc(up, kSpp, 300 + k), ""));
        gd.push_back(conformance::Reduce(RenderDesc(down, kSpp, 400 + k), ""));
    }
    const auto null = conformance::Evaluate(g, p, 1, conformance::kAgreementAlpha);
    // describe() calls the reference "bdpt"; here it is the pbrt twin.
    std::cout << "[ agree ] cornell.gltf vs cornell-gltfpbr.pbrt: max |t|/crit " << null.margin << "\n          "
              << null.describe() << "\n";
    EXPECT_FALSE(null.reject) << null.describe() << null.table;
    const auto vu = conformance::Evaluate(gu, p, 1, conformance::kAgreementAlpha);
    const auto vd = conformance::Evaluate(gd, p, 1, conformance::kAgreementAlpha);
    EXPECT_TRUE(vu.reject) << "emission x1.05 not detected: " << vu.describe();
    EXPECT_TRUE(vd.reject) << "emission x1/1.05 not detected: " << vd.describe();
}

}  // namespace
}  // namespace gradus::gltftest
