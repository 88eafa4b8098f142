// Unidirectional path tracer with next-event estimation and MIS (pbrt-v3's
// "path" semantics).
//
// Parameters (pbrt-v3 names and defaults):
//   integer maxdepth 5            maximum number of bounces
//   float rrthreshold 1           Russian roulette starts when max(beta) < rrthreshold (after 3 bounces)
//   string lightsamplestrategy "spatial"   uniform | power | spatial (see light_sampler.h)
//   integer pixelbounds []                 accepted (use --cropwindow instead)
// gpt takes the same parameters (PathParams).
#pragma once
#include <vector>

#include "render/integrator.h"
#include "render/params.h"
#include "lights/light_sampler.h"

namespace gradus {

// Every field is set by PathParams (defaults there).
struct PathSettings {
    int maxDepth;
    Float rrThreshold;
    std::string lightStrategy;
    std::vector<int> pixelBounds;  // accepted for pbrt-v3 scenes; --cropwindow crops
};

// maxdepth, rrthreshold, lightsamplestrategy, pixelbounds (path, gpt).
ParamTable<PathSettings> PathParams();

class PathIntegrator : public PixelSampleIntegrator {
  public:
    explicit PathIntegrator(const EntityDesc &desc);
    std::string name() const override { return "path"; }
    void preprocess(const Scene &scene, Film &film) override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    // Radiance along a camera ray (exposed for tests).
    Spectrum Li(const Ray &ray, Sampler &sampler, Arena &arena) const;
    // The same in a scene with participating media or BSSRDFs (pbrt-v3's
    // volpath; volpath.cpp): the camera ray starts in scene.cameraMedium;
    // `rng` serves distance sampling and transmittance estimates.
    Spectrum LiVolumetric(const Ray &ray, Sampler &sampler, Arena &arena, RNG &rng) const;
    int maxDepth() const { return set_.maxDepth; }
    bool rendersMedia() const override { return true; }
    bool rendersSubsurface() const override { return true; }
    bool rendersCamerasWithoutImportance() const override { return true; }

  private:
    // Next-event estimation at a surface (bsdf) or medium (phase) vertex, the
    // connection weighted against the scattering sample (volpath.cpp).
    Spectrum sampleLightVolumetric(const Interaction &it, const BSDF *bsdf, const Vec3 &shadingN,
                                   const HGPhase *phase, const Medium *medium, const SurfaceInteraction *surface,
                                   Sampler &sampler, RNG &rng) const;
    bool survivesRoulette(Spectrum *beta, Float etaScale, int bounces, Sampler &sampler) const;
    struct VolumePath;  // one path of LiVolumetric (volpath.cpp)
    bool volumetric_ = false;  // the scene has media or BSSRDFs: estimate() takes LiVolumetric
    PathSettings set_;
    FileLoc loc_;
    LightSampler lightSampler_;
};

}  // namespace gradus
