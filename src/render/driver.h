// The shared render driver: tiles, threads (TBB), per-(pixel, sample,
// dimension) seeding, wall-clock budget, progress, NaN/Inf guard, Ctrl-C.
// Integrators only estimate samples (SampleEstimator).
#pragma once
#include <cstdint>
#include <string>

#include "cameras/camera.h"
#include "core/arena.h"
#include "render/film.h"
#include "samplers/sampler.h"

namespace gradus {

struct RenderOptions {
    int spp = 0;              // samples per pixel; 0 = the sampler's
    double timeLimit = 0;     // seconds of wall clock; 0 = none (with a limit, spp is an upper bound only if set)
    int nthreads = 0;         // 0 = all cores
    uint64_t seed = 0;
    bool quiet = false;
    int tileSize = 16;
    int sppPerPass = 1;
};

struct RenderStats {
    int64_t cameraSamples = 0;
    int passes = 0;           // = samples per pixel completed
    double seconds = 0;
    uint64_t nonFinite = 0;   // NaN/Inf contributions discarded
    bool interrupted = false;
    bool timeLimited = false;
};

// Collects one camera sample's contributions; guards against NaN/Inf.
class SampleRecorder {
  public:
    SampleRecorder(FilmTile &tile, Point2i pixel, Point2 pFilm) : tile_(tile), pixel_(pixel), pFilm_(pFilm) {}
    // Radiance of this camera sample (main image, through the pixel filter).
    void addRadiance(const Spectrum &L);
    // Value added to a per-pixel layer at this pixel + offset.
    void addLayer(int layer, const Spectrum &v, Point2i offset = {0, 0});
    // Light-tracing contribution at a raster position (normalised by total spp),
    // to the main image or (layer >= 0) to a film layer.
    void splat(Point2 pFilm, const Spectrum &v, int layer = -1);
    Point2i pixel() const { return pixel_; }
    Point2 pFilm() const { return pFilm_; }
    uint64_t nonFinite = 0;

  private:
    bool guard(const Spectrum &v) {
        if (v.isFinite()) return true;
        ++nonFinite;
        return false;
    }
    FilmTile &tile_;
    Point2i pixel_;
    Point2 pFilm_;
};

class SampleEstimator {
  public:
    virtual ~SampleEstimator() = default;
    // Estimates one camera sample. The sampler is positioned on (pixel, index)
    // after the two film and lens dimensions (CameraSample already drawn).
    virtual void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const = 0;
};

RenderStats RenderImage(Film &film, const Sampler &prototype, const SampleEstimator &estimator,
                        const RenderOptions &opts);

// Ctrl-C: the first SIGINT asks the driver to stop after the current tiles
// (the image rendered so far is written); a second one exits at once.
void InstallInterruptHandler();
bool InterruptRequested();
void ResetInterrupt();

// Progress reporter on stderr ("[=====    ] 53% 12.1s ETA 10.7s").
class Progress {
  public:
    Progress(std::string title, int64_t total, bool quiet);
    void update(int64_t done, double elapsed, double timeLimit = 0);
    void done(double elapsed);

  private:
    std::string title_;
    int64_t total_;
    bool quiet_;
    double lastPrint_ = -1;
};

}  // namespace gradus
