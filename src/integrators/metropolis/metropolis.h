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
//      each as b f / I (expectedValueScale); the film divides by the
//      mutations per pixel, so the image is b / (mutations per pixel) times
//      the summed f / I (pbrt-v3 Sec. 16.4.5). An interrupt can skip chains
//      of the last pass: finish scales by issued / performed mutations.
//   4. Checkpoints: magic, b, issued and performed mutations, the
//      integrator's counters, the chain count, then each chain.
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
    void beginPass(PassContext &ctx) override;  // first pass: the bootstrap
    void runPass(PassContext &ctx) override;    // the chains' share of the pass's mutations
    // Main image scaled by issued / performed mutations; metadata <name()>_*.
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string saveState() const override;
    void loadState(const std::string &state) override;
    bool independentPasses() const override { return false; }

    double b() const { return b_; }
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
    struct BootstrapWeights {
        std::vector<double> weights;  // per candidate, in a fixed order (chain starts index them)
        double divisor = 1;           // b = (sum of the weights) / divisor
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

    // ---- hooks: checkpoints (after magic, b, issued and performed mutations)
    virtual void saveCounters(std::string *s) const {}
    virtual bool loadCounters(const std::string &s, size_t *at) { return true; }
    virtual void saveChain(int64_t c, std::string *s) const = 0;
    virtual bool loadChain(int64_t c, const std::string &s, size_t *at) = 0;

    // ---- for the integrators
    // A bootstrap candidate drawn in proportion to its weight (chain starts).
    int64_t drawCandidate(RNG &pick) const;
    // Expected-value splat scale b w / I of a state of target I splatted with
    // weight w (a for the proposal, 1 - a for the current state).
    double expectedValueScale(double w, double I) const { return b_ * w / I; }
    double rescale() const { return MetropolisRescale(mutationsIssued_, nMutations_.load()); }
    // Statistics lines of the driver: the interrupted pass's scale, the warning.
    std::string driverStatistics() const;

    double b_ = 0;
    std::string warning_;
    int64_t mutationsIssued_ = 0;  // running mutation index (round-robin over the chains)
    std::atomic<int64_t> nMutations_{0}, nStartMismatch_{0};
    double rescale_ = 1;  // applied by finish() when an interrupted pass skipped chains

  private:
    void bootstrap(PassContext &ctx);
    double accumulateWeights(BootstrapWeights w);  // the weights' running sums; returns b
    void startChains(PassContext &ctx, uint64_t key);
    PassMutations scheduleMutations(const PassContext &ctx);
    [[noreturn]] void refuse() const;  // a checkpoint state that is not this integrator's

    std::string stateName_;
    uint32_t magic_;
    Tags tags_;
    std::vector<double> cdf_;  // running sums of the bootstrap weights (until the chains start)
};

}  // namespace gradus
