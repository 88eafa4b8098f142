// The one render loop: it owns threads (TBB), the wall-clock budget,
// Ctrl-C/SIGTERM, progress/ETA, the NaN/Inf guard, statistics and the
// normalisation of light-tracing splats. Integrators run passes
// (Integrator::beginPass / runPass / endPass) and do their parallel work only
// through the PassContext, with two kinds of work:
//   - per-pixel-sample work (forEachPixelSample): the sampler is addressed by
//     (pixel, sample index, dimension) and the seed;
//   - per-item work inside a pass (forEachItem: n items such as light
//     subpaths or chains, an RNG keyed by (seed, pass, item)), per-tile work
//     (forEachTile) and plain parallel loops (parallelFor).
// Film output goes through FilmTiles merged in tile / item-chunk order as they
// finish (at most a window of them waits for an earlier, slower one), so images
// do not depend on the thread count and memory does not grow with the image.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cameras/camera.h"
#include "core/arena.h"
#include "render/film.h"
#include "samplers/rng.h"
#include "samplers/sampler.h"

namespace gradus {

class Integrator;
class Scene;
struct RenderStats;

struct RenderOptions {
    int spp = 0;              // samples per pixel; 0 = the sampler's
    double timeLimit = 0;     // seconds of wall clock; 0 = none (with a limit, spp is an upper bound only if set)
    int nthreads = 0;         // 0 = all cores
    bool quiet = false;
    int tileSize = 16;
    int sppPerPass = 1;       // pixel samples per pass of a pixel-sample integrator
    // --debugpixel: run only the samples of this pixel (all, or sample debugSample),
    // single-threaded with the random numbers of the full render, printing
    // vertices and contributions (pass-based integrators run their passes whole
    // and print what reaches the pixel).
    bool debug = false;
    Point2i debugPixel;
    int debugSample = -1;
    // Checkpoints and exact splitting (RenderJobImage; job/checkpoint.h).
    std::string checkpointFile;       // --checkpoint: written every checkpointInterval s, at the end, on interrupt
    double checkpointInterval = 300;  // --checkpoint-interval
    std::string resumeFile;           // --resume
    int passBegin = 0, passEnd = -1;  // --passes A:B: render passes [A, B) only (-1: to the end)
    // --display-server HOST:PORT: stream the film to a tev viewer while it
    // renders (render/display.h; RenderJobImage runs it); --display-layers:
    // the film's layers as well.
    std::string displayServer;
    bool displayLayers = false;
    // Loop level (set by RenderJobImage): start at pass firstPass with
    // firstSpp samples per pixel done (-1: firstPass x samples per pass);
    // stop before pass lastPass (-1: none); run every pass whole even when
    // interrupted (checkpoints then hold whole passes only); afterPass is
    // called after each pass with the statistics so far.
    int firstPass = 0, firstSpp = -1, lastPass = -1;
    bool wholePasses = false;
    std::function<void(const RenderStats &)> afterPass;
};

struct RenderStats {
    int64_t cameraSamples = 0;
    int passes = 0;           // passes completed
    int spp = 0;              // samples per pixel completed
    uint64_t seed = 0;        // the sampler's seed (the render's only seed)
    double seconds = 0;
    uint64_t nonFinite = 0;   // NaN/Inf contributions discarded
    bool interrupted = false;
    bool timeLimited = false;
    int firstPass = 0, firstSpp = 0;  // where this session started (resume, --passes)
    bool complete = false;            // the render's last pass is done (spp reached)
    // Where the threads went in the passes' parallel sections (forEachTile,
    // forEachItem, parallelFor; a section inside another's work unit is part
    // of that unit): their wall seconds, the same times their lanes (threads
    // that could work), and the lanes' seconds inside work units (rendering
    // and merging; a descheduled thread still counts). busy / lane seconds is
    // the scheduling's occupancy (1: no lane waited), independent of the
    // machine's load; seconds - parallelSeconds ran outside parallel sections.
    double parallelSeconds = 0, laneSeconds = 0, busySeconds = 0;
};

// Sums of RenderStats' parallel-section figures, in nanoseconds.
struct LaneTally {
    std::atomic<int64_t> wallNs{0}, laneNs{0}, busyNs{0};
};

// Collects one camera sample's (or one work item's) contributions; guards
// against NaN/Inf. In --debugpixel mode contributions to the debug pixel are printed.
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

// Per-thread scratch the loop hands to work functions.
struct Worker {
    Arena arena;
    std::unique_ptr<Sampler> sampler;  // clone of the render's sampler
};

// Row-major tiles of a pixel rectangle (the numbering every pass uses).
struct TileGrid {
    TileGrid() = default;
    TileGrid(const Bounds2i &b, int tileSize);
    int count() const { return nx * ny; }
    Bounds2i tile(int i) const;
    Bounds2i bounds;
    int size = 16, nx = 0, ny = 0;
};

// Everything a pass may use; created by the loop for each pass.
class PassContext {
  public:
    const Scene &scene() const { return scene_; }
    Film &film() const { return film_; }
    const Sampler &sampler() const { return sampler_; }
    const RenderOptions &options() const { return opts_; }
    uint64_t seed() const { return sampler_.seed(); }
    int pass() const { return pass_; }                // index of this pass
    int firstSample() const { return firstSample_; }  // pixel samples [first, first + count) of this pass
    int sampleCount() const { return sampleCount_; }
    const TileGrid &tiles() const { return tiles_; }  // tiles of the film's sample bounds
    // Ctrl-C / SIGTERM: return early. Never in the first pass, which always runs
    // whole (so an interrupted render has an image even when the interrupt came
    // during a long first beginPass, such as mlt's bootstrap).
    bool interrupted() const;
    bool debugging() const { return opts_.debug; }

    // Per-pixel-sample work: every pixel of the sample bounds, samples
    // [firstSample, firstSample + sampleCount) (only the debug pixel when debugging).
    void forEachPixelSample(const SampleEstimator &est);
    // Per-tile work over tiles(): fn(tile index, tile pixels, film tile, worker);
    // tiles start in index order and are merged in index order as they finish:
    // at most mergeWindow() of them are started and not yet merged (a thread
    // waits rather than start one more).
    static constexpr int64_t kMergeWindow = 64;
    int64_t mergeWindow() const;  // kMergeWindow, or 8 per thread when larger
    using TileFn = std::function<void(int, const Bounds2i &, FilmTile &, Worker &)>;
    void forEachTile(const TileFn &fn);
    // Per-item work: fn(item, rng, recorder, worker) for items [0, n). The RNG
    // is keyed by (seed, tag, pass, item); the recorder's splats go to the
    // film, merged in item order (chunks of kItemChunk items; the items of one
    // chunk run in order on one thread, so per-chunk output needs no locking;
    // chunks are merged as they finish, with the tiles' window). chunkMerged(c),
    // when given, runs right after chunk c's splats are merged: in chunk order,
    // one at a time (e.g. to gather per-chunk output in item order).
    // When interrupted(), forEachTile and forEachItem skip the tiles / chunks
    // not started yet (chunkMerged still runs for them).
    static constexpr int64_t kItemChunk = 256;
    using ItemFn = std::function<void(int64_t, RNG &, SampleRecorder &, Worker &)>;
    using ChunkFn = std::function<void(int64_t)>;
    void forEachItem(int64_t n, uint64_t tag, const ItemFn &fn, const ChunkFn &chunkMerged = nullptr);
    // Plain parallel loop without film output: fn(begin, end, worker) over
    // fixed-size ranges of [0, n) (grain: items per range). Always runs to the
    // end (callers check interrupted() between stages).
    using RangeFn = std::function<void(int64_t, int64_t, Worker &)>;
    void parallelFor(int64_t n, int64_t grain, const RangeFn &fn);
    void addNonFinite(uint64_t n);

  private:
    friend RenderStats RunRender(Integrator &, const Scene &, Film &, const Sampler &, const RenderOptions &);
    struct Shared;
    PassContext(const Scene &scene, Film &film, const Sampler &sampler, const RenderOptions &opts,
                const TileGrid &tiles, Shared &shared)
        : scene_(scene), film_(film), sampler_(sampler), opts_(opts), tiles_(tiles), shared_(shared) {}
    Worker &worker() const;
    const Scene &scene_;
    Film &film_;
    const Sampler &sampler_;
    const RenderOptions &opts_;
    const TileGrid &tiles_;
    Shared &shared_;
    int pass_ = 0, firstSample_ = 0, sampleCount_ = 0;
};

// Runs the integrator's passes (after Integrator::preprocess) until the
// samples per pixel are done, the budget is spent or an interrupt arrives.
RenderStats RunRender(Integrator &integrator, const Scene &scene, Film &film, const Sampler &sampler,
                      const RenderOptions &opts);

// Ctrl-C / SIGTERM: the first signal asks the loop to stop after the current
// work (the image rendered so far is written); a second one exits at once.
void InstallInterruptHandler();
bool InterruptRequested();
void ResetInterrupt();
// Asks the loop to stop as the first signal does (for hosts with their own
// signal handling, e.g. the Python module polling Python's Ctrl-C).
void RequestInterrupt();

// --debugpixel output: true on the thread that runs the debug pixel's work.
bool DebugTracing();
// Prints a line of the debug trace (printf format) when DebugTracing().
void DebugTrace(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

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
