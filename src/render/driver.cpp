#include "render/driver.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <thread>
#include <vector>

namespace gradus {

namespace {
std::atomic<int> gInterrupts{0};
void OnSigint(int) {
    if (gInterrupts.fetch_add(1) >= 1) std::_Exit(130);
}
}  // namespace

void InstallInterruptHandler() { std::signal(SIGINT, OnSigint); }
bool InterruptRequested() { return gInterrupts.load() > 0; }
void ResetInterrupt() { gInterrupts = 0; }

void SampleRecorder::addRadiance(const Spectrum &L) {
    if (guard(L)) tile_.addSample(pFilm_, L);
}
void SampleRecorder::addLayer(int layer, const Spectrum &v, Point2i off) {
    if (guard(v)) tile_.addLayer(layer, Point2i{pixel_.x + off.x, pixel_.y + off.y}, v);
}
void SampleRecorder::splat(Point2 p, const Spectrum &v, int layer) {
    if (guard(v)) tile_.addSplat(p, v, layer);
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

RenderStats RenderImage(Film &film, const Sampler &prototype, const SampleEstimator &est,
                        const RenderOptions &opts) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
    std::unique_ptr<tbb::global_control> gc;
    if (opts.nthreads > 0)
        gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, opts.nthreads);

    Bounds2i sb = film.sampleBounds();
    const int ts = std::max(1, opts.tileSize);
    int ntx = (sb.width() + ts - 1) / ts, nty = (sb.height() + ts - 1) / ts;
    int ntiles = ntx * nty;
    int spp = opts.spp > 0 ? opts.spp : prototype.samplesPerPixel();
    bool unlimited = opts.timeLimit > 0 && opts.spp <= 0;  // time budget alone: run until the budget is spent
    int perPass = std::max(1, opts.sppPerPass);

    struct ThreadState {
        std::unique_ptr<Sampler> sampler;
        Arena arena;
    };
    tbb::enumerable_thread_specific<std::unique_ptr<ThreadState>> states;
    std::atomic<uint64_t> nonFinite{0};
    RenderStats stats;
    Progress progress("Rendering", unlimited ? 0 : spp, opts.quiet);
    double lastPassTime = 0;
    int done = 0;
    while (unlimited || done < spp) {
        if (InterruptRequested()) { stats.interrupted = true; break; }
        if (opts.timeLimit > 0 && done > 0 && elapsed() + lastPassTime > opts.timeLimit) {
            stats.timeLimited = true;
            break;
        }
        double passStart = elapsed();
        int first = done, count = unlimited ? perPass : std::min(perPass, spp - done);
        std::vector<std::unique_ptr<FilmTile>> tiles(ntiles);
        tbb::parallel_for(0, ntiles, [&](int t) {
            if (InterruptRequested()) return;
            std::unique_ptr<ThreadState> &stp = states.local();
            if (!stp) {
                stp = std::make_unique<ThreadState>();
                stp->sampler = prototype.clone();
            }
            ThreadState &st = *stp;
            Bounds2i tb;
            tb.pMin = {sb.pMin.x + (t % ntx) * ts, sb.pMin.y + (t / ntx) * ts};
            tb.pMax = {std::min(tb.pMin.x + ts, sb.pMax.x), std::min(tb.pMin.y + ts, sb.pMax.y)};
            auto tile = film.makeTile(tb);
            uint64_t bad = 0;
            for (int y = tb.pMin.y; y < tb.pMax.y; ++y)
                for (int x = tb.pMin.x; x < tb.pMax.x; ++x)
                    for (int s = first; s < first + count; ++s) {
                        Point2i pixel{x, y};
                        st.sampler->startPixelSample(pixel, s);
                        CameraSample cs;
                        Point2 u = st.sampler->get2D();
                        cs.pFilm = Point2(x + u.x, y + u.y);
                        cs.pLens = st.sampler->get2D();
                        SampleRecorder rec(*tile, pixel, cs.pFilm);
                        est.estimate(cs, *st.sampler, st.arena, rec);
                        tile->addCount(pixel, 1);
                        bad += rec.nonFinite;
                        st.arena.reset();
                    }
            nonFinite += bad;
            tiles[t] = std::move(tile);
        });
        for (auto &t : tiles)
            if (t) film.mergeTile(*t);
        done += count;
        lastPassTime = elapsed() - passStart;
        progress.update(done, elapsed(), opts.timeLimit);
    }
    progress.done(elapsed());
    film.setSplatSamples(done);
    stats.passes = done;
    stats.cameraSamples = int64_t(done) * sb.area();
    stats.seconds = elapsed();
    stats.nonFinite = nonFinite;
    return stats;
}

}  // namespace gradus
