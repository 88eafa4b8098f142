#include "integrators/gpt/gpt.h"

#include <algorithm>

#include "core/error.h"
#include "integrators/factories.h"
#include "integrators/gpt/gpt_tracer.h"

namespace gradus {

std::unique_ptr<Integrator> CreateGPTIntegrator(const EntityDesc &d) { return std::make_unique<GPTIntegrator>(d); }

GPTIntegrator::GPTIntegrator(const EntityDesc &desc) : loc_(desc.loc) {
    const ParamSet &ps = desc.params;
    maxDepth_ = ps.getInt("maxdepth", 5);
    rrThreshold_ = ps.getFloat("rrthreshold", 1);
    strategy_ = ps.getString("lightsamplestrategy", "spatial");
    shiftThreshold_ = ps.getFloat("shiftthreshold", 0.001);
    std::string mode = ps.getString("shift", "halfvector");
    std::string rec = ps.getString("reconstruction", "l1");
    alpha_ = ps.getFloat("alpha", 0.2);
    std::string pf = ps.getString("pixelfilter", "film");
    if (pf != "box" && pf != "film")
        throw Error(ps.locOf("pixelfilter", desc.loc), "unknown \"pixelfilter\" \"" + pf + "\" (box, film)");
    filmFilter_ = pf == "film";
    ps.getInts("pixelbounds");
    if (maxDepth_ < 0) throw Error(ps.locOf("maxdepth", desc.loc), "\"maxdepth\" must be >= 0");
    if (!(shiftThreshold_ >= 0)) throw Error(ps.locOf("shiftthreshold", desc.loc), "\"shiftthreshold\" must be >= 0");
    if (!(alpha_ >= 0)) throw Error(ps.locOf("alpha", desc.loc), "\"alpha\" must be >= 0");
    if (mode == "halfvector")
        mode_ = ShiftMode::HalfVector;
    else if (mode == "hybrid")
        mode_ = ShiftMode::Hybrid;
    else
        throw Error(ps.locOf("shift", desc.loc), "unknown \"shift\" \"" + mode + "\" (halfvector, hybrid)");
    try {
        norm_ = ParseReconstructionNorm(rec);
    } catch (const Error &) {
        throw Error(ps.locOf("reconstruction", desc.loc),
                    "unknown \"reconstruction\" \"" + rec + "\" (l1, l2, weighted)");
    }
}

void GPTIntegrator::preprocess(const Scene &scene, Film &film) {
    lightSampler_ = LightSampler(scene.lights, strategy_, loc_, scene.bounds);
    initGradients(film, filmFilter_);
    scene_ = &scene;
    stats_.reset();
}

void GPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    bool inside[kNumNeighbours];
    Point2i p = rec.pixel();
    // Box: only pairs of film pixels need gradients. Film filter: samples of
    // pixels around the film reach it too (targets outside are dropped).
    for (int k = 0; k < kNumNeighbours; ++k) inside[k] = filmFilter_ || pairInside(p, k);
    GradientSample s = sample(cs, sampler, arena, inside);
    gfilm_.record(rec, s);
}

void GPTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    finishGradients(film, stats, norm_, alpha_, out);
}

std::string GPTIntegrator::statistics() const {
    return withReconstructionReport(stats_.format(std::string("G-PT shifts (") +
                                                  (mode_ == ShiftMode::Hybrid ? "hybrid" : "halfvector") +
                                                  ", threshold " + std::to_string(shiftThreshold_) + ")"));
}

GradientSample GPTIntegrator::sample(const CameraSample &cs, Sampler &sampler, Arena &arena,
                                     const bool inside[kNumNeighbours]) const {
    GradientSample out;
    LocalShiftStats st;
    gpt::GradientPathTracer tracer(*scene_, lightSampler_, shiftThreshold_, mode_ == ShiftMode::Hybrid, inside, arena, st);
    if (!tracer.start(cs, &out)) return out;
    tracer.trace(sampler, maxDepth_, rrThreshold_);
    tracer.result(&out);
    stats_.add(st);
    return out;
}

}  // namespace gradus
