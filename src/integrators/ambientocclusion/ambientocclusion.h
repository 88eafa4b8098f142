// Ambient occlusion (pbrt-v3's "ambientocclusion"): at the first surface with
// a material, nsamples directions over the hemisphere of the geometric normal
// (turned towards the viewer), each unoccluded one adding cos / (pdf n):
// an estimate of the integral of V(w) cos(w) over the hemisphere, pi where
// nothing occludes (pbrt-v3's scale). Materials, lights and media play no part.
//
// Parameters (pbrt-v3 names and defaults):
//   bool cossample true           cosine-weighted directions (false: uniform over the hemisphere)
//   integer nsamples 64           directions per camera sample
//   integer pixelbounds []        accepted (use --cropwindow instead)
#pragma once
#include <string>
#include <vector>

#include "render/integrator.h"
#include "render/params.h"

namespace gradus {

struct AOSettings {
    bool cosSample;
    int nSamples;
    std::vector<int> pixelBounds;
};

ParamTable<AOSettings> AOParams();

class AOIntegrator : public PixelSampleIntegrator {
  public:
    explicit AOIntegrator(const EntityDesc &desc);
    std::string name() const override { return "ambientocclusion"; }
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    bool rendersCamerasWithoutImportance() const override { return true; }
    bool rendersMedia() const override { return true; }        // ignored, as pbrt-v3 does
    bool rendersSubsurface() const override { return true; }   // ignored, as pbrt-v3 does
    // The estimate along a camera ray (exposed for tests).
    Float occlusion(const Ray &ray, Sampler &sampler) const;

  private:
    AOSettings set_;
};

}  // namespace gradus
