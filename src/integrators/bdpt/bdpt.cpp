#include "integrators/bdpt/bdpt.h"

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"

namespace gradus {

std::unique_ptr<Integrator> CreateBDPTIntegrator(const EntityDesc &d) { return std::make_unique<BDPTIntegrator>(d); }

// bdpt's parameters are the bidirectional family's (rrdepth 3).
std::vector<ParamInfo> BDPTParameters() { return BidirParams().describe(); }

BDPTIntegrator::BDPTIntegrator(const EntityDesc &desc)
    : BidirFamily("bdpt", 1), set_(BidirParams().parse(desc)), loc_(desc.loc) {}

void BDPTIntegrator::preprocess(const Scene &scene, Film &film) {
    // One light subpath per camera sample (the splat scale: see LightTracingSplatScale).
    preprocessBidir(scene, film, set_, loc_);
    // A camera without importance (orthographic, environment, realistic) has no
    // t = 1 strategies; they leave the MIS sums too, so the others stay unbiased.
    ctx_.strategies.lightTracing = scene.camera->hasImportance();
}

void BDPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    GRADUS_STAT_COUNTER("BDPT/Camera samples", nSamples);
    GRADUS_STAT_COUNTER("BDPT/Connections (shadow rays)", nShadow);
    ++nSamples;
    const Scene &scene = *scene_;
    Ray ray;
    Float w = scene.camera->generateRay(cs, &ray);
    // A blocked sample (realistic camera: vignetted) still counts, with radiance 0,
    // as pbrt-v3's Film adds its filter weight: pixels average over all samples.
    if (w == 0) return rec.addRadiance(Spectrum(0));
    const int maxCam = set_.maxDepth + 2, maxLight = set_.maxDepth + 1;
    PathVertex *camV, *lightV;
    BSDF *camB, *lightB;
    AllocSubpath(arena, maxCam, &camV, &camB);
    AllocSubpath(arena, maxLight, &lightV, &lightB);

    BidirDimensions dims(sampler, maxCam, maxLight);  // fixed blocks of dimensions (bidir.h)
    // Media: distances and transmittances from a per-sample RNG (never the sampler's dimensions).
    RNG mediaRng;
    RNG *mrng = scene.features.media ? &(mediaRng = CameraSampleMediaRNG(sampler, cs)) : nullptr;
    int nC = GenerateCameraSubpath(ctx_, ray, sampler, arena, maxCam, camV, camB, mrng);
    dims.startLightSubpath(sampler);
    int nL = scene.lights.empty() ? 0 : GenerateLightSubpath(ctx_, sampler, arena, maxLight, lightV, lightB, mrng);
    SubpathView cam{camV, camB, nC}, light{lightV, lightB, nL};

    Spectrum L(0);
    for (int t = 1; t <= nC; ++t) {
        // s = 1 samples its own light point: it runs even when the light subpath is
        // empty (a projector's emission sample outside its slide, a failed sampleLe),
        // or next-event estimation would be lost with it.
        for (int s = 0; s <= std::max(nL, scene.lights.empty() ? 0 : 1); ++s) {
            int depth = s + t - 2;
            if ((s == 1 && t == 1) || depth < 0 || depth > set_.maxDepth) continue;
            ConnectSamples u;
            u.rng = mrng;
            dims.startConnection(sampler, s, t);
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
                if (layer >= 0) rec.splat(r.pRaster, (set_.visWeights ? r.L : r.unweighted) * splatScale_, layer);
            } else {
                L += r.L;
                int layer = strategyLayer(s, t);
                if (layer >= 0) rec.addLayer(layer, (set_.visWeights ? r.L : r.unweighted) * w);
            }
        }
    }
    rec.addRadiance(L * w);
}

}  // namespace gradus
