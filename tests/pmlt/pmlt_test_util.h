// Helpers of the pmlt tests: a scene of the conformance table loaded in
// memory with the bidirectional context pmlt builds, and bidirectional
// samples whose strategies give paths with known densities.
#pragma once
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "integrators/pmlt/mutations.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "samplers/rng_sampler.h"

namespace gradus::pmlt_test {

inline std::string ReadFile(const std::string &path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

inline std::string ConformanceScene(const std::string &name) {
    return ReadFile(std::string(GRADUS_SOURCE_DIR) + "/tests/conformance/data/" + name + ".pbrt");
}

struct SceneSetup {
    RenderJob job;
    LightSampler lights;
    BidirContext ctx;
    pmlt::FilmDomain film;
    int maxDepth = 5;
    explicit SceneSetup(const std::string &text) {
        BuildOptions bo;
        bo.quiet = true;
        job = BuildRenderJob(ParseString(text), bo);
        lights = LightSampler(job.scene->lights, "power", FileLoc());
        ctx.init(*job.scene, lights, MISHeuristic::Balance);
        ctx.rrDepth = -1;
        film.pixels = job.film->pixelBounds();
        film.scale = 1;
    }
};

// One bidirectional sample (camera and light subpaths of up to maxDepth + 2
// and maxDepth + 1 vertices) drawn from rng, in arena.
struct BidirSample {
    PathVertex *cv = nullptr, *lv = nullptr;
    BSDF *cb = nullptr, *lb = nullptr;
    int nC = 0, nL = 0;
    bool make(const SceneSetup &su, RNG &rng, Arena &arena) {
        RNGSampler u(rng);
        CameraSample cs;
        cs.pFilm = su.film.sample(u.get2D());
        cs.pLens = u.get2D();
        Ray ray;
        if (su.ctx.camera->generateRay(cs, &ray) == 0) return false;
        AllocSubpath(arena, su.maxDepth + 2, &cv, &cb);
        AllocSubpath(arena, su.maxDepth + 1, &lv, &lb);
        nC = GenerateCameraSubpath(su.ctx, ray, u, arena, su.maxDepth + 2, cv, cb);
        nL = GenerateLightSubpath(su.ctx, u, arena, su.maxDepth + 1, lv, lb);
        return true;
    }
    SubpathView light(int s) const { return SubpathView{lv, lb, s}; }
    SubpathView camera(int t) const { return SubpathView{cv, cb, t}; }
};

inline ConnectSamples Numbers(RNG &rng) {
    ConnectSamples cu;
    cu.uLightSelect = Float(rng.uniform());
    cu.uLight = Point2(Float(rng.uniform()), Float(rng.uniform()));
    cu.uLens = Point2(Float(rng.uniform()), Float(rng.uniform()));
    return cu;
}

}  // namespace gradus::pmlt_test
