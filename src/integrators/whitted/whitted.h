// Whitted-style ray tracing (pbrt-v3's "whitted"): at every hit the emitted
// radiance, one light sample per light without MIS, and the specular lobes
// followed recursively up to maxdepth. directlighting derives from it.
//
// Parameters (pbrt-v3 names and defaults):
//   integer maxdepth 5            maximum recursion depth of specular reflection and transmission
//   integer pixelbounds []        accepted (use --cropwindow instead)
//
// Specular recursion. pbrt-v3 traces the reflected and the transmitted ray
// of a specular vertex both, each weighted by its lobe (SpecularReflect +
// SpecularTransmit). Gradus's BSDFs sample their lobes through one call, so a
// BSDF made of exactly two specular lobes (glass: reflection + transmission)
// is split the same way, deterministically: both lobes are sampled and each
// is weighted f |cos| (their lobe probabilities sum to 1). Any other BSDF
// with a specular lobe follows one sampled lobe with weight f |cos| / pdf,
// an unbiased estimate of the same sum (other noise, same expected image).
// Participating media and BSSRDFs are refused (pbrt-v3's whitted and
// directlighting ignore them; use path).
#pragma once
#include <string>
#include <vector>

#include "materials/bsdf.h"
#include "render/integrator.h"
#include "render/params.h"

namespace gradus {

struct WhittedSettings {
    int maxDepth;
    std::vector<int> pixelBounds;
};

ParamTable<WhittedSettings> WhittedParams();

class WhittedIntegrator : public PixelSampleIntegrator {
  public:
    explicit WhittedIntegrator(const EntityDesc &desc);
    std::string name() const override { return "whitted"; }
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    bool rendersCamerasWithoutImportance() const override { return true; }
    // Radiance along a ray at recursion depth `depth` (exposed for tests).
    Spectrum Li(const Ray &ray, Sampler &sampler, Arena &arena, int depth) const;

  protected:
    WhittedIntegrator(int maxDepth, const FileLoc &loc) : maxDepth_(maxDepth), loc_(loc) {}
    // Reflected radiance from the lights at a surface hit (pbrt-v3's whitted:
    // one sampleLi per light, no MIS).
    virtual Spectrum direct(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler) const;
    // The specular lobes' share of the reflected radiance (see the header).
    Spectrum specular(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler, Arena &arena,
                      int depth) const;
    int maxDepth_;
    FileLoc loc_;
};

}  // namespace gradus
