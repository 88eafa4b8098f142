// Film channels of gradient-domain integrators and the reconstruction step.
//
// Per-pixel layers (averaged by the pixel's sample count): the primal image
// and the forward differences
//   dx(x,y) = I(x+1,y) - I(x,y),  dy(x,y) = I(x,y+1) - I(x,y).
// dx at p sums two independent halves: shifts from base paths at p towards
// p+(1,0) ("forward") and from base paths at p+(1,0) towards p ("backward").
// With variances (Film::varianceLayers(), gradus --variance) each half also
// keeps per-sample sums of squares, so the variance of the mean is
//   var = (E[v^2] - E[v]^2 / K) / N   per half, summed over the halves,
// with K the number of pixels a sample reaches (1 for the box filter).
// Pixel filter: "box" (default) adds a sample to its own pixel only. "film"
// splats it with the film's filter h normalised to unit integral: the offset
// sample at s+e reaches pixel q+e with the same weight h(q - s) as the base
// reaches q, so h(q - s) (f(y) - f(x)) estimates the filtered gradient at q.
// Light-tracing samples (t = 1 strategies of the bidirectional integrators)
// reach arbitrary pixels: splatLightTracing() records their primal and
// differences through the film's splat path (normalised by the samples per
// pixel like every splat) on layers of their own, whose variance is
// approximated by the second moment / N; images() adds both parts.
// Separated light (G-VCM's public code; issue 59): contributions of paths
// whose camera walk reaches the emitter after Dirac (ideal specular)
// scatterings only - emitters seen directly or through mirrors and glass -
// are counted in the primal and also in a layer of their own, and in no
// gradient. The reconstruction solves for primal - separated and adds the
// separated layer to its result (reconstruction.h): these pixels (a light's
// image through glass) are not spread or lost by the screened Poisson solve.
// primal_var stays the variance of the full primal (the weighted
// reconstruction then underweights the primal term where separated light is).
// WriteGradientOutput writes primal (the full primal, separated light
// included), separated (when kept), dx, dy, primal_var, dx_var, dy_var (with
// variances), reconstructed_l1, reconstructed_l2, reconstructed_hybrid (and
// reconstructed_weighted when chosen; every reconstruction includes the
// separated light) and sets the unprefixed R, G, B to the chosen one.
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
    // The part of `primal` separated from the reconstruction (header comment):
    // no gradient carries it.
    Spectrum separated{0};
    // Estimates of I(p + offset) - I(p), one per neighbour shift.
    Spectrum diff[kNumNeighbours] = {Spectrum(0), Spectrum(0), Spectrum(0), Spectrum(0)};
    bool active[kNumNeighbours] = {false, false, false, false};
};

// A light-tracing sample's primal and differences, at raster pixel `pixel`.
struct GradientSplat {
    Point2i pixel;
    GradientSample value;
};

class GradientFilm {
  public:
    // Adds the internal accumulation layers to the film (the squares only when
    // film.varianceLayers()); useFilmFilter selects the film's pixel filter
    // instead of the box; lightTracing adds the layers of splatLightTracing().
    // samples = false: splats only (no per-sample layers; record() is not allowed).
    void init(Film &film, bool useFilmFilter = false, bool lightTracing = false, bool samples = true);
    // Records one camera sample's primal value and neighbour differences.
    void record(SampleRecorder &rec, const GradientSample &s) const;
    // Adds separated light v estimated at film position pFilm inside this
    // sample's pixel (the "separatedsamples" walks, gradient_family.h) to the primal and the
    // separated layer, with the pixel and filter handling of record(). The
    // primal's square gets v^2 as if v were a sample's value on its own (an
    // approximation of primal_var: the walks are independent of the sample
    // but share its count).
    void recordSeparated(SampleRecorder &rec, Point2 pFilm, const Spectrum &v) const;
    // Records a light-tracing sample (values times `scale`) at its pixel
    // (differences: forward at the pixel, backward at the neighbour, as in
    // record()); pixels outside the film are dropped. Needs init(.., true).
    void splatLightTracing(SampleRecorder &rec, const GradientSplat &s, Float scale) const;
    // Extracts the gradient images (with variances when kept) from the film.
    // `samplesPerPixel` is the N of the variance of the mean.
    GradientImages images(const Film &film, double samplesPerPixel) const;

  private:
    enum { Primal, PrimalSq, DxF, DxFSq, DxB, DxBSq, DyF, DyFSq, DyB, DyBSq, NumLayers };
    int sepLayer_ = -1;  // separated light of the camera samples (-1: samples false)
    static bool IsSquare(int layer) { return layer % 2 == 1; }
    // Layers (value, square) of each neighbour's difference: +x is dx at p; -x
    // is dx at p-(1,0) with the sign flipped (I(p) - I(p-1)). Same for y.
    static constexpr int kDiffLayers_[kNumNeighbours][2] = {{DxF, DxFSq}, {DxB, DxBSq}, {DyF, DyFSq}, {DyB, DyBSq}};
    void addSplats(const Film &film, double samplesPerPixel, GradientImages *g) const;
    int layer_[NumLayers] = {};       // film layer, -1 when not kept
    int splatLayer_[NumLayers] = {};  // light-tracing splats (same meaning as layer_)
    bool variance_ = false;           // the squares are kept
    bool lightTracing_ = false;
    bool samples_ = true;
    Bounds2i bounds_;
    const Filter *filter_ = nullptr;  // null: box
    Float filterNorm_ = 1;            // 1 / integral of the filter
    Float footprint_ = 1;             // K: pixels reached by one sample
};

// Output image of a gradient integrator from its gradient images: layers
// primal, separated (when g has it), dx, dy, their variances (when g has them),
// reconstructed_l1, reconstructed_l2, reconstructed_hybrid (and
// reconstructed_weighted), the chosen one in the unprefixed R, G, B; keeps
// out->metadata and adds the reconstruction's. `report` gets the timings.
void WriteGradientOutput(const GradientImages &g, ReconstructionNorm norm, double alpha, Image *out,
                         std::string *report = nullptr);

}  // namespace gradus
