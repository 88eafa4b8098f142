// The manifold walk: reaches the target, keeps half-vectors, fails explicitly,
// is reversible; both solvers.
#include <gtest/gtest.h>

#include <thread>

#include "configs.h"

using namespace gradus;
using namespace gradus::testing;

namespace {

std::vector<ChainConfig> WalkConfigs() {
    std::vector<ChainConfig> v;
    v.push_back(MirrorConfig());
    v.push_back(MirrorConfig(true));
    v.push_back(SlabConfig());
    v.push_back(SphereConfig());
    v.push_back(TwoSlabConfig());
    return v;
}

Float Scale(const ManifoldSurfacePoint &a, const ManifoldSurfacePoint &b) {
    return std::max({MaxComponent(Abs(a.p)), MaxComponent(Abs(b.p)), Distance(a.p, b.p)});
}

class WalkTest : public ::testing::TestWithParam<ManifoldSolver> {
  protected:
    ManifoldWalkOptions opts() const {
        ManifoldWalkOptions o;
        o.solver = GetParam();
        return o;
    }
};

}  // namespace

TEST_P(WalkTest, ReachesTargetAndKeepsHalfVectors) {
    for (const ChainConfig &cfg : WalkConfigs()) {
        ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
        ASSERT_TRUE(r.ok()) << cfg.name << ": " << ToString(r.status);
        const ManifoldChain &c = r.chain;
        ASSERT_EQ(c.size, cfg.base.size);
        Float scale = Scale(cfg.base.front().sp, cfg.target);
        EXPECT_LT(Distance(c.back().sp.p, cfg.target.p) / scale, 1e-7) << cfg.name;
        EXPECT_GT(Distance(c.back().sp.p, cfg.base.back().sp.p), 0.05) << cfg.name << ": end did not move";
        for (int i = 1; i < c.size - 1; ++i) {
            bool ok;
            Vec2 o = ProjectedHalfVector(c, i, &ok);
            ASSERT_TRUE(ok);
            EXPECT_NEAR(o.x, cfg.base.v[i].o.x, 1e-10) << cfg.name << " vertex " << i;
            EXPECT_NEAR(o.y, cfg.base.v[i].o.y, 1e-10) << cfg.name << " vertex " << i;
            EXPECT_EQ(c.v[i].sp.primitiveId, cfg.base.v[i].sp.primitiveId);
            // On the real surface: re-project onto the shape and compare.
            ManifoldSurfacePoint on = cfg.scene.pointOn(c.v[i].sp.primitiveId, c.v[i].sp.p);
            EXPECT_LT(Distance(on.p, c.v[i].sp.p), 1e-12 * scale) << cfg.name;
        }
        EXPECT_LE(r.iterations, 20);
    }
}

TEST_P(WalkTest, MirrorMatchesMirrorImageConstruction) {
    ChainConfig cfg = MirrorConfig();
    ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
    ASSERT_TRUE(r.ok());
    // Mirror z = 0: reflection point is where the segment start -> mirrored target crosses z = 0.
    Point3 a = cfg.base.front().sp.p, b = cfg.target.p;
    Point3 bm(b.x, b.y, -b.z);
    Float t = a.z / (a.z - bm.z);
    Point3 expected = a + (bm - a) * t;
    EXPECT_LT(Distance(r.chain.v[1].sp.p, expected), 1e-6);
}

TEST_P(WalkTest, SlabSatisfiesSnellAtBothInterfaces) {
    ChainConfig cfg = SlabConfig();
    ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
    ASSERT_TRUE(r.ok());
    const ManifoldChain &c = r.chain;
    for (int i = 1; i <= 2; ++i) {
        Vec3 win = Normalize(c.v[i].sp.p - c.v[i - 1].sp.p), wout = Normalize(c.v[i + 1].sp.p - c.v[i].sp.p);
        Vec3 n(0, 0, 1);
        Float etaIn = i == 1 ? 1.0 : 1.5, etaOut = i == 1 ? 1.5 : 1.0;
        Vec3 tIn = win - n * Dot(win, n), tOut = wout - n * Dot(wout, n);
        // eta sin(theta) is conserved and the tangential directions agree.
        EXPECT_NEAR(etaIn * tIn.x, etaOut * tOut.x, 1e-7);
        EXPECT_NEAR(etaIn * tIn.y, etaOut * tOut.y, 1e-7);
    }
    // Parallel slab: the exit direction equals the entry direction.
    Vec3 d0 = Normalize(c.v[1].sp.p - c.v[0].sp.p), d3 = Normalize(c.v[3].sp.p - c.v[2].sp.p);
    EXPECT_LT(Distance(d0, d3), 1e-7);
}

TEST_P(WalkTest, MovedStartKeepsEndAndHalfVectors) {
    // The G-BDPT use: the start vertex moves (offset x_b), the end stays at x_c.
    for (const ChainConfig &cfg : WalkConfigs()) {
        ManifoldSurfacePoint newStart = cfg.scene.moveOn(cfg.base.front().sp,
                                                         cfg.base.front().s * 0.1 + cfg.base.front().t * 0.05);
        ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, newStart, cfg.base.back().sp, opts());
        ASSERT_TRUE(r.ok()) << cfg.name << ": " << ToString(r.status);
        EXPECT_LT(Distance(r.chain.back().sp.p, cfg.base.back().sp.p) / Scale(newStart, cfg.base.back().sp), 1e-7);
        EXPECT_LT(Distance(r.chain.front().sp.p, newStart.p), 1e-15);
        for (int i = 1; i < r.chain.size - 1; ++i) {
            Vec2 o = ProjectedHalfVector(r.chain, i);
            EXPECT_NEAR(o.x, cfg.base.v[i].o.x, 1e-10);
            EXPECT_NEAR(o.y, cfg.base.v[i].o.y, 1e-10);
        }
    }
}

TEST_P(WalkTest, WalkIsReversible) {
    for (const ChainConfig &cfg : WalkConfigs()) {
        ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
        ASSERT_TRUE(r.ok()) << cfg.name;
        EXPECT_EQ(CheckReversible(cfg.scene, cfg.base, r.chain, opts()), ManifoldStatus::Success) << cfg.name;
        // A chain that is not the walk's result must be reported as not reversible.
        ManifoldSurfacePoint moved = cfg.scene.moveOn(cfg.base.v[1].sp, cfg.base.v[1].s * 0.01);
        ManifoldChain wrongBase = cfg.base;
        SetupManifoldVertex(&wrongBase.v[1], moved, &cfg.base.v[1].frameRef);
        EXPECT_EQ(CheckReversible(cfg.scene, wrongBase, r.chain, opts()), ManifoldStatus::NotReversible)
            << cfg.name;
    }
}

TEST_P(WalkTest, LeftSurfaceOnFiniteMirror) {
    AnalyticScene scene;
    int mirror = scene.addPlane({0, 0, 0}, {0, 0, 1}, 1, 1, 0.5);  // small mirror, nothing behind
    int startId = scene.addPlane({-2, 0, 3}, {1, 0, -1}, 1, 1, 0.5);
    int endId = scene.addPlane({2.5, 0.3, 2}, {-1, 0, -0.3}, 1, 1, 5);
    ManifoldChain base;
    ASSERT_TRUE(TraceSpecular(scene, scene.pointOn(startId, {-2, 0, 3}), {0.1, 0.05, 0}, {mirror, endId}, {true}, &base));
    // Reaching this target needs a reflection point far outside the mirror.
    ManifoldSurfacePoint target = scene.moveOn(base.back().sp, base.back().s * 3 + base.back().t * 3);
    ManifoldWalkResult r = ManifoldWalk(scene, base, base.front().sp, target, opts());
    EXPECT_EQ(r.status, ManifoldStatus::LeftSurface) << ToString(r.status);
}

TEST_P(WalkTest, OccludedByBlocker) {
    ChainConfig cfg = MirrorConfig();
    // A blocker in front of the end patch covering the moved target's approach.
    AnalyticScene scene = cfg.scene;
    Point3 tp = cfg.target.p;
    Point3 m = cfg.base.v[1].sp.p;
    Point3 mid = m + (tp - m) * 0.8;
    scene.addPlane(mid, Normalize(tp - m), 1, 1, 0.05);
    ManifoldWalkResult r = ManifoldWalk(scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
    EXPECT_FALSE(r.ok());
    EXPECT_EQ(r.status, ManifoldStatus::Occluded) << ToString(r.status);
}

TEST_P(WalkTest, TotalInternalReflection) {
    // Glass wedge: enter through z = 0, leave through a face tilted by 35 degrees.
    // Floor targets far to the left need an exit beyond grazing, i.e. an internal
    // incidence above the critical angle.
    AnalyticScene scene;
    Float s35 = std::sin(Radians(35)), c35 = std::cos(Radians(35));
    int faceA = scene.addPlane({0, 0, 0}, {0, 0, 1}, 1.5, 1);
    int faceB = scene.addPlane({0, 0, -1}, {s35, 0, -c35}, 1.5, 1);
    int floor = scene.addPlane({0, 0, -4}, {0, 0, 1});
    int startId = scene.addPlane({-1, 0, 2}, {0, 0, -1}, 1, 1, 0.5);
    ManifoldChain base;
    ASSERT_TRUE(TraceSpecular(scene, scene.pointOn(startId, {-1, 0, 2}), {-0.5, 0, 0},
                              {faceA, faceB, floor}, {false, false}, &base));
    ManifoldSurfacePoint target = scene.pointOn(floor, {-20, 0.3, -4});
    ManifoldWalkResult r = ManifoldWalk(scene, base, base.front().sp, target, opts());
    EXPECT_EQ(r.status, ManifoldStatus::TotalInternalReflection) << ToString(r.status);
}

TEST_P(WalkTest, IterationCapIsItsOwnStatus) {
    ChainConfig cfg = SphereConfig();
    ManifoldWalkOptions o = opts();
    o.maxIterations = 1;
    ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, o);
    EXPECT_EQ(r.status, ManifoldStatus::IterationCap) << ToString(r.status);
    EXPECT_GT(r.relativeError, 1e-7);
}

// A walk whose start did not move begins at the base chain itself: walking to
// the base's own end costs no trace at all, and a walk elsewhere one per iteration.
TEST_P(WalkTest, UnmovedStartIsNotRetraced) {
    ChainConfig cfg = SlabConfig();
    ManifoldWalkResult same = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.base.back().sp, opts());
    ASSERT_TRUE(same.ok()) << ToString(same.status);
    EXPECT_EQ(same.traces, 0);
    EXPECT_EQ(same.iterations, 0);
    if (GetParam() == ManifoldSolver::Newton) {
        ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target, opts());
        ASSERT_TRUE(r.ok()) << ToString(r.status);
        EXPECT_EQ(r.traces, r.iterations);
    }
}

// An unreachable target (the end plane behind the start, seen only through the
// mirror's back side) fails within a few iterations, not at the cap, and not as
// "iteration cap".
TEST(ManifoldWalkFastFailure, InfeasibleTargetFailsBeforeTheCap) {
    ChainConfig cfg = SphereConfig();
    // Far outside the caustic the sphere can focus onto the end plane.
    ManifoldSurfacePoint target = cfg.scene.moveOn(cfg.base.back().sp, Vec3(0, 40, 25));
    ManifoldWalkOptions o;
    o.maxIterations = 200;
    ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, target, o);
    EXPECT_FALSE(r.ok());
    EXPECT_NE(r.status, ManifoldStatus::IterationCap) << ToString(r.status);
    EXPECT_LT(r.iterations, 30) << ToString(r.status);
}

TEST_P(WalkTest, TargetOnOtherPrimitiveIsInvalid) {
    ChainConfig cfg = MirrorConfig();
    ManifoldSurfacePoint wrong = cfg.scene.pointOn(0, {0.5, 0.5, 0});
    ManifoldWalkResult r = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, wrong, opts());
    EXPECT_EQ(r.status, ManifoldStatus::InvalidInput);
}

INSTANTIATE_TEST_SUITE_P(Solvers, WalkTest,
                         ::testing::Values(ManifoldSolver::Newton, ManifoldSolver::CeresTiny),
                         [](const auto &info) {
                             return info.param == ManifoldSolver::Newton ? std::string("Newton")
                                                                         : std::string("CeresTiny");
                         });

TEST(ManifoldStats, CountsWalksAndFailuresAcrossThreads) {
    ChainConfig cfg = SlabConfig();
    ResetManifoldStats();
    const int perThread = 50;
    auto work = [&] {
        for (int i = 0; i < perThread; ++i) {
            ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, cfg.target);
            ManifoldSurfacePoint wrong = cfg.scene.pointOn(0, {0, 0, 0});
            ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, wrong);  // invalid input
        }
    };
    std::thread a(work), b(work);
    a.join();
    b.join();
    ManifoldStatsSnapshot s = GetManifoldStats();
    EXPECT_EQ(s.walks, uint64_t(4 * perThread));
    EXPECT_EQ(s.successes, uint64_t(2 * perThread));
    EXPECT_EQ(s.failures(), uint64_t(2 * perThread));
    EXPECT_EQ(s.byStatus[size_t(ManifoldStatus::InvalidInput)], uint64_t(2 * perThread));
    EXPECT_GE(s.iterations, uint64_t(2 * perThread));  // every successful walk iterates
    EXPECT_GE(s.traces, s.iterations);
}
