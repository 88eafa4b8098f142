// The gradient-domain family (gpt, gbdpt; later gvcm, gmlt): its runtime
// state - the GradientFilm, the film's pixel bounds, the reconstruction
// report - and the common end of a render. A mix-in beside the integrator's
// render-loop base (PixelSampleIntegrator, PassIntegrator):
//   preprocess:  initGradients(film, ...)
//   finish:      finishGradients(film, stats, norm, alpha, out): the gradient
//                images with N = stats.spp, then WriteGradientOutput (primal,
//                dx, dy, variances, reconstructions)
//   statistics:  withReconstructionReport(the integrator's own lines)
// The settings (reconstruction norm, alpha, pixel filter, ...) stay with each
// integrator's parameters and are passed in.
#pragma once
#include <string>

#include "integrators/gradient/gradient_film.h"

namespace gradus {

struct BidirContext;
struct CameraSample;
class Arena;
class Sampler;

class GradientFamily {
  protected:
    // Adds the gradient layers to the film (lightTracing: also the layers of
    // light-tracing splats; samples false: those only) and records its bounds.
    void initGradients(Film &film, bool useFilmFilter, bool lightTracing = false, bool samples = true);
    // Both pixel p and its neighbour k lie on the film (a gradient between them is kept).
    bool pairInside(Point2i p, int k) const {
        return filmBounds_.inside(p) &&
               filmBounds_.inside({p.x + kNeighbourOffsets[k].x, p.y + kNeighbourOffsets[k].y});
    }
    // The integrator's finish(): replaces *out by the gradient output (keeping its metadata).
    // `scale` multiplies the gradient images (variances by its square) before
    // the reconstruction (an interrupted Metropolis pass); `add` (same size)
    // is then added, unscaled (gmlt's direct pass).
    void finishGradients(const Film &film, const RenderStats &stats, ReconstructionNorm norm, Float alpha,
                         Image *out, double scale = 1, const GradientImages *add = nullptr);

    // Seconds finishGradients will take at this film's size: reconstructions
    // of 64x64 and 128x128 problems, timed on first use (only a render with a
    // --time budget asks), give a fixed cost and a cost per pixel (x 1.5 for
    // safety); plus the page faults of the memory it allocates (timed once).
    // The render loop reserves it from the budget.
    double reconstructionEstimate(ReconstructionNorm norm, Float alpha) const;
    // "separatedsamples K" (gpt, gbdpt, gvcm; gradient_family.cpp): the
    // camera sample's separated light becomes one of K + 1 estimates (its
    // primal keeps the rest plus that share) ...
    static void shareSeparated(GradientSample *s, int K);
    // ... and the K Dirac-only walks (DiracCameraWalk) of camera sample cs at
    // rec's pixel add theirs, each times 1 / (K + 1). Scenes without media.
    void separatedWalks(const BidirContext &ctx, int K, int maxDepth, const CameraSample &cs, const Sampler &sampler,
                        Arena &arena, SampleRecorder &rec) const;
    // The statistics tail: the integrator's lines followed by the reconstruction's.
    std::string withReconstructionReport(const std::string &lines) const { return lines + reconReport_; }

    GradientFilm gfilm_;
    Bounds2i filmBounds_;

  private:
    std::string reconReport_;
    mutable double reconEstimate_ = -1;  // not yet timed
};

}  // namespace gradus
