#include "render/render_loop.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "render/integrator.h"

namespace gradus {

namespace {
std::atomic<int> gInterrupts{0};
void OnSignal(int) {
    if (gInterrupts.fetch_add(1) >= 1) std::_Exit(130);
}

// --debugpixel state: set by RunRender, read by the recorders and DebugTrace.
std::atomic<bool> gDebugMode{false};
Point2i gDebugPixel;
thread_local bool tDebugTracing = false;

bool IsDebugPixel(Point2i p) { return gDebugMode.load(std::memory_order_relaxed) && p == gDebugPixel; }

void PrintContribution(const char *what, Point2i p, const Spectrum &v, int layer) {
    std::printf("  %s pixel (%d, %d)%s%s: %.9g %.9g %.9g\n", what, p.x, p.y, layer >= 0 ? " layer " : "",
                layer >= 0 ? std::to_string(layer).c_str() : "", v.r, v.g, v.b);
}

}  // namespace

void InstallInterruptHandler() {
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
}
bool InterruptRequested() { return gInterrupts.load() > 0; }
void ResetInterrupt() { gInterrupts = 0; }
void RequestInterrupt() {
    int none = 0;
    gInterrupts.compare_exchange_strong(none, 1);  // never counts as a second signal
}

bool DebugTracing() { return tDebugTracing; }
void DebugTrace(const char *fmt, ...) {
    if (!tDebugTracing) return;
    va_list ap;
    va_start(ap, fmt);
    std::printf("    ");
    std::vprintf(fmt, ap);
    std::printf("\n");
    va_end(ap);
}

void SampleRecorder::addRadiance(const Spectrum &L) {
    if (!guard(L)) return;
    if (IsDebugPixel(pixel_)) PrintContribution("radiance", pixel_, L, -1);
    tile_.addSample(pFilm_, L);
}
void SampleRecorder::addLayer(int layer, const Spectrum &v, Point2i off) {
    if (!guard(v)) return;
    Point2i p{pixel_.x + off.x, pixel_.y + off.y};
    if (IsDebugPixel(p)) PrintContribution("layer value", p, v, layer);
    tile_.addLayer(layer, p, v);
}
void SampleRecorder::splat(Point2 p, const Spectrum &v, int layer) {
    if (!guard(v)) return;
    if (gDebugMode.load(std::memory_order_relaxed)) {
        Point2i q{int(std::floor(p.x)), int(std::floor(p.y))};
        if (IsDebugPixel(q)) PrintContribution("splat", q, v, layer);
    }
    tile_.addSplat(p, v, layer);
}

Progress::Progress(std::string title, int64_t total, bool quiet)
    : title_(std::move(title)), total_(total), quiet_(quiet) {}

void Progress::update(int64_t done, double elapsed, double timeLimit) {
    if (quiet_ || elapsed - lastPrint_ < 0.5) return;
    lastPrint_ = elapsed;
    double frac = total_ > 0 ? double(done) / total_ : 0;
    if (timeLimit > 0) frac = std::max(frac, std::min(1.0, elapsed / timeLimit));
    int bars = int(frac * 30);
    std::string bar(bars, '=');
    bar.resize(30, ' ');
    double eta = frac > 0 ? elapsed / frac - elapsed : 0;
    std::fprintf(stderr, "\r%s [%s] %3d%% %.1fs ETA %.1fs ", title_.c_str(), bar.c_str(), int(frac * 100), elapsed,
                 eta);
    std::fflush(stderr);
}

void Progress::done(double elapsed) {
    if (quiet_) return;
    std::fprintf(stderr, "\r%s [%s] 100%% %.1fs            \n", title_.c_str(), std::string(30, '=').c_str(),
                 elapsed);
}

TileGrid::TileGrid(const Bounds2i &b, int ts) : bounds(b), size(std::max(1, ts)) {
    nx = (b.width() + size - 1) / size;
    ny = (b.height() + size - 1) / size;
}

Bounds2i TileGrid::tile(int i) const {
    Bounds2i t;
    t.pMin = {bounds.pMin.x + (i % nx) * size, bounds.pMin.y + (i / nx) * size};
    t.pMax = {std::min(t.pMin.x + size, bounds.pMax.x), std::min(t.pMin.y + size, bounds.pMax.y)};
    return t;
}

struct PassContext::Shared {
    const Sampler *prototype = nullptr;
    tbb::enumerable_thread_specific<Worker> workers;
    std::atomic<uint64_t> nonFinite{0};
    LaneTally lanes;
};

Worker &PassContext::worker() const {
    Worker &w = shared_.workers.local();
    if (!w.sampler) w.sampler = shared_.prototype->clone();
    return w;
}

bool PassContext::interrupted() const { return pass_ > 0 && !opts_.wholePasses && InterruptRequested(); }

void PassContext::addNonFinite(uint64_t n) { shared_.nonFinite += n; }

namespace {
using Clock = std::chrono::steady_clock;
int64_t Nanoseconds(Clock::duration d) { return std::chrono::duration_cast<std::chrono::nanoseconds>(d).count(); }
// Set while this thread runs a work unit of a tallied parallel section: a
// section started inside one (nested) is part of that unit, not tallied again.
thread_local bool tInWorkUnit = false;

// One parallel section's share of the LaneTally: its wall time times its
// lanes, and the work units' durations (added by the lanes as they finish).
class SectionTally {
  public:
    SectionTally(LaneTally *t, int64_t lanes) : tally_(tInWorkUnit ? nullptr : t), lanes_(lanes), t0_(Clock::now()) {}
    ~SectionTally() {
        if (!tally_) return;
        const int64_t wall = Nanoseconds(Clock::now() - t0_);
        tally_->wallNs += wall;
        tally_->laneNs += wall * lanes_;
    }
    // Runs f() as one work unit (its duration counted as busy). A unit this
    // thread runs while in another (a task taken while a unit waits on a
    // nested loop) is part of that one.
    template <typename F>
    void unit(F &&f) {
        if (!tally_ || tInWorkUnit) return void(f());
        const auto t0 = Clock::now();
        tInWorkUnit = true;
        struct Reset {
            ~Reset() { tInWorkUnit = false; }
        } reset;
        f();
        tally_->busyNs += Nanoseconds(Clock::now() - t0);
    }

  private:
    LaneTally *tally_;
    const int64_t lanes_;
    const Clock::time_point t0_;
};

// Runs work(i) for i in [0, n) on the loop's threads, started in increasing
// order, and merges each result into the film in index order as soon as it and
// all before it are done (so the film does not depend on the thread count).
// At most `window` results are started and not yet merged: a thread that would
// start one more waits for the earliest to finish, so memory is bounded by the
// window, not by n. onMerged(i), when given, runs right after result i is
// merged (in index order, one at a time).
class OrderedMerge {
  public:
    using Work = std::function<std::unique_ptr<FilmTile>(int64_t)>;  // null: nothing to merge
    OrderedMerge(Film &film, int64_t n, int64_t window, LaneTally *tally,
                 const std::function<void(int64_t)> &onMerged = nullptr)
        : film_(film), n_(n), window_(std::max<int64_t>(1, window)), onMerged_(onMerged), tally_(tally),
          slot_(size_t(window_)), ready_(size_t(window_)) {}

    void run(const Work &work) {
        const int threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
        const int lanes = int(std::max<int64_t>(1, std::min<int64_t>(n_, std::max(1, threads))));
        SectionTally section(tally_, lanes);
        tbb::parallel_for(0, lanes, [&](int) { lane(work, section); }, tbb::simple_partitioner());
        GRADUS_CHECK(merged_ == n_);
    }

  private:
    // Work units: rendering a result and merging results (mergeReady).
    void lane(const Work &work, SectionTally &section) {
        for (;;) {
            int64_t i;
            {
                std::unique_lock<std::mutex> lk(m_);
                canStart_.wait(lk, [&] { return claimed_ >= n_ || claimed_ < merged_ + window_; });
                if (claimed_ >= n_) return;
                i = claimed_++;
            }
            std::unique_ptr<FilmTile> t;
            // Isolated: a nested parallel wait inside work must not pick up another lane (which could wait on i).
            section.unit([&] { tbb::this_task_arena::isolate([&] { t = work(i); }); });
            {
                std::lock_guard<std::mutex> lk(m_);
                slot_[size_t(i % window_)] = std::move(t);
                ready_[size_t(i % window_)] = 1;
            }
            section.unit([&] { mergeReady(); });
        }
    }
    // Merges the ready results from merged_ on; one thread merges at a time (the
    // others go on rendering), and re-checks after each merge, so none is left.
    void mergeReady() {
        for (;;) {
            std::unique_ptr<FilmTile> t;
            int64_t i;
            {
                std::lock_guard<std::mutex> lk(m_);
                i = merged_;
                const size_t k = size_t(i % window_);
                if (merging_ || i >= n_ || !ready_[k]) return;
                merging_ = true;
                t = std::move(slot_[k]);
                ready_[k] = 0;
            }
            if (t) film_.mergeTile(*t);
            t.reset();
            if (onMerged_) onMerged_(i);
            {
                std::lock_guard<std::mutex> lk(m_);
                ++merged_;
                merging_ = false;
            }
            canStart_.notify_all();
        }
    }

    Film &film_;
    const int64_t n_, window_;
    const std::function<void(int64_t)> onMerged_;
    LaneTally *tally_;
    std::mutex m_;
    std::condition_variable canStart_;
    int64_t claimed_ = 0, merged_ = 0;
    bool merging_ = false;
    std::vector<std::unique_ptr<FilmTile>> slot_;  // result i at i % window
    std::vector<char> ready_;
};
}  // namespace

int64_t PassContext::mergeWindow() const {
    const int threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    return std::max<int64_t>(kMergeWindow, 8 * int64_t(threads));
}

void PassContext::forEachTile(const TileFn &fn) {
    OrderedMerge(film_, tiles_.count(), mergeWindow(), &shared_.lanes).run([&](int64_t t) -> std::unique_ptr<FilmTile> {
        if (interrupted()) return nullptr;
        Bounds2i tb = tiles_.tile(int(t));
        auto tile = film_.makeTile(tb);
        fn(int(t), tb, *tile, worker());
        return tile;
    });
}

void PassContext::forEachPixelSample(const SampleEstimator &est) {
    const int first = firstSample_, count = sampleCount_;
    auto run = [&](Point2i pixel, int s, FilmTile &tile, Worker &w) {
        Sampler &sampler = *w.sampler;
        sampler.startPixelSample(pixel, s);
        CameraSample cs;
        Point2 u = sampler.get2D();
        cs.pFilm = Point2(pixel.x + u.x, pixel.y + u.y);
        cs.pLens = sampler.get2D();
        SampleRecorder rec(tile, pixel, cs.pFilm);
        est.estimate(cs, sampler, w.arena, rec);
        tile.addCount(pixel, 1);
        w.arena.reset();
        return rec.nonFinite;
    };
    if (opts_.debug) {  // the debug pixel's samples only, on this thread
        Point2i p = opts_.debugPixel;
        Bounds2i one{p, {p.x + 1, p.y + 1}};
        auto tile = film_.makeTile(one);
        Worker &w = worker();
        for (int s = first; s < first + count; ++s) {
            if (opts_.debugSample >= 0 && s != opts_.debugSample) continue;
            std::printf("sample %d of pixel (%d, %d):\n", s, p.x, p.y);
            tDebugTracing = true;
            addNonFinite(run(p, s, *tile, w));
            tDebugTracing = false;
        }
        film_.mergeTile(*tile);
        return;
    }
    forEachTile([&](int, const Bounds2i &tb, FilmTile &tile, Worker &w) {
        uint64_t bad = 0;
        for (int y = tb.pMin.y; y < tb.pMax.y; ++y)
            for (int x = tb.pMin.x; x < tb.pMax.x; ++x)
                for (int s = first; s < first + count; ++s) bad += run({x, y}, s, tile, w);
        addNonFinite(bad);
    });
}

void PassContext::forEachItem(int64_t n, uint64_t tag, const ItemFn &fn, const ChunkFn &chunkMerged) {
    const int64_t chunks = std::max<int64_t>(0, (n + PassContext::kItemChunk - 1) / PassContext::kItemChunk);
    const uint64_t key = seed() ^ tag;
    OrderedMerge(film_, chunks, mergeWindow(), &shared_.lanes, chunkMerged).run([&](int64_t c) -> std::unique_ptr<FilmTile> {
        if (interrupted()) return nullptr;
        auto tile = film_.makeSplatTile();
        Worker &w = worker();
        uint64_t bad = 0;
        for (int64_t i = c * PassContext::kItemChunk; i < std::min(n, (c + 1) * PassContext::kItemChunk); ++i) {
            RNG rng(Hash(key, uint64_t(pass_), uint64_t(i)));
            SampleRecorder rec(*tile, Point2i{-1, -1}, Point2(-1, -1));
            fn(i, rng, rec, w);
            bad += rec.nonFinite;
            w.arena.reset();
        }
        addNonFinite(bad);
        return tile;
    });
}

void PassContext::parallelFor(int64_t n, int64_t grain, const RangeFn &fn) {
    grain = std::max<int64_t>(1, grain);
    const int64_t ranges = (n + grain - 1) / grain;
    const int threads = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    SectionTally section(&shared_.lanes, std::max<int64_t>(1, std::min<int64_t>(ranges, std::max(1, threads))));
    tbb::parallel_for(int64_t(0), ranges, [&](int64_t r) {
        section.unit([&] { fn(r * grain, std::min(n, (r + 1) * grain), worker()); });
    });
}

RenderStats RunRender(Integrator &integ, const Scene &scene, Film &film, const Sampler &sampler,
                      const RenderOptions &opts) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
    const int threads = opts.debug ? 1 : opts.nthreads;
    std::unique_ptr<tbb::global_control> gc;
    if (threads > 0)
        gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    gDebugMode = opts.debug;
    gDebugPixel = opts.debugPixel;

    TileGrid grid(film.sampleBounds(), opts.tileSize);
    PassContext::Shared shared;
    shared.prototype = &sampler;
    PassContext ctx(scene, film, sampler, opts, grid, shared);

    const int spp = opts.spp > 0 ? opts.spp : sampler.samplesPerPixel();
    const bool unlimited = opts.timeLimit > 0 && opts.spp <= 0;  // time budget alone: run until it is spent
    const int perPass = std::max(1, integ.samplesPerPass(opts));
    RenderStats stats;
    stats.seed = sampler.seed();
    Progress progress("Rendering", unlimited ? 0 : spp, opts.quiet || opts.debug);
    double lastPassTime = 0;
    int done = opts.firstSpp >= 0 ? opts.firstSpp : opts.firstPass * perPass;
    if (!unlimited) done = std::min(done, spp);
    stats.passes = stats.firstPass = opts.firstPass;
    stats.firstSpp = done;
    film.setSplatSamples(done);
    const int startDone = done;
    while ((unlimited || done < spp) && (opts.lastPass < 0 || stats.passes < opts.lastPass)) {
        if (InterruptRequested()) {
            stats.interrupted = true;
            break;
        }
        // Stop before a pass that would end past the budget (estimated by the last pass).
        if (opts.timeLimit > 0 && done > startDone && elapsed() + lastPassTime > opts.timeLimit) {
            stats.timeLimited = true;
            break;
        }
        double passStart = elapsed();
        ctx.pass_ = stats.passes;
        ctx.firstSample_ = done;
        ctx.sampleCount_ = unlimited ? perPass : std::min(perPass, spp - done);
        integ.beginPass(ctx);
        const double afterBegin = elapsed();
        integ.runPass(ctx);
        integ.endPass(ctx);
        // A pass cut short by an interrupt keeps what it merged and counts.
        done += ctx.sampleCount_;
        ++stats.passes;
        film.setSplatSamples(done);
        // The first beginPass is one-off setup (mlt's bootstrap): not part of the estimate of the next pass.
        lastPassTime = elapsed() - (stats.passes == 1 ? afterBegin : passStart);
        progress.update(done, elapsed(), opts.timeLimit);
        if (opts.afterPass) {
            stats.spp = done;
            stats.nonFinite = shared.nonFinite;
            stats.complete = !unlimited && done >= spp;
            opts.afterPass(stats);
        }
    }
    progress.done(elapsed());
    gDebugMode = false;
    stats.spp = done;
    stats.complete = !unlimited && done >= spp;
    stats.cameraSamples = int64_t(done) * grid.bounds.area();
    stats.seconds = elapsed();
    stats.nonFinite = shared.nonFinite;
    stats.parallelSeconds = 1e-9 * double(shared.lanes.wallNs.load());
    stats.laneSeconds = 1e-9 * double(shared.lanes.laneNs.load());
    stats.busySeconds = 1e-9 * double(shared.lanes.busyNs.load());
    return stats;
}

}  // namespace gradus
