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
// Passes: the render's "spp" is mutations per pixel (mutationsperpixel
// without --spp); a pass of k spp runs k x (pixels) mutations, dealt to the
// chains round-robin by a running mutation index, so any number of passes
// gives exactly b / (mutations per pixel). Random numbers are keyed by
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
// largestepmis: Kelemen et al. 2002 (Sec. 4) combine the chain with its large
// steps, which are uniform samples of primary sample space, by the balance
// heuristic: chain density I / b, large-step density q_d = largestepprobability
// x b_d / b at depth d (b_d / b: a chain's chance to start there), weights
// w_c = (I/b) / (I/b + q_d) and w_l = q_d / (I/b + q_d). The chain's states
// keep pbrt-v3's estimate (b L / I with expected values) times w_c; each
// large step y adds L(y) w_l(y) divided by the large steps' realised density
// at that depth (largestepprobability x chains at d / chains). Regions the
// chains almost never visit (a dim emitter beside one 1e18 times brighter)
// get their light from the large steps. The weights use the bootstrap's b
// and b_d, so the estimate is consistent (bias O(1 / bootstrap size)), not
// unbiased for any bootstrap as pbrt-v3's; the image mean is no longer b.
// Lights are chosen by power, as in pbrt-v3. Splats are unfiltered (the pixel
// holding the raster point), as pbrt-v3's MLT; the chains sample the film's
// pixel bounds (pbrt-v3: the filter's sample bounds, the margin of which an
// unfiltered splat never reaches).
#pragma once
#include <atomic>
#include <string>
#include <vector>

#include "integrators/common/bidir.h"
#include "render/integrator.h"
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
};

class MLTIntegrator : public Integrator {
  public:
    explicit MLTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "mlt"; }
    void preprocess(const Scene &scene, Film &film) override;
    int defaultSamplesPerPixel() const override { return set_.mutationsPerPixel; }
    void beginPass(PassContext &ctx) override;
    void runPass(PassContext &ctx) override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string statistics() const override;
    // Checkpoints: b, the chains (states, contributions, raster positions),
    // the running mutation index and the counters.
    std::string saveState() const override;
    void loadState(const std::string &state) override;
    bool independentPasses() const override { return false; }

    const MLTSettings &settings() const { return set_; }
    double b() const { return b_; }
    // Set when the bootstrap found no light-carrying path (the image is black).
    const std::string &warning() const { return warning_; }

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

  private:
    struct Chain {
        explicit Chain(const mlt::PrimarySampler &start) : u(start) {}
        mlt::PrimarySampler u;
        int depth = 0;
        Spectrum L;      // contribution of the current state
        Float I = 0;     // its luminance (> 0 for an active chain)
        Point2 pRaster;  // its raster position
    };
    void bootstrap(PassContext &ctx);
    void startChains(PassContext &ctx);

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
    std::vector<double> cdf_;  // running sums of the bootstrap weights I / N_d
    double b_ = 0;
    std::vector<double> bDepth_;  // b's share of each depth, b_d = (1 / N_d) sum_k I_dk
    std::string warning_;
    std::vector<Chain> chains_;
    int64_t mutationsIssued_ = 0;  // running mutation index (round-robin over the chains)

    std::atomic<int64_t> nMutations_{0}, nSmall_{0}, nLarge_{0}, nSmallAccepted_{0}, nLargeAccepted_{0};
    std::atomic<int64_t> nZeroProposals_{0}, nNonFinite_{0}, nStartMismatch_{0};
    int64_t nBootstrapNonZero_ = 0;
    double rescale_ = 1;  // applied by finish() when an interrupted pass skipped chains
};

}  // namespace gradus
