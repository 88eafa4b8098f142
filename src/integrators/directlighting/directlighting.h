// Direct lighting (pbrt-v3's "directlighting", the default integrator of
// several exporters): at every hit the emitted radiance and the light
// reflected straight from the lights, each light estimated by multiple
// importance sampling of a light sample and a BSDF sample (power heuristic,
// Veach 1997 Eq. 9.13; specular lobes excluded), plus the specular lobes
// followed recursively up to maxdepth as in whitted (see whitted.h).
//
// Parameters (pbrt-v3 names and defaults):
//   integer maxdepth 5            maximum recursion depth of specular reflection and transmission
//   string strategy "all"         all: every light, with its "samples" count (area and infinite lights); one: one light chosen uniformly
//   integer pixelbounds []        accepted (use --cropwindow instead)
#pragma once
#include "integrators/whitted/whitted.h"

namespace gradus {

struct DirectLightingSettings {
    int maxDepth;
    std::string strategy;
    std::vector<int> pixelBounds;
};

ParamTable<DirectLightingSettings> DirectLightingParams();

class DirectLightingIntegrator : public WhittedIntegrator {
  public:
    explicit DirectLightingIntegrator(const EntityDesc &desc);
    std::string name() const override { return "directlighting"; }
    // One light's reflected radiance at isect: a light sample and a BSDF
    // sample combined by the power heuristic (exposed for tests).
    Spectrum estimateDirect(const SurfaceInteraction &isect, const BSDF &bsdf, const Light &light,
                            Sampler &sampler) const;

  protected:
    Spectrum direct(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler) const override;

  private:
    DirectLightingIntegrator(const DirectLightingSettings &set, const FileLoc &loc);
    bool sampleAll_;
};

}  // namespace gradus
