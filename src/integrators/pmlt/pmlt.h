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
//      the mutations per pixel (pass work and normalisation: the Metropolis
//      driver, metropolis/metropolis.h, shared with mlt).
//   4. b converges with the render: beside the chains, normalizationsamples
//      bidirectional samples per mutation, drawn and weighed as the
//      bootstrap's (their own random numbers), are independent estimates of b
//      and join the bootstrap's by sample count; the film keeps unnormalised
//      splats and every image read from it carries the current b (the
//      driver). With the bootstrap's b alone, the image mean of a scene whose
//      light is hard to reach differs from seed to seed by b's spread at the
//      bootstrap's size (door gap: +-8% at 100000 samples) however long the render.
//      Cost: a bidirectional sample takes the time of 5-9 mutations (pmlt and
//      gmlt on the door, Cornell box and glass cube scenes), so the default
//      0.005 costs 2.5-4.5% of the chains' time; a 5-minute render then
//      draws ~10x the bootstrap's samples.
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
//   float normalizationsamples 0.005   bidirectional samples per mutation that refine b (below; 0: none)
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

#include "integrators/metropolis/metropolis.h"
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
    Float normalizationSamples;
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

class PMLTIntegrator : public MetropolisIntegrator {
  public:
    explicit PMLTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "pmlt"; }
    void preprocess(const Scene &scene, Film &film) override;
    int defaultSamplesPerPixel() const override { return set_.mutationsPerPixel; }
    std::string statistics() const override;

    const PMLTSettings &settings() const { return set_; }
    int64_t bootstrapSampleCount() const;  // N after the bootstrapconnections cap
    struct TypeCounts {
        int64_t proposed = 0, accepted = 0, notApplicable = 0, zero = 0;
        double acceptSum = 0;  // sum of acceptance probabilities
    };
    TypeCounts counts(pmlt::MutationType t) const;
    int64_t startMismatches() const { return nStartMismatch_; }
    int64_t manifoldWalks() const { return nWalks_; }

  protected:
    // gmlt: its own settings (a PMLTSettings part), mutation stream and hooks below.
    PMLTIntegrator(const EntityDesc &desc, const PMLTSettings &set, uint64_t mutationTag);
    struct Candidate {
        int64_t sample;
        int8_t s, t;
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
    void flushCounts(const ItemCounts &c, const pmlt::MutationStats &mst);
    // One chain's `count` mutations from its rebuilt state x (BSDFs in `cur`),
    // leaving the new state in x; returns the mutations run (gmlt overrides).
    virtual int64_t runMutations(Chain &ch, int64_t count, pmlt::State &x, Arena &cur, RNG &rng,
                                 SampleRecorder &rec, Worker &wk);
    // A mutation's proposal: the type chosen among those that apply to x's
    // pattern (weights renormalised, wsum their sum) and its result.
    struct Proposal {
        int type = 0;
        pmlt::ProposalResult res = pmlt::ProposalResult::NotApplicable;
        double ratio = 0, wsum = 0;
    };
    Proposal proposeMutation(const pmlt::State &x, RNG &rng, Sampler &u, Arena &arena, pmlt::State *y,
                             pmlt::MutationStats *mst) const;
    // directsamples: paths of at most one scattering vertex are outside the chains' target.
    bool outsideTarget(const pmlt::State &y) const { return direct_ && y.x.size() <= 3; }
    // Moves the chain to y with probability a (y's BSDFs rebuilt in cur); true when it moved.
    bool acceptStep(Float a, RNG &rng, pmlt::State &x, pmlt::State &y, Arena &cur) const;
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
    // directsamples: the integrator of the direct pass (paths of at most one
    // scattering vertex; pmlt: the path tracer at maxdepth 1, gmlt: G-PT's).
    virtual EntityDesc directDesc() const;
    // Calls fn(sample, s, t, connection numbers, luminance) for every strategy
    // of bootstrap sample k with a finite positive contribution (its subpaths
    // in arena); returns the number of non-finite contributions left out.
    uint64_t forEachStrategy(uint64_t key, int64_t k, Arena &arena,
                             const std::function<void(const Sample &, int, int, const ConnectSamples &, double)> &fn) const;
    // Bidirectional sample k of the bootstrap (camera and light subpaths, in arena).
    bool makeSample(uint64_t key, int64_t k, Arena &arena, Sample *s) const;

    PMLTSettings set_;
    Float weights_[pmlt::kMutationTypes];  // selection weights by MutationType
    FileLoc loc_;
    LightSampler lightSampler_;
    BidirContext ctx_;
    pmlt::FilmDomain film_;
    pmlt::MutationSettings mset_;
    std::unique_ptr<pmlt::Mutator> mut_;  // the chains' mutations (gmlt: with its shift's settings)
    std::vector<Candidate> candidates_;  // bootstrap strategies (freed once the chains start)
    int64_t nCandidates_ = 0;
    std::vector<Chain> chains_;
    std::vector<const Light *> lights_;  // checkpoint indices of light vertices

    struct AtomicCounts {
        std::atomic<int64_t> proposed{0}, accepted{0}, notApplicable{0}, zero{0};
        std::atomic<int64_t> acceptMicro{0};  // sum of acceptance probabilities x 1e6
    };
    AtomicCounts typeCounts_[pmlt::kMutationTypes];
    std::atomic<int64_t> nWalks_{0}, nWalkFailures_{0};
    std::unique_ptr<EmbreeManifoldScene> mscene_;
    std::unique_ptr<Integrator> direct_;  // directsamples: the direct pass (directDesc)
    int64_t nBootstrapSamples_ = 0;

  private:
    // The driver's hooks (metropolis/metropolis.h).
    BootstrapWeights weighBootstrap(PassContext &ctx, uint64_t key) override;
    std::string emptyBootstrapWarning() const override;
    int chainsParameter() const override { return set_.chains; }
    bool allocateChains(uint64_t n) override;
    int64_t chainCount() const override { return int64_t(chains_.size()); }
    int64_t startChain(int64_t c, RNG &pick, uint64_t key, Worker &wk) override;
    void releaseBootstrap() override;
    double independentRate() const override { return double(set_.normalizationSamples); }
    double independentSample(uint64_t key, int64_t n, int64_t c, Worker &wk) override;
    void beginChains(PassContext &ctx) override;
    int64_t mutateChain(PassContext &ctx, int64_t c, int64_t count, RNG &rng, SampleRecorder &rec,
                        Worker &wk) override;
    void saveChain(int64_t c, std::string *s) const override;
    bool loadChain(int64_t c, const std::string &s, size_t *at) override;

    void renderDirect(PassContext &ctx);
};

}  // namespace gradus
