// Full-size (1280x720) checks; label "slow" (tens of seconds on 2 cores).
#include <gtest/gtest.h>

#include <cstdio>

#include "recon_test_util.h"
#include "reconstruction/reconstruction.h"

using namespace gradus;
using namespace gradus::testutil;

TEST(ReconstructionSlow, FullSizeL1DefaultBeatsReferenceScheduleAndSolversAgree) {
    const int W = 1280, H = 720;
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    AddNoise(g, 0.3, 0.05, 21, 0.01, 8.0);
    ReconstructionResult d = Reconstruct(g, ReconstructionOptions::L1Default());
    ReconstructionResult ref = Reconstruct(g, ReconstructionOptions::L1Reference());
    std::printf("1280x720 L1 objective: default %.1f in %.2f s, reference schedule %.1f in %.2f s\n",
                d.stats.objective, d.stats.seconds, ref.stats.objective, ref.stats.seconds);
    EXPECT_LE(d.stats.objective, ref.stats.objective);
    ReconstructionResult exact = Reconstruct(g, ReconstructionOptions::L2Exact());
    ReconstructionResult cg = Reconstruct(g, ReconstructionOptions::L2CG());
    EXPECT_LE(MaxAbsDiff(exact.image, cg.image), 2e-4 * MaxAbs(exact.image));
}
