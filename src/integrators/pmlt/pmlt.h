// Path-space Metropolis light transport (Veach and Guibas 1997; Veach 1997,
// Ch. 11): integrator "pmlt".
//
// A chain's state is a full path (pmlt/path.h) and its target function the
// luminance of the path's measurement contribution, I(x) = Y(F(x)).
//   1. Bootstrap (first pass): `bootstrapsamples` bidirectional samples (the
//      bdpt estimator at uniform film positions over the pixel bounds, all
//      strategies of depth <= maxdepth, balance heuristic). Each strategy's
//      weighted contribution w_st C*_st is a candidate; b = (sum of their
//      luminances) / samples estimates the integral of I (times the film's
//      pixel-bounds factor, as in mlt.h).
//   2. Chains start at candidates picked in proportion to their luminance:
//      then E[b g(X_0)] is the integral of I g for any g (resampling the
//      MIS-weighted samples), so there is no start-up bias.
//   3. Mutations (pmlt/mutations.h) with selection weights `bidirectional`,
//      `lens`, `caustic`, `multichain`, `manifold`; a mutation that does not apply to the
//      path's pattern of specular vertices leaves the state (a rejected
//      proposal). Each mutation splats the proposal with a and the current
//      state with 1 - a (expected values), b F / I each; the film divides by
//      the mutations per pixel (pass work and normalisation as mlt.h).
// Parameters:
//   integer maxdepth 5                 maximum path depth (edges - 1)
//   integer bootstrapsamples 100000    bidirectional samples of the bootstrap
//   integer bootstrapconnections 0     cap on the bootstrap's connections (0: none): a sample
//                                        of full-length subpaths (rrdepth -1) evaluates
//                                        ~(d + 2)^2 / 2 strategies at maxdepth d, so
//                                        N = min(bootstrapsamples, cap / ((d + 2)^2 / 2)), at least 1000
//   integer chains 1000                Markov chains
//   integer mutationsperpixel 100      mutations per pixel when --spp is not given
//   integer directsamples 0            direct light separately (below); 0: the chains render it
//   integer rrdepth 3                  Russian roulette in the bootstrap's subpaths after this many
//                                        bounces (-1: off), bdpt's default (the G-MLT paper uses 5)
//   float bidirectional 1              selection weights (relative) of the mutations;
//   float lens 1                         the bidirectional mutation's must be positive
//   float caustic 1
//   float multichain 1
//   float manifold 1
// directsamples N > 0 (G-MLT paper, Sec. 7: "direct lighting is computed
// separately using low discrepancy sampling"): paths with at most one
// scattering vertex (emitters seen directly, one-bounce light) leave the
// chains' target (the bootstrap, b and the mutations ignore them) and are
// estimated in the first pass by N samples per pixel of the scene's sampler
// with the path tracer at maxdepth 1 (next-event estimation and BSDF sampling
// under MIS), through the pixel filter; the film adds that average to the
// chains' splats.
// Splats are unfiltered (the pixel holding the raster point), as mlt's.
#pragma once
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "render/integrator.h"
#include "integrators/pmlt/mutations.h"
#include "lights/light_sampler.h"

namespace gradus {

struct PMLTSettings {
    int maxDepth;
    int bootstrapSamples;
    int bootstrapConnections;
    int chains;
    int mutationsPerPixel;
    int directSamples;
    int rrDepth;
    // Selection weights (relative) by MutationType.
    Float bidirectional, lens, caustic, multiChain, manifold;
    Float weight(pmlt::MutationType t) const {
        switch (t) {
        case pmlt::MutationType::Bidirectional: return bidirectional;
        case pmlt::MutationType::Lens: return lens;
        case pmlt::MutationType::Caustic: return caustic;
        case pmlt::MutationType::MultiChain: return multiChain;
        case pmlt::MutationType::Manifold: return manifold;
        }
        return 0;
    }
};

// pmlt's parameter table (gmlt appends it to its own).
ParamTable<PMLTSettings> PMLTParamTable();

class PMLTIntegrator : public Integrator {
  public:
    explicit PMLTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "pmlt"; }
    void preprocess(const Scene &scene, Film &film) override;
    int defaultSamplesPerPixel() const override { return set_.mutationsPerPixel; }
    void beginPass(PassContext &ctx) override;
    void runPass(PassContext &ctx) override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string statistics() const override;
    std::string saveState() const override;
    void loadState(const std::string &state) override;
    bool independentPasses() const override { return false; }

    const PMLTSettings &settings() const { return set_; }
    double b() const { return b_; }
    int64_t bootstrapSampleCount() const;  // N after the bootstrapconnections cap
    struct TypeCounts {
        int64_t proposed = 0, accepted = 0, notApplicable = 0, zero = 0;
        double acceptSum = 0;  // sum of acceptance probabilities
    };
    TypeCounts counts(pmlt::MutationType t) const;
    int64_t startMismatches() const { return nStartMismatch_; }
    int64_t manifoldWalks() const { return nWalks_; }
    const std::string &warning() const { return warning_; }

  protected:
    // gmlt: its own settings (a PMLTSettings part) and hooks below.
    PMLTIntegrator(const EntityDesc &desc, const PMLTSettings &set);
    struct Candidate {
        int64_t sample;
        int8_t s, t;
        double cdf;
    };
    struct Chain {
        pmlt::Path x;
        Spectrum F;
        Float I = 0;
        Point2 pRaster;
        int8_t dir = 0;  // gmlt: the shift direction of the extended state (CandidateDirection)
    };
    // Bidirectional sample k of the bootstrap: camera and light subpaths.
    struct Sample {
        PathVertex *cv = nullptr, *lv = nullptr;
        BSDF *cb = nullptr, *lb = nullptr;
        int nC = 0, nL = 0;
        Float w = 0;
    };
    // Per-item counts of one pass (flushed into the totals by flushCounts).
    struct ItemCounts {
        int64_t prop[pmlt::kMutationTypes] = {}, acc[pmlt::kMutationTypes] = {}, na[pmlt::kMutationTypes] = {},
                zero[pmlt::kMutationTypes] = {}, accMicro[pmlt::kMutationTypes] = {};
        void record(int type, pmlt::ProposalResult res, Float a) {
            if (res == pmlt::ProposalResult::NotApplicable) ++na[type];
            if (res == pmlt::ProposalResult::Zero) ++zero[type];
            if (res == pmlt::ProposalResult::Proposed) {
                ++prop[type];
                accMicro[type] += int64_t(a * 1e6);
            }
        }
    };
    void flushCounts(const ItemCounts &c, const pmlt::MutationStats &mst, int64_t mutations);
    // One pass of the chains: direct light in the first pass (directsamples),
    // each chain's share of the pass's mutations (items keyed by `tag`), its
    // state x rebuilt (BSDFs in `cur`); fn runs the chain's `count` mutations,
    // leaving its state in x, which is stored back.
    using ChainFn = std::function<void(Chain &ch, int64_t count, pmlt::State &x, Arena &cur, RNG &rng,
                                       SampleRecorder &rec, Worker &wk)>;
    void runChains(PassContext &ctx, uint64_t tag, const ChainFn &fn);
    void selectionWeights(Float *weights) const;
    // The mutation type of one step: chosen among those that apply to x's
    // pattern, weights renormalised (*wsum: their sum).
    static int SelectMutation(const pmlt::Mutator &mut, const pmlt::Path &x, const Float *weights, double u,
                              double *wsum);
    // The selection ratio P(t | y) / P(t | x) of a pattern-changing mutation
    // (Metropolis-Hastings for a mixture of kernels).
    static double SelectionRatio(const pmlt::Mutator &mut, int type, const pmlt::Path &y, const Float *weights,
                                 double wsum) {
        return mut.selectionProbability(pmlt::MutationType(type), y, weights) * wsum / weights[type];
    }
    // The weight with which a bootstrap strategy's path (luminance `lum` of its
    // MIS-weighted contribution) enters b and the chain starts: pmlt's target
    // is the path's luminance itself; gmlt reweights to its own target.
    virtual double candidateWeight(const Sample &smp, int64_t k, int s, int t, const ConnectSamples &cu, double lum,
                                   uint64_t key, Arena &arena) const;
    // A uniform direction in [0, 4) of candidate (k, s, t) (gmlt's extended state).
    static int CandidateDirection(uint64_t key, int64_t k, int s, int t);
    // The evaluated path of strategy (s, t) of a bootstrap sample (BSDFs in
    // arena); false when it cannot be rebuilt or does not evaluate.
    bool strategyState(const Sample &smp, int s, int t, const ConnectSamples &cu, Arena &arena,
                       pmlt::State *st) const;
    // Called before the bootstrap's candidates are weighted (key: the bootstrap's).
    virtual void prepareBootstrap(PassContext &, uint64_t) {}
    // Calls fn(sample, s, t, connection numbers, luminance) for every strategy
    // of bootstrap sample k with a finite positive contribution (its subpaths
    // in arena); returns the number of non-finite contributions left out.
    uint64_t forEachStrategy(uint64_t key, int64_t k, Arena &arena,
                             const std::function<void(const Sample &, int, int, const ConnectSamples &, double)> &fn) const;
    void bootstrap(PassContext &ctx);
    // Bidirectional sample k of the bootstrap (camera and light subpaths, in arena).
    bool makeSample(uint64_t key, int64_t k, Arena &arena, Sample *s) const;

    PMLTSettings set_;
    FileLoc loc_;
    LightSampler lightSampler_;
    BidirContext ctx_;
    pmlt::FilmDomain film_;
    pmlt::MutationSettings mset_;
    std::vector<Candidate> candidates_;  // bootstrap strategies (freed once the chains start)
    int64_t nCandidates_ = 0;
    double b_ = 0;
    std::string warning_;
    std::vector<Chain> chains_;
    int64_t mutationsIssued_ = 0;
    std::vector<const Light *> lights_;  // checkpoint indices of light vertices

    struct AtomicCounts {
        std::atomic<int64_t> proposed{0}, accepted{0}, notApplicable{0}, zero{0};
        std::atomic<int64_t> acceptMicro{0};  // sum of acceptance probabilities x 1e6
    };
    AtomicCounts typeCounts_[pmlt::kMutationTypes];
    std::atomic<int64_t> nMutations_{0}, nStartMismatch_{0}, nWalks_{0}, nWalkFailures_{0};
    std::unique_ptr<EmbreeManifoldScene> mscene_;
    std::unique_ptr<Integrator> direct_;  // directsamples: the path tracer at maxdepth 1
    void renderDirect(PassContext &ctx);
    int64_t nBootstrapSamples_ = 0;
    double rescale_ = 1;
};

}  // namespace gradus
