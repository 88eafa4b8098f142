// Microseconds per manifold walk and success rate, direct Newton vs
// ceres::TinySolver, on analytic chains with 1, 2 and 4 specular vertices.
#include <benchmark/benchmark.h>

#include <random>

#include "configs.h"

using namespace gradus;
using namespace gradus::testing;

namespace {

ChainConfig Config(int k) {
    switch (k) {
    case 1: return MirrorConfig();
    case 2: return SlabConfig();
    case 3: return SphereConfig();  // 2 vertices on a curved surface
    default: return TwoSlabConfig();
    }
}

void BM_Walk(benchmark::State &state) {
    ChainConfig cfg = Config(int(state.range(0)));
    ManifoldWalkOptions opts;
    opts.solver = state.range(1) == 0 ? ManifoldSolver::Newton : ManifoldSolver::CeresTiny;
    // Fixed set of targets: random moves of the end vertex within +-r in its tangent plane.
    Float r = cfg.name == "sphere" ? 0.3 : 1.5;
    std::mt19937 rng(1234);
    std::uniform_real_distribution<Float> u(-r, r);
    std::vector<ManifoldSurfacePoint> targets;
    for (int i = 0; i < 256; ++i)
        targets.push_back(cfg.scene.moveOn(cfg.base.back().sp, cfg.base.back().s * u(rng) + cfg.base.back().t * u(rng)));
    size_t i = 0, ok = 0, iters = 0, walks = 0, traces = 0;
    for (auto _ : state) {
        ManifoldWalkResult res = ManifoldWalk(cfg.scene, cfg.base, cfg.base.front().sp, targets[i], opts);
        benchmark::DoNotOptimize(res.chain.v[1].sp.p.x);
        ok += res.ok();
        iters += size_t(res.iterations);
        traces += size_t(res.traces);
        ++walks;
        i = (i + 1) % targets.size();
    }
    state.SetLabel(cfg.name + (opts.solver == ManifoldSolver::Newton ? "/newton" : "/ceres-tiny"));
    state.counters["success"] = double(ok) / double(walks);
    state.counters["iters"] = double(iters) / double(walks);
    state.counters["traces"] = double(traces) / double(walks);
}

}  // namespace

// Args: {chain (1 = mirror, 2 = slab, 3 = sphere, 4 = two slabs), solver (0 Newton, 1 Ceres)}
BENCHMARK(BM_Walk)
    ->ArgsProduct({{1, 2, 3, 4}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
