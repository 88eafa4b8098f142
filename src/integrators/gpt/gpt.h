// Gradient-domain path tracing (Kettunen et al. 2015, "Gradient-Domain Path
// Tracing"; summary in gradient-domain-bdpt.md Sec. 2.1-2.2 and 4).
//
// Each camera sample traces a base path (next-event estimation + BSDF
// sampling, power-heuristic MIS, pbrt-v3 "path" conventions) and four offset
// paths shifted by one pixel (+x, -x, +y, -y). The offset follows the base
// with half-vector copy (or random replay) until the base has two consecutive
// rough vertices, then reconnects (gradient/shift.h). Gradients use the
// symmetric estimator with gradient MIS combined with NEE/BSDF MIS (G-BDPT
// Eq. 8 with the power heuristic); failed or non-invertible shifts fall back
// to counting the base contribution alone (Sec. 2.2). The primal and
// gradients are reconstructed at the end (screened Poisson). Emission reached
// after Dirac bounces only (emitters seen directly or through mirrors and
// glass) is separated light: primal and layer "separated", no gradients,
// added after the reconstruction (gradient_film.h). Scenes with participating
// media take gpt_volume.h's tracer (distance-copy and medium-vertex shifts).
//
// Parameters (path tracing, integrators/path/path.h):
//   integer maxdepth 5               maximum number of bounces
//   float rrthreshold 1              Russian roulette threshold (pbrt-v3, after 3 bounces)
//   string lightsamplestrategy "spatial"   uniform | power | spatial
//   integer pixelbounds []           accepted (use --cropwindow)
// (gradient family, integrators/gradient/gradient_params.h):
//   float shiftthreshold 0.001       roughness below which a vertex is not reconnected
//   string reconstruction "hybrid"   hybrid | l1 | l2 | weighted: the image in the unprefixed R,G,B
//   float alpha 0.2                  screened-Poisson primal weight
//   string pixelfilter "film"        film (the scene's PixelFilter, so gpt estimates the same image as
//                                    path; 9x lower relMSE than box against triangle-filtered references)
//                                    | box (a sample counts in its own pixel, as in the papers)
// (gpt):
//   string shift "halfvector"        halfvector (G-PT) | hybrid (random replay until reconnection)
//   integer separatedsamples 0       K extra camera walks per camera sample for the separated
//                                    light only (gradient_family.h; scenes without media)
#pragma once
#include <memory>

#include "integrators/common/bidir.h"
#include "integrators/gradient/gradient_film.h"
#include "integrators/gradient/gradient_params.h"
#include "integrators/gradient/gradient_family.h"
#include "integrators/gradient/shift.h"
#include "render/integrator.h"
#include "integrators/path/path.h"
#include "lights/light_sampler.h"

namespace gradus {

// Every field is set by the parameter table (gpt.cpp).
struct GPTSettings : PathSettings, GradientSettings {
    enum class ShiftMode { HalfVector, Hybrid };
    ShiftMode mode;
    int separatedSamples;  // extra Dirac-only camera walks per camera sample (separated light)
};

class GPTIntegrator : public PixelSampleIntegrator, public GradientFamily {
  public:
    using ShiftMode = GPTSettings::ShiftMode;
    explicit GPTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "gpt"; }
    void preprocess(const Scene &scene, Film &film) override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    double finishEstimate() const override { return reconstructionEstimate(set_.norm, set_.alpha); }
    std::string statistics() const override;
    // Media: gpt_volume.h (a scene without media takes the surface-only tracer).
    bool rendersMedia() const override { return true; }

    // One camera sample without a film (for tests): primal and the four neighbour
    // differences; `pixelInside` says which neighbours exist.
    GradientSample sample(const CameraSample &cs, Sampler &sampler, Arena &arena,
                          const bool neighbourInside[kNumNeighbours]) const;
    const ShiftStats &shiftStats() const { return stats_; }

  private:
    GPTSettings set_;
    FileLoc loc_;
    LightSampler lightSampler_;
    bool volumetric_ = false;  // the scene has media: sample() takes gpt::VolumeGradientPathTracer
    BidirContext walkCtx_;     // the separatedsamples walks' scene and camera
    mutable ShiftStats stats_;
};

}  // namespace gradus
