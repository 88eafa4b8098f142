// Rays per second inside path and bdpt against Embree's raw incoherent rays
// per second on the same scene (issue "Speed and scale").
//
//   bench_rays [--spp N] [--rays N] SCENE.pbrt ...
//
// For each scene and integrator: one single-threaded render (in process,
// RunRender), counting its closest-hit and shadow rays (the Rays/ counters);
// then the same numbers of incoherent rays traced bare through the
// accelerator (origins uniform in the scene's bounds, directions uniform on
// the sphere; shadow rays with tMax uniform up to the bounds' diagonal).
// "ray share" = the time those raw rays take / the render's time: the
// fraction of the render that tracing would take at Embree's raw speed; the
// issue's goal is >= 0.6 (path) and >= 0.5 (bdpt).
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/stats.h"
#include "job/job.h"
#include "samplers/sampling.h"

using namespace gradus;

namespace {

using Clock = std::chrono::steady_clock;

uint64_t Counter(const char *name) { return StatRegistry::get().snapshot()[name]; }

// Seconds to trace n closest-hit and m shadow random rays, one thread.
void RawRates(const Scene &scene, uint64_t n, uint64_t m, double *closestSec, double *shadowSec) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(0, 1);
    const Bounds3 &b = scene.bounds;
    const Float diag = (b.pMax - b.pMin).length();
    auto randomRay = [&](bool shadow) {
        Point3 o(Lerp(U(rng), b.pMin.x, b.pMax.x), Lerp(U(rng), b.pMin.y, b.pMax.y), Lerp(U(rng), b.pMin.z, b.pMax.z));
        return Ray(o, SampleUniformSphere(Point2(U(rng), U(rng))), shadow ? U(rng) * diag : Infinity);
    };
    constexpr size_t kBatch = 1 << 16;  // rays made ahead of timing
    std::vector<Ray> rays(kBatch);
    auto run = [&](uint64_t count, bool shadow) {
        double sec = 0;
        uint64_t hits = 0;
        for (uint64_t done = 0; done < count;) {
            const size_t k = size_t(std::min<uint64_t>(kBatch, count - done));
            for (size_t i = 0; i < k; ++i) rays[i] = randomRay(shadow);
            const auto t0 = Clock::now();
            for (size_t i = 0; i < k; ++i) {
                if (shadow) {
                    hits += scene.accel.occluded(rays[i]);
                } else {
                    RayHit h;
                    hits += scene.accel.intersect(rays[i], &h);
                }
            }
            sec += std::chrono::duration<double>(Clock::now() - t0).count();
            done += k;
        }
        if (hits == count + 1) std::printf("!");  // keeps the loop's results alive
        return sec;
    };
    *closestSec = run(n, false);
    *shadowSec = run(m, true);
}

}  // namespace

int main(int argc, char **argv) {
    int spp = 4;
    std::vector<std::string> scenes;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--spp") && i + 1 < argc) spp = std::atoi(argv[++i]);
        else if (argv[i][0] == '-') {
            std::fprintf(stderr, "usage: bench_rays [--spp N] SCENE.pbrt ...\n");
            return 2;
        } else scenes.push_back(argv[i]);
    }
    if (scenes.empty()) {
        for (const char *name : {"cornell-box", "veach-bidir", "veach-ajar"}) {
            auto p = std::filesystem::path(GRADUS_SOURCE_DIR) / ".." / "shared" / "references" / name / "ref.pbrt";
            if (std::filesystem::exists(p)) scenes.push_back(p.string());
        }
        if (scenes.empty()) scenes.push_back(std::string(GRADUS_SOURCE_DIR) + "/scenes/cornell-box.pbrt");
    }
    std::printf("| scene | integrator | spp | render s | closest rays | shadow rays | rays/s in render | raw closest rays/s "
                "| raw shadow rays/s | ray share |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (const std::string &path : scenes) {
        for (const char *integ : {"path", "bdpt"}) {
            try {
                BuildOptions bo;
                bo.integratorOverride = integ;
                bo.sppOverride = spp;
                bo.quiet = true;
                RenderJob job = BuildRenderJob(ParseFile(path), bo);
                RenderOptions ro;
                ro.spp = spp;
                ro.quiet = true;
                ro.nthreads = 1;
                const uint64_t c0 = Counter("Rays/Closest-hit rays"), s0 = Counter("Rays/Shadow rays");
                const auto t0 = Clock::now();
                job.integrator->preprocess(*job.scene, *job.film);
                RunRender(*job.integrator, *job.scene, *job.film, *job.sampler, ro);
                const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
                const uint64_t nc = Counter("Rays/Closest-hit rays") - c0, ns = Counter("Rays/Shadow rays") - s0;
                double rc, rs;
                RawRates(*job.scene, nc, ns, &rc, &rs);
                std::string name = std::filesystem::path(path).parent_path().filename().string();
                if (name.empty() || name == "scenes") name = std::filesystem::path(path).stem().string();
                std::printf("| %s | %s | %d | %.2f | %llu | %llu | %.3g | %.3g | %.3g | %.2f |\n", name.c_str(), integ, spp,
                            sec, (unsigned long long)nc, (unsigned long long)ns, (nc + ns) / sec, nc / rc, ns / rs,
                            (rc + rs) / sec);
                std::fflush(stdout);
            } catch (const std::exception &e) {
                std::fprintf(stderr, "%s (%s): %s\n", path.c_str(), integ, e.what());
                return 1;
            }
        }
    }
    return 0;
}
