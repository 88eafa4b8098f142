// Integrator base class and the registry of integrator names.
#pragma once
#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "render/params.h"
#include "parser/scene_desc.h"
#include "render/render_loop.h"
#include "render/film.h"
#include "scene/scene.h"

namespace gradus {

// An integrator runs passes inside the one render loop (render/render_loop.h):
// beginPass / runPass / endPass, with all parallel work through the
// PassContext. finish() receives the render statistics.
class Integrator {
  public:
    virtual ~Integrator() = default;
    virtual std::string name() const = 0;
    // Called once after the scene is built: build light distributions, add film layers.
    virtual void preprocess(const Scene &scene, Film &film) {}
    // Samples per pixel of a render without --spp (0: the sampler's). A
    // positive count replaces the sampler's (mlt: mutationsperpixel).
    virtual int defaultSamplesPerPixel() const { return 0; }
    // Pixel samples one pass represents (splat normalisation, spp, budget checks).
    virtual int samplesPerPass(const RenderOptions &opts) const { return std::max(1, opts.sppPerPass); }
    virtual void beginPass(PassContext &ctx) {}
    virtual void runPass(PassContext &ctx) = 0;
    virtual void endPass(PassContext &ctx) {}
    // Adds integrator-specific results (e.g. reconstructed layers) to the output image.
    virtual void finish(const Film &film, const RenderStats &stats, Image *out) {}
    // Seconds finish() is expected to take (reserved from the time budget).
    virtual double finishEstimate() const { return 0; }
    // Integrator-specific statistics for the end-of-render report.
    virtual std::string statistics() const { return ""; }
    // Checkpoints (job/checkpoint.h): what later passes need beyond the
    // film and the pass index, as bytes (mlt: chains and b); loadState throws
    // Error on bytes it did not write. Counters of statistics() are per session.
    virtual std::string saveState() const { return ""; }
    virtual void loadState(const std::string &state) {
        if (!state.empty()) throw Error("checkpoint: integrator state given to " + name() + ", which keeps none");
    }
    // True when pass p needs nothing from passes before it but its index
    // (gradus --passes A:B can then render [A, B) alone); false for mlt.
    virtual bool independentPasses() const { return true; }
    // Scene parts an integrator must handle or refuse (the job refuses a scene
    // with media or BSSRDFs, at the Integrator directive, when these are false).
    virtual bool rendersMedia() const { return false; }
    virtual bool rendersSubsurface() const { return false; }
    // Cameras without an importance function (Camera::hasImportance false:
    // orthographic, environment, realistic) need an integrator that makes no
    // light-to-camera (t = 1) connections, or drops them (bdpt).
    virtual bool rendersCamerasWithoutImportance() const { return false; }
};

// An integrator that estimates independent camera samples: each pass is
// per-pixel-sample work over the whole image.
class PixelSampleIntegrator : public Integrator, public SampleEstimator {
  public:
    void beginPass(PassContext &ctx) override { scene_ = &ctx.scene(); }
    void runPass(PassContext &ctx) override { ctx.forEachPixelSample(*this); }

  protected:
    const Scene *scene_ = nullptr;
};

}  // namespace gradus
