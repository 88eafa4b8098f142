// The render loop (render/render_loop.h) with test integrators: pass
// bookkeeping, per-item random numbers keyed by (seed, tag, pass, item),
// thread-count independent merging of item splats and tiles, budget and
// interrupt handling, statistics handed to finish().
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <thread>

#include "common/render_test_util.h"

using namespace gradus;

namespace {

const char *kScene =
    "LookAt 0 0 -3  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" [40]\n"
    "Film \"image\" \"integer xresolution\" [20] \"integer yresolution\" [12]\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n"
    "Shape \"sphere\" \"float radius\" [1]\n"
    "WorldEnd\n";

RenderJob Job(uint64_t seed = 3) { return test::MakeTestJob(ParseString(kScene, "loop.pbrt", "."), 1, seed, "path"); }

constexpr uint64_t kTag = 0x1234;

// Splats item-keyed random values at item-keyed raster positions and records
// what the loop told it.
class ItemIntegrator : public Integrator {
  public:
    std::string name() const override { return "items"; }
    int samplesPerPass(const RenderOptions &) const override { return perPass; }
    void beginPass(PassContext &ctx) override {
        firsts.push_back(ctx.firstSample());
        counts.push_back(ctx.sampleCount());
        if (interruptInBeginPass >= 0 && ctx.pass() == interruptInBeginPass) std::raise(SIGINT);
        if (setupMs > 0 && ctx.pass() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(setupMs));
    }
    void runPass(PassContext &ctx) override {
        const Point2i res = ctx.film().fullResolution();
        ctx.forEachItem(items, kTag, [&](int64_t i, RNG &rng, SampleRecorder &rec, Worker &) {
            Point2 p(rng.uniform() * res.x, rng.uniform() * res.y);
            Float v = rng.uniform();
            rec.splat(p, Spectrum(v, 2 * v, Float(i % 7)));
            if (i == 5) rec.splat(p, Spectrum(std::nan(""), 0, 0));  // discarded and counted
            ++calls;
        });
        if (sleepMs > 0) std::this_thread::sleep_for(std::chrono::milliseconds(sleepMs));
        if (interruptAtPass >= 0 && ctx.pass() == interruptAtPass) std::raise(SIGINT);
    }
    void finish(const Film &, const RenderStats &s, Image *) override { finished = s; }
    int perPass = 1, items = 1000, sleepMs = 0, interruptAtPass = -1, interruptInBeginPass = -1, setupMs = 0;
    std::vector<int> firsts, counts;
    std::atomic<int64_t> calls{0};
    RenderStats finished;
};

RenderStats RunLoop(Integrator &integ, RenderJob &job, int spp, int threads, double timeLimit = 0) {
    RenderOptions ro;
    ro.spp = spp;
    ro.nthreads = threads;
    ro.quiet = true;
    ro.timeLimit = timeLimit;
    return RunRender(integ, *job.scene, *job.film, *job.sampler, ro);
}

}  // namespace

TEST(RenderLoop, PassesCoverTheSamplesAndFinishGetsTheStatistics) {
    RenderJob job = Job();  // its integrator is "path": 7 samples in 7 one-sample passes
    RenderOptions o;
    o.spp = 7;
    o.quiet = true;
    RenderResult r = RenderJobImage(job, o);
    EXPECT_EQ(r.stats.spp, 7);
    EXPECT_EQ(r.stats.passes, 7);
    EXPECT_EQ(r.image.metadata.at("spp"), "7");
    EXPECT_EQ(r.image.metadata.at("seed"), "3");

    RenderJob job2 = Job();
    auto owned = std::make_unique<ItemIntegrator>();
    ItemIntegrator &it = *owned;
    it.perPass = 3;
    job2.integrator = std::move(owned);
    RenderStats s = RenderJobImage(job2, o).stats;
    EXPECT_EQ(s.passes, 3);
    EXPECT_EQ(s.spp, 7);
    EXPECT_EQ(it.finished.spp, 7);
    EXPECT_EQ(it.finished.passes, 3);
    EXPECT_EQ(it.firsts, (std::vector<int>{0, 3, 6}));
    EXPECT_EQ(it.counts, (std::vector<int>{3, 3, 1}));
    EXPECT_EQ(job2.film->splatSamples(), 7);
    EXPECT_EQ(it.calls.load(), 3 * it.items);
    EXPECT_EQ(s.nonFinite, 3u);  // one NaN splat per pass
    EXPECT_EQ(s.seed, 3u);
}

TEST(RenderLoop, ItemRandomNumbersAreKeyedBySeedPassAndItem) {
    for (uint64_t seed : {3u, 11u}) {
        RenderJob job = Job(seed);
        std::vector<double> first(2 * 50);
        struct Probe : Integrator {
            std::vector<double> *out;
            std::string name() const override { return "probe"; }
            void runPass(PassContext &ctx) override {
                ctx.forEachItem(50, kTag, [&](int64_t i, RNG &rng, SampleRecorder &, Worker &) {
                    (*out)[size_t(ctx.pass()) * 50 + size_t(i)] = rng.uniform();
                });
            }
        } probe;
        probe.out = &first;
        RunLoop(probe, job, 2, 2);
        for (int pass = 0; pass < 2; ++pass)
            for (int i = 0; i < 50; ++i) {
                RNG expect(Hash(seed ^ kTag, uint64_t(pass), uint64_t(i)));
                EXPECT_EQ(first[size_t(pass) * 50 + i], expect.uniform()) << "seed " << seed << " pass " << pass;
            }
    }
}

TEST(RenderLoop, ItemSplatsDoNotDependOnTheThreadCount) {
    Image ref;
    for (int threads : {1, 2, 7}) {
        RenderJob job = Job();
        ItemIntegrator it;
        it.items = 3000;  // several chunks
        RunLoop(it, job, 2, threads);
        Image img = job.film->toImage();
        if (threads == 1) {
            ref = img;
            double sum = 0;
            for (float v : img.data()) sum += v;
            EXPECT_GT(sum, 0);
            continue;
        }
        ASSERT_EQ(img.data().size(), ref.data().size());
        for (size_t i = 0; i < img.data().size(); ++i)
            ASSERT_EQ(img.data()[i], ref.data()[i]) << threads << " threads, value " << i;
    }
}

TEST(RenderLoop, TilesAndPixelSamplesCoverTheSampleBoundsOnce) {
    RenderJob job = Job();
    struct Cover : Integrator, SampleEstimator {
        std::string name() const override { return "cover"; }
        void runPass(PassContext &ctx) override {
            ctx.forEachTile([&](int, const Bounds2i &tb, FilmTile &, Worker &) { tilePixels += tb.area(); });
            ctx.forEachPixelSample(*this);
        }
        void estimate(const CameraSample &cs, Sampler &, Arena &, SampleRecorder &rec) const override {
            EXPECT_EQ(int(std::floor(cs.pFilm.x)), rec.pixel().x);
            EXPECT_EQ(int(std::floor(cs.pFilm.y)), rec.pixel().y);
            ++samples;
        }
        std::atomic<int64_t> tilePixels{0};
        mutable std::atomic<int64_t> samples{0};
    } cover;
    RenderStats s = RunLoop(cover, job, 3, 2);
    const int64_t area = job.film->sampleBounds().area();
    EXPECT_EQ(cover.tilePixels.load(), 3 * area);
    EXPECT_EQ(cover.samples.load(), 3 * area);
    EXPECT_EQ(s.cameraSamples, 3 * area);
}

TEST(RenderLoop, TimeBudgetStopsBeforeAPassThatWouldExceedIt) {
    RenderJob job = Job();
    ItemIntegrator it;
    it.sleepMs = 40;
    RenderStats s = RunLoop(it, job, 0, 2, 0.3);
    EXPECT_TRUE(s.timeLimited);
    EXPECT_GE(s.passes, 2);
    // The loop starts a pass only when the last pass's duration still fits:
    // the budget is exceeded by at most the variation of one pass's duration.
    EXPECT_LE(s.seconds, 0.3 + 0.04);
}

TEST(RenderLoop, InterruptEndsAfterTheCurrentPass) {
    InstallInterruptHandler();
    ResetInterrupt();
    RenderJob job = Job();
    ItemIntegrator it;
    it.interruptAtPass = 1;
    RenderStats s = RunLoop(it, job, 10, 2);
    ResetInterrupt();
    EXPECT_TRUE(s.interrupted);
    EXPECT_EQ(s.passes, 2);
    EXPECT_EQ(s.spp, 2);
    EXPECT_EQ(job.film->splatSamples(), 2);
}

// A long first beginPass (one-off setup) does not count as the length of a
// pass: a budget of 0.5 s after 0.3 s of setup still runs many short passes
// (with the setup in the estimate the loop stopped after the first).
TEST(RenderLoop, FirstPassSetupIsNotInThePassEstimate) {
    RenderJob job = Job();
    ItemIntegrator it;
    it.setupMs = 300;
    it.items = 10;
    RenderStats s = RunLoop(it, job, 0, 2, 0.5);
    EXPECT_TRUE(s.timeLimited);
    EXPECT_GT(s.passes, 5);
    EXPECT_LE(s.seconds, 0.5 + 0.05);
}

// An interrupt before the first pass's items run (a long first beginPass, e.g.
// mlt's bootstrap) still lets all of them run: the image is never empty. In a
// later pass the items not started are skipped.
TEST(RenderLoop, InterruptRunsTheFirstPassWhole) {
    InstallInterruptHandler();
    for (int pass : {0, 1}) {
        SCOPED_TRACE(pass);
        ResetInterrupt();
        RenderJob job = Job();
        ItemIntegrator it;
        it.interruptInBeginPass = pass;
        RenderStats s = RunLoop(it, job, 10, 2);
        ResetInterrupt();
        EXPECT_TRUE(s.interrupted);
        EXPECT_EQ(s.passes, pass + 1);
        // Pass 0's items all run (none would without the rule); pass 1's are all skipped.
        EXPECT_EQ(it.calls, it.items);
    }
}

// Tiles and item chunks are merged as they finish: while the first one is
// slow, the others start only up to the merge window (so memory is bounded by
// the window, not by the image), and every one of them is merged.
TEST(RenderLoop, MergeWindowBoundsWorkAheadOfASlowTile) {
    RenderJob job = Job();
    struct Slow : Integrator {
        std::string name() const override { return "slow"; }
        void runPass(PassContext &ctx) override {
            window = ctx.mergeWindow();
            tiles = ctx.tiles().count();
            std::atomic<bool> firstDone{false};
            ctx.forEachTile([&](int t, const Bounds2i &tb, FilmTile &tile, Worker &) {
                if (!firstDone) aheadTiles = std::max<int64_t>(aheadTiles, t);
                if (t == 0) {
                    std::this_thread::sleep_for(std::chrono::milliseconds(200));
                    firstDone = true;
                }
                tile.addSample(Point2(tb.pMin.x + 0.5, tb.pMin.y + 0.5), Spectrum(1));
            });
            firstDone = false;
            chunks = (items + PassContext::kItemChunk - 1) / PassContext::kItemChunk;
            ctx.forEachItem(items, kTag, [&](int64_t i, RNG &, SampleRecorder &rec, Worker &) {
                const int64_t c = i / PassContext::kItemChunk;
                if (!firstDone) aheadChunks = std::max<int64_t>(aheadChunks, c);
                if (i == PassContext::kItemChunk - 1) {
                    std::this_thread::sleep_for(std::chrono::milliseconds(200));
                    firstDone = true;
                }
                rec.splat(Point2(0.5, 0.5), Spectrum(1));
            });
        }
        const int64_t items = 100 * PassContext::kItemChunk;
        int64_t window = 0, tiles = 0, chunks = 0;
        std::atomic<int64_t> aheadTiles{0}, aheadChunks{0};
    } slow;
    RenderOptions ro;
    ro.spp = 1;
    ro.nthreads = 2;
    ro.quiet = true;
    ro.tileSize = 1;  // one tile per pixel: more tiles than the window
    RunRender(slow, *job.scene, *job.film, *job.sampler, ro);
    ASSERT_GT(slow.tiles, slow.window);
    ASSERT_GT(slow.chunks, slow.window);
    EXPECT_LT(slow.aheadTiles.load(), slow.window);
    EXPECT_LT(slow.aheadChunks.load(), slow.window);
    // Every tile's sample and every splat reached the film.
    Image img = job.film->mainImage();
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x)
            ASSERT_EQ(img.at(x, y, 0), x == 0 && y == 0 ? 1 + slow.items : 1) << x << ", " << y;
}

// RenderStats' lane figures: a section whose one long work unit leaves the
// other lane idle has occupancy ~1/2, equal units ~1; a section nested in a
// work unit is part of that unit (not tallied again: the sections' wall time
// stays within the pass); time outside sections is not in parallelSeconds.
TEST(RenderLoop, LaneOccupancyCountsIdleLanesAndSerialTime) {
    struct Lanes : Integrator {
        std::string name() const override { return "lanes"; }
        void runPass(PassContext &ctx) override {
            auto sleep = [](int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); };
            // Two work units: the 20x12 film is 2 x 1 tiles of 16 pixels.
            ctx.forEachTile([&](int t, const Bounds2i &, FilmTile &, Worker &) {
                if (t == 0 || balanced) sleep(200);
                ctx.parallelFor(4, 1, [&](int64_t, int64_t, Worker &) { sleep(nestedMs); });
            });
            tiles = ctx.tiles().count();
            sleep(serialMs);  // one thread, outside every section
        }
        bool balanced = false;
        int serialMs = 0, nestedMs = 0, tiles = 0;
    };
    auto run = [](Lanes &l) {
        RenderJob job = Job();
        RenderOptions ro;
        ro.spp = 1;
        ro.nthreads = 2;
        ro.quiet = true;
        ro.tileSize = 16;
        return RunRender(l, *job.scene, *job.film, *job.sampler, ro);
    };
    Lanes skewed;
    skewed.nestedMs = 5;
    RenderStats s = run(skewed);
    ASSERT_EQ(skewed.tiles, 2);
    EXPECT_NEAR(s.laneSeconds, 2 * s.parallelSeconds, 1e-6);
    EXPECT_GE(s.parallelSeconds, 0.2);
    // Busy: the 200 ms unit and the short one; the other lane waits.
    EXPECT_GT(s.busySeconds / s.laneSeconds, 0.4);
    EXPECT_LT(s.busySeconds / s.laneSeconds, 0.65);

    Lanes even;  // both units 200 ms plus their nested loops (4 x 50 ms on the unit's own thread)
    even.balanced = true;
    even.nestedMs = 50;
    even.serialMs = 150;
    s = run(even);
    EXPECT_GT(s.busySeconds / s.laneSeconds, 0.9);
    EXPECT_LE(s.busySeconds, s.laneSeconds * (1 + 1e-9));
    EXPECT_GE(s.parallelSeconds, 0.2);
    EXPECT_LT(s.parallelSeconds, s.seconds - 0.14);  // the serial sleep is outside
}
