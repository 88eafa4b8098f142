#include "integrators/gpt/gpt.h"

#include <algorithm>

#include "core/error.h"
#include "integrators/factories.h"
#include "integrators/gpt/gpt_tracer.h"
#include "integrators/gpt/gpt_volume.h"

namespace gradus {

std::unique_ptr<Integrator> CreateGPTIntegrator(const EntityDesc &d) { return std::make_unique<GPTIntegrator>(d); }

namespace {
ParamTable<GPTSettings> Table() {
    using S = GPTSettings;
    ParamTable<S> t("gpt");
    t.append(PathParams());
    t.append(GradientParams());
    t.enumeration<S::ShiftMode>("shift", &S::mode, "halfvector",
                                {{"halfvector", S::ShiftMode::HalfVector}, {"hybrid", S::ShiftMode::Hybrid}},
                                "offset paths: half-vector copy (G-PT), or hybrid: random replay until reconnection");
    t.integer("separatedsamples", &S::separatedSamples, 0,
              "extra camera walks through Dirac scattering only per camera sample, for the separated light "
              "(scenes without media)",
              AtLeast(0));
    return t;
}
}  // namespace

std::vector<ParamInfo> GPTParameters() { return Table().describe(); }

GPTIntegrator::GPTIntegrator(const EntityDesc &desc) : set_(Table().parse(desc)), loc_(desc.loc) {}

void GPTIntegrator::preprocess(const Scene &scene, Film &film) {
    lightSampler_ = LightSampler(scene.lights, set_.lightStrategy, loc_, scene.bounds);
    initGradients(film, set_.filmFilter);
    scene_ = &scene;
    volumetric_ = scene.features.media;
    if (set_.separatedSamples > 0 && volumetric_)
        throw Error(loc_, "gpt: \"separatedsamples\" needs a scene without media");
    if (set_.separatedSamples > 0) walkCtx_.init(scene, lightSampler_, MISHeuristic::Balance);
    stats_.reset();
}

void GPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    bool inside[kNumNeighbours];
    Point2i p = rec.pixel();
    // Box: only pairs of film pixels need gradients. Film filter: samples of
    // pixels around the film reach it too (targets outside are dropped).
    for (int k = 0; k < kNumNeighbours; ++k) inside[k] = set_.filmFilter || pairInside(p, k);
    GradientSample s = sample(cs, sampler, arena, inside);
    const int K = set_.separatedSamples;
    shareSeparated(&s, K);
    gfilm_.record(rec, s);
    if (K > 0) separatedWalks(walkCtx_, K, set_.maxDepth, cs, sampler, arena, rec);
}

void GPTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    finishGradients(film, stats, set_.norm, set_.alpha, out);
}

std::string GPTIntegrator::statistics() const {
    return withReconstructionReport(stats_.format(std::string("G-PT shifts (") +
                                                  (set_.mode == ShiftMode::Hybrid ? "hybrid" : "halfvector") +
                                                  ", threshold " + std::to_string(set_.shiftThreshold) + ")"));
}

GradientSample GPTIntegrator::sample(const CameraSample &cs, Sampler &sampler, Arena &arena,
                                     const bool inside[kNumNeighbours]) const {
    GradientSample out;
    LocalShiftStats st;
    if (volumetric_) {
        // Media draw from their own stream, keyed as path's (path.cpp).
        RNG rng(Hash(sampler.seed(), FloatBits(cs.pFilm.x), FloatBits(cs.pFilm.y), FloatBits(cs.pLens.x)));
        gpt::VolumeGradientPathTracer vt(*scene_, lightSampler_, set_.shiftThreshold, set_.mode == ShiftMode::Hybrid,
                                         inside, arena, st, rng);
        if (!vt.start(cs, &out)) return out;
        vt.trace(sampler, set_.maxDepth, set_.rrThreshold);
        vt.result(&out);
        stats_.add(st);
        return out;
    }
    gpt::GradientPathTracer tracer(*scene_, lightSampler_, set_.shiftThreshold, set_.mode == ShiftMode::Hybrid, inside, arena, st);
    if (!tracer.start(cs, &out)) return out;
    tracer.trace(sampler, set_.maxDepth, set_.rrThreshold);
    tracer.result(&out);
    stats_.add(st);
    return out;
}

}  // namespace gradus
