#include "integrators/bdpt/bdpt.h"

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"

namespace gradus {

std::unique_ptr<Integrator> CreateBDPTIntegrator(const EntityDesc &d) { return std::make_unique<BDPTIntegrator>(d); }

BDPTIntegrator::BDPTIntegrator(const EntityDesc &desc) : loc_(desc.loc) {
    const ParamSet &ps = desc.params;
    maxDepth_ = ps.getInt("maxdepth", 5);
    rrDepth_ = ps.getInt("rrdepth", 3);
    strategy_ = ps.getString("lightsamplestrategy", "power");
    visStrategies_ = ps.getBool("visualizestrategies", false);
    visWeights_ = ps.getBool("visualizeweights", false);
    std::string h = ps.getString("misheuristic", "balance");
    ps.getInts("pixelbounds");
    if (maxDepth_ < 0) throw Error(ps.locOf("maxdepth", desc.loc), "\"maxdepth\" must be >= 0");
    if (h == "balance")
        heuristic_ = MISHeuristic::Balance;
    else if (h == "power")
        heuristic_ = MISHeuristic::Power;
    else
        throw Error(ps.locOf("misheuristic", desc.loc),
                    "unknown \"misheuristic\" \"" + h + "\" (valid: balance, power)");
}

std::string BDPTIntegrator::LayerName(int s, int t) {
    return "bdpt_s" + std::to_string(s) + "_t" + std::to_string(t);
}

int BDPTIntegrator::strategyLayer(int s, int t) const {
    if (layers_.empty() || s < 0 || t < 0 || s > maxDepth_ + 2 || t > maxDepth_ + 2) return -1;
    return layers_[size_t(s) * (maxDepth_ + 3) + t];
}

void BDPTIntegrator::preprocess(const Scene &scene, Film &film) {
    lightSampler_ = LightSampler(scene.lights, strategy_, loc_);
    ctx_.init(scene, lightSampler_, heuristic_);
    ctx_.rrDepth = rrDepth_;
    // One light subpath per camera sample over the sampled pixels; the film
    // normalises splats by the samples per pixel, so light tracing estimates
    // the full image times (sampled pixels / full-image pixels).
    Point2i full = film.fullResolution();
    int64_t sampled = film.sampleBounds().area();
    splatScale_ = sampled > 0 ? Float(int64_t(full.x) * full.y) / Float(sampled) : 1;
    layers_.clear();
    if (visStrategies_ || visWeights_) {
        layers_.assign(size_t(maxDepth_ + 3) * (maxDepth_ + 3), -1);
        for (int depth = 0; depth <= maxDepth_; ++depth)
            for (int t = 1; t <= depth + 2; ++t) {
                int s = depth + 2 - t;
                layers_[size_t(s) * (maxDepth_ + 3) + t] = film.addLayer(LayerName(s, t));
            }
    }
}

void BDPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    GRADUS_STAT_COUNTER("BDPT/Camera samples", nSamples);
    GRADUS_STAT_COUNTER("BDPT/Connections (shadow rays)", nShadow);
    ++nSamples;
    const Scene &scene = *scene_;
    Ray ray;
    Float w = scene.camera->generateRay(cs, &ray);
    if (w == 0) return;
    const int maxCam = maxDepth_ + 2, maxLight = maxDepth_ + 1;
    PathVertex *camV = static_cast<PathVertex *>(arena.alloc(sizeof(PathVertex) * maxCam, alignof(PathVertex)));
    PathVertex *lightV = static_cast<PathVertex *>(arena.alloc(sizeof(PathVertex) * maxLight, alignof(PathVertex)));
    BSDF *camB = static_cast<BSDF *>(arena.alloc(sizeof(BSDF) * maxCam, alignof(BSDF)));
    BSDF *lightB = static_cast<BSDF *>(arena.alloc(sizeof(BSDF) * maxLight, alignof(BSDF)));
    for (int i = 0; i < maxCam; ++i) new (&camB[i]) BSDF();
    for (int i = 0; i < maxLight; ++i) new (&lightB[i]) BSDF();

    int nC = GenerateCameraSubpath(ctx_, ray, sampler, arena, maxCam, camV, camB);
    int nL = scene.lights.empty() ? 0 : GenerateLightSubpath(ctx_, sampler, arena, maxLight, lightV, lightB);
    SubpathView cam{camV, camB, nC}, light{lightV, lightB, nL};

    Spectrum L(0);
    for (int t = 1; t <= nC; ++t) {
        for (int s = 0; s <= nL; ++s) {
            int depth = s + t - 2;
            if ((s == 1 && t == 1) || depth < 0 || depth > maxDepth_) continue;
            ConnectSamples u;
            if (s == 1) {
                u.uLightSelect = sampler.get1D();
                u.uLight = sampler.get2D();
            }
            if (t == 1) u.uLens = sampler.get2D();
            ConnectResult r;
            bool ok = ConnectBDPT(ctx_, light, cam, s, t, u, &r);
            if (r.shadowRayTraced) ++nShadow;
            if (!ok) continue;
            if (DebugTracing())
                DebugTrace("strategy s=%d t=%d: weight %.4g, weighted (%.4g, %.4g, %.4g)%s", s, t, r.weight, r.L.r,
                           r.L.g, r.L.b, r.splat ? " (light tracing splat)" : "");
            if (r.splat) {
                rec.splat(r.pRaster, r.L * splatScale_);
                int layer = strategyLayer(s, t);
                if (layer >= 0) rec.splat(r.pRaster, (visWeights_ ? r.L : r.unweighted) * splatScale_, layer);
            } else {
                L += r.L;
                int layer = strategyLayer(s, t);
                if (layer >= 0) rec.addLayer(layer, (visWeights_ ? r.L : r.unweighted) * w);
            }
        }
    }
    rec.addRadiance(L * w);
}

}  // namespace gradus
