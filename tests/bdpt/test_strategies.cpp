// Each strategy (s, t) alone (unweighted, "visualizestrategies" layers)
// estimates the same image of its path depth. Depth 1 and 2 of a diffuse box
// with a large light: every strategy's image mean (luminance) over 16 seeded
// runs is compared with next-event estimation (1, depth + 1) by a Welch z
// test, |z| < 5 (Student t with 15 dof: false-positive rate about 2e-4 per
// comparison, 3 comparisons). Light tracing (t = 1) has no layer (splats).
#include <gtest/gtest.h>

#include <map>

#include "bdpt_test_util.h"
#include "integrators/bdpt/bdpt.h"

namespace gradus::bdpt_test {
namespace {

TEST(BDPTStrategies, UnweightedStrategiesAgreePerDepth) {
    std::string s = BoxScene("bdpt", CeilingLight(0.6, 4), Sphere("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.3]", 0.3, 0.45, 0.1, 0.45));
    // maxdepth 2 and visualizestrategies.
    size_t pos = s.find("\"integer maxdepth\" [4]");
    s.replace(pos, std::string("\"integer maxdepth\" [4]").size(),
              "\"integer maxdepth\" [2] \"bool visualizestrategies\" [\"true\"]");
    const int runs = 16;
    std::map<std::pair<int, int>, std::vector<double>> means;
    for (int r = 0; r < runs; ++r) {
        Image img = Render(s, "bdpt", 16, 500 + r);
        for (int depth = 1; depth <= 2; ++depth)
            for (int t = 2; t <= depth + 2; ++t) {
                int sv = depth + 2 - t;
                means[{sv, t}].push_back(BlockMean(img, 0, 0, 16, 16, BDPTIntegrator::LayerName(sv, t)));
            }
    }
    for (int depth = 1; depth <= 2; ++depth) {
        RunStats ref = Stats(means[{1, depth + 1}]);
        EXPECT_GT(ref.mean, 0.01);
        for (int t = 2; t <= depth + 2; ++t) {
            int sv = depth + 2 - t;
            if (sv == 1) continue;
            RunStats st = Stats(means[{sv, t}]);
            EXPECT_LT(std::abs(ZScore(st, ref)), 5) << "(s,t)=(" << sv << "," << t << ") " << st.mean << " vs NEE "
                                                    << ref.mean;
            EXPECT_GT(st.mean, 0.5 * ref.mean);
        }
    }
}

}  // namespace
}  // namespace gradus::bdpt_test
