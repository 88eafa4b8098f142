// Slow tier: bdpt, vcm, mbdpt and path agree in expectation on
// scenes/media/fog-box.pbrt (fog, spot and area light, a material-less smoke
// sphere) by Welch t-tests on the image mean and six blocks, with a power
// check (a 2% bias is detected). The default tier's conformance media rows
// (tests/conformance/media_rows.h) compare the same integrators on three
// media scenes at 5% power.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "common/render_test_util.h"
#include "conformance/agreement.h"
#include "conformance/conformance_util.h"

namespace gradus {
namespace {

using conformance::StudentCritical;
using conformance::Welch;
using conformance::WelchTest;

// ---------------------------------------------------------------- agreement
// K runs of S spp per integrator (disjoint seeds), each reduced to the mean
// luminance of the image and of six 8x9 blocks (path, noisier here: 2K runs).
// Welch's t of vcm, mbdpt and path against bdpt per set; false positives:
// alpha = 1e-4 in all,
// Bonferroni over the 3 pairs and their 7 sets (the union bound holds for any
// correlation). Power: X's runs scaled to a mean 2% above and below bdpt's
// must be rejected on the image mean of each pair.
struct Runs {
    std::vector<std::vector<double>> sets;  // [set][run]
};

Runs RenderRuns(const SceneDesc &desc, const std::string &integrator, int K, int spp, uint64_t seed0) {
    Runs r;
    r.sets.resize(7);
    for (int k = 0; k < K; ++k) {
        const Image img = test::RenderTestDesc(desc, spp, seed0 + k, 2, integrator).image;
        EXPECT_EQ(img.width(), 24);
        EXPECT_EQ(img.height(), 18);
        r.sets[0].push_back(test::BlockMean(img, 0, 0, 24, 18));
        for (int b = 0; b < 6; ++b) {
            const int x0 = (b % 3) * 8, y0 = (b / 3) * 9;
            r.sets[1 + b].push_back(test::BlockMean(img, x0, y0, x0 + 8, y0 + 9));
        }
    }
    return r;
}

TEST(MediaBidirSlow, BdptVcmPathAgreeOnFogBox) {
    std::ifstream file(std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt");
    std::stringstream text;
    text << file.rdbuf();
    const SceneDesc desc = ParseString(text.str());
    constexpr int K = 16, kSpp = 128;
    const Runs bdpt = RenderRuns(desc, "bdpt", K, kSpp, 100);
    const Runs vcm = RenderRuns(desc, "vcm", K, kSpp, 200);
    const Runs mbdpt = RenderRuns(desc, "mbdpt", K, kSpp, 300);
    const Runs path = RenderRuns(desc, "path", 2 * K, kSpp, 400);
    const double alpha = 1e-4 / 3 / 7;
    struct Pair {
        const char *name;
        const Runs *x, *ref;
    };
    for (const Pair &p : {Pair{"vcm", &vcm, &bdpt}, Pair{"mbdpt", &mbdpt, &bdpt}, Pair{"path", &path, &bdpt}}) {
        const char *name = p.name;
        const Runs *x = p.x;
        const Runs &ref = *p.ref;
        for (int set = 0; set < 7; ++set) {
            const Welch w = WelchTest(x->sets[set], ref.sets[set]);
            const double crit = StudentCritical(alpha, w.dof);
            if (set == 0)
                std::cout << "[ agree ] " << name << " vs bdpt, image mean: " << w.meanA << " +- " << w.seA << " vs "
                          << w.meanB << " +- " << w.seB << ", t " << w.t << " (critical " << crit << ")\n";
            EXPECT_LT(std::abs(w.t), crit) << name << " vs bdpt, set " << set << ": " << w.meanA << " vs " << w.meanB;
            if (set != 0) continue;
            for (double bias : {1.02, 1 / 1.02}) {
                // X's runs scaled so that their mean is bdpt's times `bias` (the
                // chance difference of these runs taken out).
                std::vector<double> scaled = x->sets[0];
                for (double &v : scaled) v *= bias * w.meanB / w.meanA;
                const Welch ws = WelchTest(scaled, ref.sets[0]);
                EXPECT_GT(std::abs(ws.t), StudentCritical(alpha, ws.dof))
                    << "power check: " << name << " biased by x" << bias << " not detected (t " << ws.t << ")";
            }
        }
    }
}

}  // namespace
}  // namespace gradus
