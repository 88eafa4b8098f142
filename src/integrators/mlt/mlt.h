// Multiplexed primary-sample-space Metropolis light transport (Kelemen et al.
// 2002; Hachisuka, Kaplanyan, Dachsbacher 2014; pbrt-v3 "mlt", book Sec. 16.4)
// on the shared bidirectional core in integrators/common/.
//
// A state is (depth, u): a path depth and a primary sample vector (three
// streams, primary_sample.h). u's connection stream picks one BDPT strategy
// (s, t) of that depth; the state's contribution is that strategy's
// MIS-weighted estimate divided by the selection probability, its target
// function the luminance of that.
//   1. Bootstrap (first pass): N_d independent states at each depth d (N_d =
//      bootstrapsamples unless bootstrapvertices caps the work, below);
//      b = sum over d of (summed luminance at d) / N_d estimates the integral
//      of the target over all depths.
//   2. Chains: each starts from a bootstrap state picked in proportion to its
//      luminance (b times an estimate at such a start is unbiased, so there is
//      no start-up bias), then mutates (small/large steps) in the later passes
//      and in the rest of the first.
//   3. Each mutation splats current and proposed state with the expected-value
//      weights, scaled by b; the film divides by the mutations per pixel.
//   4. b converges with the render (normalization "running", the default;
//      pbrt-v3 keeps the bootstrap's b, "bootstrap"): the large steps are
//      uniform states of their chain's depth d, so b_d = (bootstrap's sum of
//      I at d + the large steps' sum at d) / (N_d + their count), b = sum_d
//      b_d; the film keeps the unnormalised splats and every image read from
//      it carries the current b (metropolis/metropolis.h). With the bootstrap's
//      b alone its relative spread from seed to seed stays ~ the bootstrap's
//      (sd(I) / b / sqrt(N_d)) however long the render; running, it shrinks
//      as 1 / sqrt(N_d + large steps). Running is consistent (ratio bias O(1 /
//      samples)), pbrt-v3's is unbiased for any bootstrap size.
// Passes: the render's "spp" is mutations per pixel (mutationsperpixel
// without --spp); a pass of k spp runs k x (pixels) mutations, dealt to the
// chains round-robin by a running mutation index, so any number of passes
// gives exactly b / (mutations per pixel) (the Metropolis driver,
// metropolis/metropolis.h, shared with pmlt and gmlt). Random numbers are keyed by
// (seed, bootstrap index), (seed, chain) and (seed, pass, chain): images do
// not depend on the thread count.
//
// Parameters (pbrt-v3 names and defaults):
//   integer maxdepth 5                  maximum path depth (edges - 1)
//   integer bootstrapsamples 100000     bootstrap states per depth (b and the chain starts)
//   integer bootstrapvertices 50000000  cap on the bootstrap's path vertices (0: no cap).
//       A state of depth d has d + 2 vertices, so pbrt-v3's bootstrap costs
//       bootstrapsamples x sum_d (d + 2), quadratic in maxdepth (100000 states
//       per depth take ~10 s at maxdepth 65 and hours at 1000). With the cap,
//       N_d = min(bootstrapsamples, max(1, cap / ((maxdepth + 1)(d + 2)))):
//       an equal share of vertices per depth, cutting only the deepest depths
//       (no change up to maxdepth 20 with the defaults). Any N_d >= 1 keeps b
//       and the chain starts unbiased: each depth's mean is unbiased, and a
//       start is drawn with probability (I / N_d) / sum (I / N_d).
//   integer chains 1000                 Markov chains
//   integer mutationsperpixel 100       mutations per pixel when --spp is not given
//   float largestepprobability 0.3      probability of a large step (independent proposal)
//   float sigma 0.01                    standard deviation of a small step in primary sample space
//   bool largestepmis false             also count large steps as independent samples (below)
//   string normalization "running"      running | bootstrap (4. above; pbrt-v3: bootstrap)
//   float normalizationsamples 0        independent samples of b per mutation besides the
//       large steps (0: large steps only). A large step is one strategy picked
//       out of depth + 2 and divided by its probability; an independent sample
//       here evaluates all of them on one pair of subpaths of the chain's depth
//       (bdpt's prefix reuse): E[sum_(s,t) I_st / (depth + 2)] = E[I] = b_d, at
//       a much smaller variance where one strategy carries the light (a small
//       light seen through its own emission: Cornell box, 2% seed-to-seed
//       spread of the image mean at 16 mutations per pixel with large steps alone).
// largestepmis: Kelemen et al. 2002 (Sec. 4) combine the chain with its large
// steps, which are uniform samples of primary sample space, by the balance
// heuristic: chain density I / b, large-step density q_d = largestepprobability
// x b_d / b at depth d (b_d / b: a chain's chance to start there), weights
// w_c = (I/b) / (I/b + q_d) and w_l = q_d / (I/b + q_d). The chain's states
// keep pbrt-v3's estimate (b L / I with expected values) times w_c; each
// large step y adds L(y) w_l(y) divided by the large steps' realised density
// at that depth (largestepprobability x chains at d / chains): splats of their
// own (a film layer added to the main image), as they do not scale with b. Regions the
// chains almost never visit (a dim emitter beside one 1e18 times brighter)
// get their light from the large steps. The weights use the bootstrap's b
// and b_d (a fixed partition of unity), while the chain's part scales with the
// (running) b; the image mean is no longer b.
// Participating media as pbrt-v3's MLT (its subpaths and connections are
// BDPT's): medium vertices on both subpaths and transmittance in the
// connections (integrators/common/bidir.h). Every random number of the media
// (distance sampling, delta tracking, ratio-tracking transmittance) is read
// from the primary samples, in the stream being read (camera and light
// subpaths: interleaved with the walk's numbers; connection: after the s = 1
// and t = 1 numbers), as pbrt-v3's MLTSampler serves Medium::Sample and
// Medium::Tr: mutations perturb them like the rest. A scene without media
// reads exactly the numbers it read before.
// Lights are chosen by power, as in pbrt-v3. Splats are unfiltered (the pixel
// holding the raster point), as pbrt-v3's MLT; the chains sample the film's
// pixel bounds (pbrt-v3: the filter's sample bounds, the margin of which an
// unfiltered splat never reaches).
#pragma once
#include <atomic>
#include <string>
#include <vector>

#include "integrators/common/bidir.h"
#include "integrators/metropolis/metropolis.h"
#include "integrators/mlt/primary_sample.h"
#include "render/params.h"
#include "lights/light_sampler.h"

namespace gradus {

// Every field is set by the parameter table (mlt.cpp; defaults there).
struct MLTSettings {
    int maxDepth;
    int bootstrapSamples;
    int bootstrapVertices;
    int chains;
    int mutationsPerPixel;
    Float largeStepProbability;
    Float sigma;
    bool largeStepMIS;
    std::string normalization;
    Float normalizationSamples;
};

class MLTIntegrator : public MetropolisIntegrator {
  public:
    explicit MLTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "mlt"; }
    bool rendersMedia() const override { return true; }  // medium vertices of the shared core (above)
    void preprocess(const Scene &scene, Film &film) override;
    int defaultSamplesPerPixel() const override { return set_.mutationsPerPixel; }
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string statistics() const override;

    const MLTSettings &settings() const { return set_; }

    // Counts of the render so far (statistics(), tests).
    struct Counts {
        int64_t mutations, small, large, smallAccepted, largeAccepted, zeroProposals, nonFinite, startMismatch;
    };
    Counts counts() const {
        return {nMutations_, nSmall_, nLarge_, nSmallAccepted_, nLargeAccepted_, nZeroProposals_, nNonFinite_,
                nStartMismatch_};
    }

    // Chains per depth (their depth is fixed at the start) and the bootstrap's
    // states per depth N_d.
    std::vector<int64_t> chainsPerDepth() const;
    const std::vector<int64_t> &bootstrapStatesPerDepth() const { return perDepth_; }

    // Contribution of state `u` at `depth` (the chosen strategy's weighted
    // estimate over its selection probability) and its raster position.
    Spectrum contribution(mlt::PrimarySampler &u, int depth, Arena &arena, Point2 *pRaster) const;
    // The sum over every strategy (s, t) of `depth` of the target of its
    // weighted estimate, all from one pair of subpaths drawn from u: an
    // estimate of b_d with the same mean as I (normalizationsamples, below).
    double allStrategies(mlt::PrimarySampler &u, int depth, Arena &arena) const;

  private:
    struct Chain {
        explicit Chain(const mlt::PrimarySampler &start) : u(start) {}
        mlt::PrimarySampler u;
        int depth = 0;
        Spectrum L;      // contribution of the current state
        Float I = 0;     // its luminance (> 0 for an active chain)
        Point2 pRaster;  // its raster position
    };
    // Counts of one chain's mutations in a pass (added to the totals after it).
    struct StepCounts {
        int64_t small = 0, large = 0, smallAccepted = 0, largeAccepted = 0, zero = 0, nonFinite = 0;
    };

    // The driver's hooks (metropolis/metropolis.h).
    BootstrapWeights weighBootstrap(PassContext &ctx, uint64_t key) override;
    std::string emptyBootstrapWarning() const override;
    int chainsParameter() const override { return set_.chains; }
    bool allocateChains(uint64_t n) override;
    int64_t chainCount() const override { return int64_t(chains_.size()); }
    int64_t startChain(int64_t c, RNG &pick, uint64_t key, Worker &wk) override;
    void releaseBootstrap() override { std::vector<double>().swap(bootstrapI_); }
    bool runningNormalization() const override { return set_.normalization == "running"; }
    int chainStratum(int64_t c) const override { return chains_[size_t(c)].depth; }
    double independentRate() const override { return double(set_.normalizationSamples); }
    double independentSample(uint64_t key, int64_t n, int64_t c, Worker &wk) override;
    void scaleFilm(Film &film, double b, double rescale) const override;
    void beginChains(PassContext &ctx) override;
    int64_t mutateChain(PassContext &ctx, int64_t c, int64_t count, RNG &rng, SampleRecorder &rec,
                        Worker &wk) override;
    void saveCounters(std::string *s) const override;
    bool loadCounters(const std::string &s, size_t *at) override;
    void saveChain(int64_t c, std::string *s) const override;
    bool loadChain(int64_t c, const std::string &s, size_t *at) override;

    // Bootstrap: I of every state (d, k), at index rowStart_[k] + d.
    std::vector<double> evaluateBootstrap(PassContext &ctx, uint64_t key);
    // The row k of bootstrap index i, and the key of state (d, k)'s numbers.
    int64_t rowOf(int64_t i) const;
    uint64_t stateKey(int64_t d, int64_t k) const { return uint64_t(k * (set_.maxDepth + 1) + d); }
    // One mutation of chain c: proposal, acceptance, splats, the step.
    // (large: the chain's running sum of its large steps' I, metropolis.h)
    void mutate(Chain &c, RNG &rng, SampleRecorder &rec, Arena &arena, StepCounts *n, RunningSum *large) const;
    void splatMutation(const Chain &c, const Spectrum &LY, Float IY, Point2 pY, Float a, bool isLarge,
                       SampleRecorder &rec) const;

    MLTSettings set_;
    FileLoc loc_;
    LightSampler lightSampler_;
    BidirContext ctx_;
    Bounds2i pixels_;         // the film's pixel bounds: where camera strategies start
    Float splatScale_ = 1;    // light-tracing (t = 1) contributions: film pixels / pixel bounds
    // States per depth (N_d, non-increasing in d) and the bootstrap arrays'
    // layout, index-major as pbrt-v3's interleaved index: row k holds state k
    // of every depth with N_d > k, so state (d, k) is at rowStart_[k] + d.
    std::vector<int64_t> perDepth_, rowStart_;
    std::vector<double> bootstrapI_;  // I of the bootstrap states (until the chains start)
    std::vector<double> bDepth_;  // b's share of each depth, b_d = (1 / N_d) sum_k I_dk
    std::vector<Chain> chains_;
    // largestepmis (beginChains): q_d and the large steps' normaliser per depth.
    std::vector<double> qLarge_, largeNorm_;
    int largeLayer_ = -1;  // largestepmis: the large steps' splats (part of the main image)

    std::atomic<int64_t> nSmall_{0}, nLarge_{0}, nSmallAccepted_{0}, nLargeAccepted_{0};
    std::atomic<int64_t> nZeroProposals_{0}, nNonFinite_{0};
    int64_t nBootstrapNonZero_ = 0;
};

}  // namespace gradus
