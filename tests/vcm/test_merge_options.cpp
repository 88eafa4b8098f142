// Two merging options of vcm and gvcm taken from the G-VCM authors' public code
// (issue 59): the photon-normal filter (normalfilter, merge_kernel.h) and the
// radius schedule r_i = r_1 i^(alpha - 1) (radiusschedule radius, vcm.h).
//  - planted photons around a camera vertex: the filter keeps the coplanar and
//    slightly tilted ones and rejects perpendicular and back-facing ones (the
//    0.1 threshold from both sides); off, it keeps all;
//  - the schedules' radii against their closed forms, evaluated independently
//    (a running product of ratios), and as the integrators read them;
//  - whole renders: where every photon lies in the camera vertex's plane the
//    filter changes no bit (vcm, gvcm, G-PM, every layer); in a box (corners)
//    it only removes merges from vcm (no pixel brighter, some darker) and
//    changes gvcm's and G-PM's images.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "bdpt/bdpt_test_util.h"
#include "integrators/common/photon_grid.h"
#include "integrators/gvcm/gvcm.h"
#include "integrators/vcm/vcm.h"

namespace gradus {
namespace {

PhotonGrid::ParallelFor Serial() {
    return [](int64_t n, int64_t grain, const std::function<void(int64_t, int64_t)> &fn) {
        for (int64_t b = 0; b < n; b += grain) fn(b, std::min(n, b + grain));
    };
}

LightVertex Planted(const Point3 &p, const Vec3 &ng) {
    LightVertex lv;
    std::memset(static_cast<void *>(&lv), 0, sizeof lv);
    lv.p = p;
    lv.ng = ng;
    lv.ns = ng;
    lv.wo = Vec3(0, 1, 0);
    lv.depth = 1;
    return lv;
}

// A unit normal at angle acos(c) from +y (tilted towards +x).
Vec3 Tilted(double c) { return Vec3(std::sqrt(1 - c * c), c, 0); }

TEST(MergeOptions, NormalFilterKeepsCoplanarRejectsPerpendicularAndBackFacing) {
    PathVertex z;
    z.type = VertexType::Surface;
    z.p = Point3(0.3, -0.2, 0.5);
    z.ng = Vec3(0, 1, 0);
    const Float r = 0.01;
    std::vector<LightVertex> v;
    v.push_back(Planted(z.p + Vec3(0.004, 0, 0.002), Vec3(0, 1, 0)));    // 0: coplanar (dot 1)
    v.push_back(Planted(z.p + Vec3(-0.003, 0.002, 0), Vec3(1, 0, 0)));   // 1: perpendicular (dot 0)
    v.push_back(Planted(z.p + Vec3(0, -0.002, 0.001), Vec3(0, -1, 0)));  // 2: back-facing (dot -1)
    v.push_back(Planted(z.p + Vec3(0.001, 0.001, -0.003), Tilted(0.15)));  // 3: dot 0.15 >= 0.1
    v.push_back(Planted(z.p + Vec3(-0.002, 0, -0.002), Tilted(0.05)));   // 4: dot 0.05 < 0.1
    v.push_back(Planted(z.p + Vec3(0.02, 0, 0), Vec3(0, 1, 0)));         // 5: coplanar, beyond r
    v.push_back(Planted(z.p + Vec3(0, 0, 0.005), Tilted(-0.5)));         // 6: dot -0.5
    PhotonGrid grid;
    grid.build(v.size(), [&](size_t i) { return v[i].p; }, r, Serial());
    for (bool filter : {false, true}) {
        std::vector<uint32_t> got;
        ForEachMergeCandidate(grid, v, z, r, filter, [&](uint32_t k, const LightVertex &lv) {
            EXPECT_EQ(&lv, &v[k]);
            got.push_back(k);
        });
        std::sort(got.begin(), got.end());
        const std::vector<uint32_t> want = filter ? std::vector<uint32_t>{0, 3} : std::vector<uint32_t>{0, 1, 2, 3, 4, 6};
        EXPECT_EQ(got, want) << "normalfilter " << filter;
    }
}

// Area: r_i^2 = r_1^2 i^(alpha - 1); Radius: r_i = r_1 i^(alpha - 1), the
// latter as r_1 times the running product of (j / (j - 1))^(alpha - 1).
TEST(MergeOptions, RadiusSchedulesMatchTheirClosedForms) {
    const double r1 = 0.037;
    for (double alpha : {0.75, 0.9, 0.5}) {
        long double prod = 1;
        for (int i = 1; i <= 3000; ++i) {
            if (i > 1) prod *= std::pow((long double)i / (i - 1), (long double)(alpha - 1));
            const double rr = VCMRadius(r1, alpha, i, RadiusSchedule::Radius);
            EXPECT_NEAR(rr, double(r1 * prod), 1e-12 * r1) << "radius, alpha " << alpha << " i " << i;
            const double ra = VCMRadius(r1, alpha, i, RadiusSchedule::Area);
            EXPECT_NEAR(ra * ra / (r1 * r1), std::exp((alpha - 1) * std::log(double(i))), 1e-12)
                << "area, alpha " << alpha << " i " << i;
        }
    }
    // The authors' alpha 0.9: 1000 iterations shrink the radius to 1000^-0.1 = 0.501.
    EXPECT_NEAR(VCMRadius(1, 0.9, 1000, RadiusSchedule::Radius), 0.50119, 1e-5);
}

// The integrators read the schedule: radiusschedule "radius" alone takes
// alpha 0.9; a given radiusalpha is kept; the default stays the area schedule.
TEST(MergeOptions, IntegratorsUseTheSchedule) {
    using namespace bdpt_test;
    const std::string objects = Sphere("Material \"glass\"", 0.2, 0.45, 0.1, 0.4);
    struct Case {
        const char *params;
        double exponent;  // r_i = r_1 i^exponent
    } cases[] = {{"", 0.5 * (0.75 - 1)},
                 {" \"string radiusschedule\" \"radius\"", 0.9 - 1},
                 {" \"string radiusschedule\" \"radius\" \"float radiusalpha\" [0.6]", 0.6 - 1},
                 {" \"float radiusalpha\" [0.6]", 0.5 * (0.6 - 1)}};
    for (const char *integrator : {"vcm", "gvcm"})
        for (const Case &c : cases) {
            std::string text = BoxScene(integrator, CeilingLight(0.3, 10), objects);
            text.insert(text.find('\n'), std::string(" \"float radius\" [0.05]") + c.params);
            RenderJob job = test::MakeTestJob(ParseString(text), 1, 0);
            job.integrator->preprocess(*job.scene, *job.film);
            for (int i : {1, 2, 10, 777}) {
                const double want = 0.05 * std::pow(double(i), c.exponent);
                double got;
                if (auto *v = dynamic_cast<VCMIntegrator *>(job.integrator.get()))
                    got = v->radiusAt(i);
                else
                    got = dynamic_cast<GVCMIntegrator &>(*job.integrator).radiusAt(i);
                EXPECT_NEAR(got, want, 1e-12) << integrator << c.params << " i " << i;
            }
        }
}

// The parameter appended to the Integrator line.
std::string WithParam(std::string text, const std::string &param) {
    text.insert(text.find('\n', text.find("Integrator ")), " " + param);
    return text;
}

// A floor (the only surface that holds photons: a point light, a glass sphere)
// seen by the camera: every merge is coplanar, the filter rejects none.
std::string FloorScene(const std::string &integrator) {
    return test::TestSceneHeader("0 1.2 2.5  0 0.2 0  0 1 0", 45, 24, 16,
                                 "Integrator \"" + integrator + "\" \"integer maxdepth\" [5] \"float radius\" [0.04]") +
           "WorldBegin\nLightSource \"point\" \"point from\" [0.3 1.5 0.2] \"rgb I\" [4 4 4]\n" +
           test::Quad("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]", "-3 0 -3  -3 0 3  3 0 3  3 0 -3") +
           bdpt_test::Sphere("Material \"glass\"", 0, 0.35, 0, 0.35) + "WorldEnd\n";
}

TEST(MergeOptions, NormalFilterChangesNothingWhereAllPhotonsAreCoplanar) {
    for (const char *integrator : {"vcm", "gvcm", "gvcm/mergeonly"}) {
        const bool gpm = std::string(integrator) == "gvcm/mergeonly";
        std::string text = FloorScene(gpm ? "gvcm" : integrator);
        if (gpm) text = WithParam(text, "\"string mode\" \"mergeonly\"");
        const Image off = test::RenderTestDesc(ParseString(text), 4, 3, 1).image;
        const test::TestRender on = test::RenderTestDesc(ParseString(WithParam(text, "\"bool normalfilter\" \"true\"")), 4, 3, 1);
        EXPECT_NE(on.statistics.find("photon-normal filter"), std::string::npos) << integrator;
        ASSERT_EQ(on.image.channelNames(), off.channelNames()) << integrator;
        EXPECT_TRUE(on.image.data() == off.data()) << integrator;
        double sum = 0;
        for (float x : off.data()) sum += x;
        EXPECT_GT(sum, 0) << integrator;
    }
}

// In the box (floor, walls, ceiling meeting at right angles) with a glass
// sphere and a large kernel, photons on a wall fall into kernels on the floor
// near the corners: the filter drops them. vcm's merges draw no random
// numbers, so its filtered image is the unfiltered one minus those merges:
// no pixel brighter (beyond rounding), some darker.
TEST(MergeOptions, NormalFilterOnlyRemovesMergesInCorners) {
    using namespace bdpt_test;
    const std::string objects = Sphere("Material \"glass\"", 0.2, 0.45, 0.1, 0.4);
    std::string text = BoxScene("vcm", CeilingLight(0.3, 10), objects);
    text = WithParam(text, "\"float radius\" [0.12]");
    const Image off = test::RenderTestDesc(ParseString(text), 4, 7, 1).image.layerRGB("");
    const Image on =
        test::RenderTestDesc(ParseString(WithParam(text, "\"bool normalfilter\" \"true\"")), 4, 7, 1).image.layerRGB("");
    ASSERT_EQ(on.data().size(), off.data().size());
    int darker = 0;
    for (size_t i = 0; i < on.data().size(); ++i) {
        EXPECT_LE(on.data()[i], off.data()[i] * (1 + 1e-5) + 1e-9) << "value " << i;
        darker += on.data()[i] < off.data()[i] * (1 - 1e-3);
    }
    EXPECT_GT(darker, 10);
    for (const char *mode : {"vcm", "mergeonly"}) {
        std::string g = WithParam(BoxScene("gvcm", CeilingLight(0.3, 10), objects),
                                  std::string("\"float radius\" [0.12] \"string mode\" \"") + mode + "\"");
        const Image goff = test::RenderTestDesc(ParseString(g), 2, 7, 1).image;
        const Image gon = test::RenderTestDesc(ParseString(WithParam(g, "\"bool normalfilter\" \"true\"")), 2, 7, 1).image;
        EXPECT_FALSE(gon.layerRGB("primal").data() == goff.layerRGB("primal").data()) << "gvcm mode " << mode;
    }
}

}  // namespace
}  // namespace gradus
