// mlt in participating media: the media's random numbers (distance sampling,
// delta tracking, ratio-tracking transmittance) are read from the primary
// samples (mlt.h), so that a state's contribution is a function of its
// primary sample vector alone and a small step moves the media's numbers
// by as little as the rest. Agreement with bdpt in expectation:
// tests/integrators/media_test.cpp.
#include <fstream>
#include <sstream>

#include "mlt_test_util.h"

namespace gradus::mlt_test {
namespace {

// scenes/media/fog-box.pbrt (a homogeneous smoke sphere behind a material-less
// interface) with its fog replaced by a 3x2x3 density grid over the room
// (grey sigma_t 0.5 x density): delta tracking in the walks, ratio tracking in
// the connections.
std::string GridFogBox() {
    std::ifstream f(std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt");
    std::stringstream ss;
    ss << f.rdbuf();
    std::string text = ss.str();
    const std::string fog =
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
        "    \"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.35 0.3 0.25] \"float g\" [0.3]\n";
    const std::string grid =
        "MakeNamedMedium \"fog\" \"string type\" \"heterogeneous\"\n"
        "    \"rgb sigma_a\" [0.0625 0.125 0.1875] \"rgb sigma_s\" [0.4375 0.375 0.3125] \"float g\" [0.3]\n"
        "    \"point p0\" [-1.5 0 -3.3] \"point p1\" [1.5 2 1.5] \"integer nx\" [3] \"integer ny\" [2] \"integer nz\" [3]\n"
        "    \"float density\" [0.5 1 2  0 1.5 1  2 0.5 1  1 0 2  1.5 1 0.5  0 2 1]\n";
    const std::string line = "Integrator \"bdpt\" \"integer maxdepth\" [5]";
    const size_t a = text.find(fog), b = text.find(line);
    if (a == std::string::npos || b == std::string::npos) {
        ADD_FAILURE() << "fog-box.pbrt changed";
        return text;
    }
    text.replace(b, line.size(), MLTLine("\"integer maxdepth\" [5] \"float sigma\" [1e-7]"));
    text.replace(a, fog.size(), grid);
    return text;
}

// For states carrying light at depths 1-5: (1) a copy of the state, whose
// unread coordinates would come from another RNG, has the same contribution
// bit for bit (nothing else feeds the media); (2) a small step of deviation
// 1e-7 changes it by less than 1e-4 relative for at least 90% of the states
// (measured: 400 of 400; with the media drawing from an RNG keyed by the film
// and lens position, as bdpt's, deterministic but redrawn by any step: 0 of 400).
TEST(MLTMedia, ContributionIsAFunctionOfThePrimarySamplesAndSmallStepsPerturbIt) {
    BuildOptions bo;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseString(GridFogBox()), bo);
    auto &mlt = dynamic_cast<MLTIntegrator &>(*job.integrator);
    mlt.preprocess(*job.scene, *job.film);
    Arena arena;
    int lit = 0, kept = 0;
    for (int i = 0; i < 4000 && lit < 400; ++i) {
        const int depth = 1 + i % 5;
        RNG rng(Hash(23, uint64_t(i)));
        mlt::PrimarySampler u(mlt.settings().sigma, 0);  // small steps only
        u.restart(&rng);
        Point2 p;
        const Spectrum L = mlt.contribution(u, depth, arena, &p);
        arena.reset();
        if (!(L.y() > 0)) continue;
        ++lit;
        mlt::PrimarySampler copy = u;
        RNG other(Hash(99, uint64_t(i)));
        copy.setRNG(&other);
        Point2 pc;
        const Spectrum Lc = mlt.contribution(copy, depth, arena, &pc);
        arena.reset();
        EXPECT_TRUE(Lc.r == L.r && Lc.g == L.g && Lc.b == L.b && pc.x == p.x && pc.y == p.y)
            << "state " << i << ": (" << L.r << ", " << L.g << ", " << L.b << ") re-evaluated (" << Lc.r << ", "
            << Lc.g << ", " << Lc.b << ")";
        u.propose();
        Point2 py;
        const Spectrum Ly = mlt.contribution(u, depth, arena, &py);
        arena.reset();
        u.reject();
        if (std::abs(Ly.y() - L.y()) < 1e-4 * L.y()) ++kept;
    }
    ASSERT_GE(lit, 200);
    std::cout << "[ media ] " << kept << " of " << lit << " states kept their contribution within 1e-4 after a step of 1e-7\n";
    EXPECT_GE(kept, 0.9 * lit);
}

// Chains start from their bootstrap states exactly (the re-evaluation reads
// the same primary samples, media included), and the image mean is b.
TEST(MLTMedia, ChainStartsRecreateTheirBootstrapStates) {
    std::string text = GridFogBox();
    const std::string from = "\"float sigma\" [1e-7]";
    text.replace(text.find(from), from.size(), "\"integer bootstrapsamples\" [2000] \"integer chains\" [64]");
    Rendered r = Render(text, 4, 3);
    const auto c = r.mlt().counts();
    EXPECT_EQ(c.startMismatch, 0);
    EXPECT_EQ(c.nonFinite, 0);
    EXPECT_GT(c.smallAccepted, 0);
    EXPECT_NEAR(MeanLum(r.image) / r.mlt().b(), 1, 1e-5);
}

}  // namespace
}  // namespace gradus::mlt_test
