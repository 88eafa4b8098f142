// Film channels of gradient-domain integrators and the reconstruction step.
//
// Per-pixel layers (averaged by the pixel's sample count): the primal image
// and the forward differences
//   dx(x,y) = I(x+1,y) - I(x,y),  dy(x,y) = I(x,y+1) - I(x,y).
// dx at p sums two independent halves: shifts from base paths at p towards
// p+(1,0) ("forward") and from base paths at p+(1,0) towards p ("backward").
// Each half keeps per-sample sums of squares, so the variance of the mean is
//   var = (E[v^2] - E[v]^2 / K) / N   per half, summed over the halves,
// with K the number of pixels a sample reaches (1 for the box filter).
// Pixel filter: "box" (default) adds a sample to its own pixel only. "film"
// splats it with the film's filter h normalised to unit integral: the offset
// sample at s+e reaches pixel q+e with the same weight h(q - s) as the base
// reaches q, so h(q - s) (f(y) - f(x)) estimates the filtered gradient at q.
// finish() writes primal, dx, dy, primal_var, dx_var, dy_var,
// reconstructed_l1, reconstructed_l2 (and reconstructed_weighted when chosen)
// and sets the unprefixed R, G, B to the chosen reconstruction.
#pragma once
#include <string>

#include "core/spectrum.h"
#include "image/image.h"
#include "reconstruction/reconstruction.h"
#include "render/render_loop.h"
#include "render/film.h"

namespace gradus {

// The four neighbour shifts of a base path: +x, -x, +y, -y.
constexpr int kNumNeighbours = 4;
extern const Point2i kNeighbourOffsets[kNumNeighbours];

struct GradientSample {
    Spectrum primal{0};
    // Estimates of I(p + offset) - I(p), one per neighbour shift.
    Spectrum diff[kNumNeighbours] = {Spectrum(0), Spectrum(0), Spectrum(0), Spectrum(0)};
    bool active[kNumNeighbours] = {false, false, false, false};
};

class GradientFilm {
  public:
    // Adds the internal accumulation layers to the film; useFilmFilter selects
    // the film's pixel filter instead of the box.
    void init(Film &film, bool useFilmFilter = false);
    // Records one camera sample's primal value and neighbour differences.
    void record(SampleRecorder &rec, const GradientSample &s) const;
    // Builds the output image from the film (replaces *out, keeping its metadata).
    // `samplesPerPixel` is the N of the variance of the mean.
    void finish(const Film &film, double samplesPerPixel, ReconstructionNorm norm, double alpha, Image *out,
                std::string *report = nullptr) const;
    // Extracts the gradient images (with variances) from the film.
    GradientImages images(const Film &film, double samplesPerPixel) const;

  private:
    enum { Primal, PrimalSq, DxF, DxFSq, DxB, DxBSq, DyF, DyFSq, DyB, DyBSq, NumLayers };
    void splat(SampleRecorder &rec, int layer, int layerSq, const Spectrum &v, Point2i offset) const;
    int layer_[NumLayers] = {};
    const Filter *filter_ = nullptr;  // null: box
    Float filterNorm_ = 1;            // 1 / integral of the filter
    Float footprint_ = 1;             // K: pixels reached by one sample
};

// Output image of a gradient integrator from its gradient images: layers
// primal, dx, dy, their variances, reconstructed_l1, reconstructed_l2 (and
// reconstructed_weighted), the chosen one in the unprefixed R, G, B; keeps
// out->metadata and adds the reconstruction's. `report` gets the timings.
void WriteGradientOutput(const GradientImages &g, ReconstructionNorm norm, double alpha, Image *out,
                         std::string *report = nullptr);

}  // namespace gradus
