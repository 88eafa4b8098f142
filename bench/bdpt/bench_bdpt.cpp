// BDPT throughput: camera samples/s and rays/s (closest-hit + shadow) on an
// in-code Cornell-like box and on ../shared/scenes/veach-bidir (via the
// reference variant, if present), and raw Embree incoherent rays/s on the
// same scenes (random origins in the bounds, uniform directions) for the
// ratio "rays/s inside BDPT / raw rays/s". Single thread.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "bdpt_test_util.h"
#include "core/stats.h"
#include "samplers/sampling.h"

using namespace gradus;
using namespace gradus::bdpt_test;

namespace {

const char *kVeach = GRADUS_SOURCE_DIR "/../shared/references/veach-bidir/ref.pbrt";

std::string CornellText() {
    return BoxScene("bdpt", CeilingLight(0.3, 12), Sphere("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.3]", 0.35, 0.45, 0.1, 0.45), 64);
}

bool LoadVeach(std::string *text) {
    if (!std::filesystem::exists(kVeach)) return false;
    std::ifstream in(kVeach);
    std::stringstream ss;
    ss << in.rdbuf();
    *text = ss.str();
    return true;
}

uint64_t RayCount() {
    auto s = StatRegistry::get().snapshot();
    return s["Rays/Closest-hit rays"] + s["Rays/Shadow rays"];
}

void RunBDPT(benchmark::State &state, const std::string &text, const std::string &dir, int spp) {
    BuildOptions bo;
    bo.integratorOverride = "bdpt";
    bo.sppOverride = spp;
    bo.quiet = true;
    SceneDesc desc = ParseString(text, dir + "/scene.pbrt", dir);
    RenderJob job = BuildRenderJob(desc, bo);
    job.integrator->preprocess(*job.scene, *job.film);
    RenderOptions ro;
    ro.spp = spp;
    ro.quiet = true;
    ro.nthreads = 1;
    int64_t samples = 0;
    uint64_t rays0 = RayCount();
    for (auto _ : state) {
        RenderStats st = RunRender(*job.integrator, *job.scene, *job.film, *job.sampler, ro);
        samples += st.cameraSamples;
    }
    uint64_t rays = RayCount() - rays0;
    state.counters["samples/s"] = benchmark::Counter(double(samples), benchmark::Counter::kIsRate);
    state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
    state.counters["rays/sample"] = double(rays) / double(std::max<int64_t>(samples, 1));
}

void RunRaw(benchmark::State &state, const std::string &text, const std::string &dir) {
    BuildOptions bo;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseString(text, dir + "/scene.pbrt", dir), bo);
    const Scene &scene = *job.scene;
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(0, 1);
    const int N = 1 << 16;
    std::vector<Ray> rays(N);
    for (auto &r : rays) {
        Point3 o(Lerp(U(rng), scene.bounds.pMin.x, scene.bounds.pMax.x), Lerp(U(rng), scene.bounds.pMin.y, scene.bounds.pMax.y),
                 Lerp(U(rng), scene.bounds.pMin.z, scene.bounds.pMax.z));
        r = Ray(o, SampleUniformSphere(Point2(U(rng), U(rng))));
    }
    int64_t n = 0;
    for (auto _ : state) {
        for (const Ray &r : rays) {
            RayHit h;
            benchmark::DoNotOptimize(scene.accel.intersect(r, &h));
        }
        n += N;
    }
    state.counters["rays/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsRate);
}

void BM_BDPT_Cornell(benchmark::State &s) { RunBDPT(s, CornellText(), "/tmp", 4); }
void BM_Raw_Cornell(benchmark::State &s) { RunRaw(s, CornellText(), "/tmp"); }
void BM_BDPT_VeachBidir(benchmark::State &s) {
    std::string t;
    if (!LoadVeach(&t)) return s.SkipWithError("veach-bidir absent");
    RunBDPT(s, t, std::filesystem::path(kVeach).parent_path().string(), 1);
}
void BM_Raw_VeachBidir(benchmark::State &s) {
    std::string t;
    if (!LoadVeach(&t)) return s.SkipWithError("veach-bidir absent");
    RunRaw(s, t, std::filesystem::path(kVeach).parent_path().string());
}

}  // namespace

BENCHMARK(BM_BDPT_Cornell)->Unit(benchmark::kMillisecond)->MinTime(2);
BENCHMARK(BM_Raw_Cornell)->Unit(benchmark::kMillisecond)->MinTime(1);
BENCHMARK(BM_BDPT_VeachBidir)->Unit(benchmark::kMillisecond)->MinTime(3);
BENCHMARK(BM_Raw_VeachBidir)->Unit(benchmark::kMillisecond)->MinTime(1);
BENCHMARK_MAIN();
