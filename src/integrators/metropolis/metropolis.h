// The Metropolis driver shared by mlt (primary sample space, Kelemen et al.
// 2002), pmlt (path space, Veach and Guibas 1997) and gmlt (gradient domain,
// Lehtinen et al. 2013, on pmlt): everything about a Metropolis render that
// does not depend on what a chain's state is or how it mutates.
//   1. Bootstrap (first pass): the integrator weighs its bootstrap candidates
//      (its own sampling); the driver accumulates the weights, b = sum /
//      divisor estimates the integral of the target function, and every chain
//      starts at a candidate drawn in proportion to its weight (no start-up
//      bias: E[b g(X_0)] is the integral of I g; pbrt-v3 Secs. 13.4.3, 16.4.5).
//   2. Chains (every pass): a pass of k spp runs k x (pixels) mutations, dealt
//      to the chains round-robin by a running mutation index (ChainShare), so
//      any split into passes gives every chain the same mutations.
//   3. Splat normalisation: a mutation splats its proposal with weight a and
//      its current state with 1 - a (expected values, Veach and Guibas 1997),
//      each as f / I (expectedValueScale, without b); the film divides by
//      the mutations per pixel and multiplies the splats by its splat scale,
//      which the driver sets after every pass to b times issued / performed
//      mutations (an interrupt or an inactive chain skips mutations). So the
//      film keeps unnormalised sums and every image read from it (the final
//      one, the live display) carries the current b (pbrt-v3 Sec. 16.4.5
//      fixes b by the bootstrap and splats b f / I).
//   4. Normalisation b ("running", the default): per stratum (mlt: a path
//      depth; pmlt, gmlt: one) the bootstrap's sum and count of target values
//      I, plus each chain's independent samples of its stratum (mlt: the
//      large steps, uniform in primary sample space, Kelemen et al. 2002;
//      pmlt, gmlt: bidirectional samples drawn beside the chain as the
//      bootstrap's, independentRate() per mutation): b = sum over strata of
//      (bootstrap sum + samples' sum) / (bootstrap count + samples' count),
//      the two estimates combined by sample count. Consistent (b times the
//      chains' sums is a ratio estimate: bias O(1 / samples)), and its
//      seed-to-seed spread shrinks with the render instead of staying the
//      bootstrap's; "bootstrap" keeps b = the bootstrap's estimate (pbrt-v3,
//      unbiased for any bootstrap size). Each chain sums its samples in its
//      own order and the strata add the chains in index order: b does not
//      depend on the thread count nor on the split into passes.
//   5. Checkpoints: magic, the bootstrap's b, issued and performed
//      mutations, the bootstrap's strata, the integrator's counters, the
//      chain count, then per chain its samples' sum and count and its state.
// Virtual hooks rather than a template on the chain type: the chain types
// stay private to their integrators, gmlt overrides pmlt's hooks as a plain
// subclass, the driver compiles once here, and a hook runs once per chain and
// pass (never per mutation), so the indirect call costs nothing measurable.
#pragma once
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "render/integrator.h"

namespace gradus {

// Chain i performs ChainShare(x, i, chains) of a render's first x mutations
// (mutation j goes to chain j mod chains).
inline int64_t ChainShare(int64_t x, int64_t i, int64_t chains) { return x > i ? (x - i - 1) / chains + 1 : 0; }

// The mutations [first, first + count) of the render's running index that
// one pass deals to its chains.
struct PassMutations {
    int64_t first = 0, count = 0, chains = 0;
    // Chain i's share of this pass.
    int64_t of(int64_t i) const { return ChainShare(first + count, i, chains) - ChainShare(first, i, chains); }
};

// The end-of-render factor issued / performed mutations (1 unless an
// interrupt or an inactive chain left mutations unrun).
double MetropolisRescale(int64_t issued, int64_t performed);
// Scales the main image's R, G, B (the unprefixed channels) by `rescale`.
void ScaleMainImage(Image *out, double rescale);
// Writes <prefix>_b, _mutations, _chains and (when not empty) _warning.
void WriteMetropolisMetadata(Metadata *m, const std::string &prefix, double b, int64_t performed, int64_t chains,
                             const std::string &warning);

class MetropolisIntegrator : public Integrator {
  public:
    // Records the film whose splat scale carries b (integrators call it first).
    void preprocess(const Scene &scene, Film &film) override { film_ = &film; }
    void beginPass(PassContext &ctx) override;  // first pass: the bootstrap
    void runPass(PassContext &ctx) override;    // the chains' share of the pass's mutations
    // Metadata <name()>_* (the film's splat scale already carries b and
    // issued / performed mutations).
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string saveState() const override;
    void loadState(const std::string &state) override;
    bool independentPasses() const override { return false; }

    double b() const { return b_; }                  // the current normalisation
    double bootstrapB() const { return b0_; }        // the bootstrap's estimate
    int64_t independentSamples() const;              // the chains' samples of b so far
    // Set when the bootstrap found no light-carrying path (the image is black).
    const std::string &warning() const { return warning_; }

  protected:
    // The integrator's own RNG streams: keys (seed ^ tag) of the bootstrap and
    // the chain starts, and the forEachItem tag of the mutations.
    struct Tags {
        uint64_t bootstrap, chain, mutation;
    };
    // stateName names the checkpoint state in its error message; magic opens it.
    MetropolisIntegrator(std::string stateName, uint32_t magic, Tags tags)
        : stateName_(std::move(stateName)), magic_(magic), tags_(tags) {}

    // ---- hooks: the bootstrap (beginPass of the first pass)
    // A sum of target values and its sample count (one stratum of b).
    struct RunningSum {
        double sum = 0, count = 0;
    };
    struct BootstrapWeights {
        std::vector<double> weights;  // per candidate, in a fixed order (chain starts index them)
        double divisor = 1;           // b = (sum of the weights) / divisor
        // The strata of the running b (empty: one, {sum of the weights, divisor}).
        std::vector<RunningSum> strata;
    };
    // Samples and weighs the candidates (key: seed ^ tags.bootstrap).
    virtual BootstrapWeights weighBootstrap(PassContext &ctx, uint64_t key) = 0;
    // The warning of a bootstrap without light (b = 0: no chain runs).
    virtual std::string emptyBootstrapWarning() const = 0;
    virtual int chainsParameter() const = 0;
    // Makes n fresh chains (the bootstrap: chainsParameter(); loadState: the
    // stored count); false when a checkpoint's count n is not one this
    // integrator writes.
    virtual bool allocateChains(uint64_t n) = 0;
    virtual int64_t chainCount() const = 0;
    // Starts chain c from candidates drawn with drawCandidate(pick); returns
    // the number of starts that did not rebuild their candidate.
    virtual int64_t startChain(int64_t c, RNG &pick, uint64_t key, Worker &wk) = 0;
    // Frees what only the chain starts needed.
    virtual void releaseBootstrap() {}

    // ---- hooks: a pass
    // Runs at the start of every pass, before the chains (also without chains).
    virtual void beginChains(PassContext &ctx) {}
    // Runs `count` mutations of chain c; returns how many ran (0 for an
    // inactive chain: finish compensates by issued / performed).
    virtual int64_t mutateChain(PassContext &ctx, int64_t c, int64_t count, RNG &rng, SampleRecorder &rec,
                                Worker &wk) = 0;

    // ---- hooks: the running normalisation (4. above)
    // False: b stays the bootstrap's (mlt's "normalization" "bootstrap").
    virtual bool runningNormalization() const { return true; }
    // The stratum of chain c's independent samples (mlt: its depth).
    virtual int chainStratum(int64_t c) const { return 0; }
    // Independent samples the driver draws per mutation (pmlt, gmlt; mlt's
    // normalizationsamples); sample n is drawn by the chain running mutation
    // j when floor(j r) <= n < floor((j + 1) r). 0: none (mlt adds its large
    // steps itself in any case).
    virtual double independentRate() const { return 0; }
    // Target value of independent sample n, drawn for chain c (it joins c's
    // stratum; key: the driver's stream of them; wk.arena is free and reset
    // afterwards).
    virtual double independentSample(uint64_t key, int64_t n, int64_t c, Worker &wk) { return 0; }
    // Sets the film's splat scales (default: the main image's to b x rescale).
    virtual void scaleFilm(Film &film, double b, double rescale) const { film.setSplatScale(-1, b * rescale); }

    // ---- hooks: checkpoints (after magic, the bootstrap's b, issued and
    // performed mutations and the strata)
    virtual void saveCounters(std::string *s) const {}
    virtual bool loadCounters(const std::string &s, size_t *at) { return true; }
    virtual void saveChain(int64_t c, std::string *s) const = 0;
    virtual bool loadChain(int64_t c, const std::string &s, size_t *at) = 0;

    // ---- for the integrators
    // A bootstrap candidate drawn in proportion to its weight (chain starts).
    int64_t drawCandidate(RNG &pick) const;
    // Expected-value splat scale w / I of a state of target I splatted with
    // weight w (a for the proposal, 1 - a for the current state); the film's
    // splat scale multiplies by b (3. above).
    double expectedValueScale(double w, double I) const { return w / I; }
    // Chain c's independent samples of its stratum: its thread adds each
    // sample as it draws it (one running sum in mutation order, whatever the
    // split into passes).
    RunningSum &independentSum(int64_t c) { return chainSamples_[size_t(c)]; }
    // Metadata of the normalisation: <name>_b_bootstrap, <name>_b_samples (the
    // independent samples in b; 0 when b is the bootstrap's).
    void writeNormalizationMetadata(Metadata *m) const;
    double rescale() const { return MetropolisRescale(mutationsIssued_, nMutations_.load()); }
    // Statistics lines of the driver: b, the interrupted pass's scale, the warning.
    std::string driverStatistics() const;

    double b_ = 0;   // the current normalisation (running or the bootstrap's)
    double b0_ = 0;  // the bootstrap's
    std::string warning_;
    int64_t mutationsIssued_ = 0;  // running mutation index (round-robin over the chains)
    std::atomic<int64_t> nMutations_{0}, nStartMismatch_{0};
    double rescale_ = 1;  // applied by finish() when an interrupted pass skipped chains

  private:
    void bootstrap(PassContext &ctx);
    double accumulateWeights(BootstrapWeights w);  // the weights' running sums; returns b
    void startChains(PassContext &ctx, uint64_t key);
    // Chain i's independent samples of one pass (independentRate() > 0).
    void drawIndependent(int64_t i, const PassMutations &pass, uint64_t key, Worker &wk);
    // b from the strata and the chains' samples; the film's splat scale.
    void updateNormalization();
    PassMutations scheduleMutations(const PassContext &ctx);
    [[noreturn]] void refuse() const;  // a checkpoint state that is not this integrator's

    std::string stateName_;
    uint32_t magic_;
    Tags tags_;
    std::vector<double> cdf_;  // running sums of the bootstrap weights (until the chains start)
    std::vector<RunningSum> strata_;        // the bootstrap's, per stratum
    std::vector<RunningSum> chainSamples_;  // per chain: its independent samples
    Film *film_ = nullptr;
};

}  // namespace gradus
