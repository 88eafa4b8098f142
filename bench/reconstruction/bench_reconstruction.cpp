// Reconstruction timings at 1280x720 RGB on a noisy render-like input.
// Counters: "objective" (the minimised energy of the preset) and CG iterations.
#include <benchmark/benchmark.h>

#include "../../tests/reconstruction/recon_test_util.h"
#include "reconstruction/poisson_ops.h"
#include "reconstruction/reconstruction.h"

using namespace gradus;

namespace {

const GradientImages &Input() {
    static const GradientImages g = [] {
        const int W = 1280, H = 720;
        GradientImages in = testutil::ExactInputs(testutil::SceneImage(W, H), W, H);
        testutil::AddNoise(in, 0.3, 0.05, 21, 0.01, 8.0);
        in.primalVar.assign(in.primal.size(), 0.09f);
        in.dxVar.assign(in.primal.size(), 0.0025f);
        in.dyVar = in.dxVar;
        return in;
    }();
    return g;
}

void Run(benchmark::State &state, ReconstructionOptions opt) {
    const GradientImages &g = Input();
    ReconstructionStats st;
    for (auto _ : state) {
        ReconstructionResult r = Reconstruct(g, opt);
        benchmark::DoNotOptimize(r.image.data());
        st = r.stats;
    }
    state.counters["objective"] = st.objective;
    state.counters["cg_iterations"] = st.cgIterations;
}

// Cost of one Jacobi-PCG iteration at 1280x720x3 (unit weights).
void CGIteration(benchmark::State &state) {
    const GradientImages &g = Input();
    recon::PoissonProblem P;
    P.W = g.width;
    P.H = g.height;
    P.C = 3;
    P.N = size_t(P.W) * P.H;
    P.p.resize(3 * P.N);
    P.gx = P.gy = P.p;
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < P.N; ++i) {
            P.p[c * P.N + i] = g.primal[i * 3 + c];
            P.gx[c * P.N + i] = g.dx[i * 3 + c];
            P.gy[c * P.N + i] = g.dy[i * 3 + c];
        }
    P.setUnitWeights();
    std::vector<float> x = P.p;
    for (auto _ : state) recon::SolveCG(P, x.data(), int(state.range(0)), 0.0, recon::CGPrecond::Jacobi);
    state.SetItemsProcessed(state.iterations() * state.range(0));
}

// L1Default's IRLS with other schedules: IRLS iterations x CG iterations per
// solve (ranges 0 and 1), to see which schedules reach the reference
// schedule's objective in less time.
void L1Schedule(benchmark::State &state) {
    ReconstructionOptions o = ReconstructionOptions::L1Default();
    o.irlsIterations = int(state.range(0));
    o.cgIterations = int(state.range(1));
    Run(state, o);
}

}  // namespace

BENCHMARK(L1Schedule)->ArgsProduct({{12, 14, 16, 18, 20, 24}, {6, 8, 10}})->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);
BENCHMARK_CAPTURE(Run, Hybrid, ReconstructionOptions::Hybrid())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK(CGIteration)->Arg(1)->Arg(21)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(Run, L2Exact, ReconstructionOptions::L2Exact())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(Run, L2CGJacobi, [] {
    ReconstructionOptions o = ReconstructionOptions::L2CG();
    o.preconditioner = Preconditioner::Jacobi;
    return o;
}())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);
BENCHMARK_CAPTURE(Run, L2CGMultigrid, ReconstructionOptions::L2CG())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);
BENCHMARK_CAPTURE(Run, L1Default, ReconstructionOptions::L1Default())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(Run, L1ReferenceSchedule, ReconstructionOptions::L1Reference())
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);
BENCHMARK_CAPTURE(Run, Weighted, ReconstructionOptions::Weighted())->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);

BENCHMARK_MAIN();
