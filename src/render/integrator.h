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

// ---- Pass bookkeeping of the Metropolis integrators (mlt, pmlt)
// A render's mutations are dealt to the chains round-robin by a running
// index: chain i performs ChainShare(x, i, chains) of the first x, so any split
// into passes gives every chain the same mutations.
inline int64_t ChainShare(int64_t x, int64_t i, int64_t chains) { return x > i ? (x - i - 1) / chains + 1 : 0; }

// Ends a Metropolis render: an interrupt can skip chains of the last pass, so
// the main image's R, G, B are scaled by issued / performed mutations (the
// factor is returned); writes <prefix>_b, _mutations, _chains and _warning.
// Writes <prefix>_b, _mutations, _chains and _warning.
inline void WriteMetropolisMetadata(Metadata *m, const std::string &prefix, double b, int64_t performed,
                                    int64_t chains, const std::string &warning) {
    (*m)[prefix + "_b"] = MetaValue::Double(b);
    (*m)[prefix + "_mutations"] = MetaValue::Int(performed);
    (*m)[prefix + "_chains"] = MetaValue::Int(chains);
    if (!warning.empty()) (*m)[prefix + "_warning"] = warning;
}

inline double FinishMetropolisImage(Image *out, const std::string &prefix, double b, int64_t issued,
                                    int64_t performed, int64_t chains, const std::string &warning) {
    double rescale = 1;
    if (performed > 0 && performed != issued) {
        rescale = double(issued) / double(performed);
        const auto &names = out->channelNames();
        for (int ch = 0; ch < out->numChannels(); ++ch) {
            if (names[size_t(ch)] != "R" && names[size_t(ch)] != "G" && names[size_t(ch)] != "B") continue;
            for (int y = 0; y < out->height(); ++y)
                for (int x = 0; x < out->width(); ++x) out->at(x, y, ch) = float(out->at(x, y, ch) * rescale);
        }
    }
    WriteMetropolisMetadata(&out->metadata, prefix, b, performed, chains, warning);
    return rescale;
}

}  // namespace gradus
