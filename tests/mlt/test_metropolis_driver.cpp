// The Metropolis driver (integrators/metropolis/) under mlt, pmlt and gmlt:
// chain scheduling, the bootstrap's b and chain starts, splat normalisation,
// the end-of-render rescale and the checkpoint framing, on a toy integrator
// whose every mutation splats b in total (so the image mean must be b).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "integrators/metropolis/metropolis.h"
#include "mlt_test_util.h"

namespace gradus {
namespace {

using mlt_test::BoxScene;
using mlt_test::MeanLum;
using mlt_test::MLTLine;

// Mutation j of a render goes to chain j mod chains, whatever the passes.
TEST(MetropolisDriver, ChainShareDealsMutationsRoundRobinForAnySplitIntoPasses) {
    for (int64_t chains : {1, 3, 7, 1000}) {
        for (const std::vector<int64_t> &passes :
             {std::vector<int64_t>{5000}, std::vector<int64_t>{1, 2, 3, 4, 990, 4000}, std::vector<int64_t>{0, 7, 0, 13}}) {
            std::vector<int64_t> got(size_t(chains), 0), want(size_t(chains), 0);
            int64_t first = 0;
            for (int64_t count : passes) {
                PassMutations p;
                p.first = first;
                p.count = count;
                p.chains = chains;
                int64_t sum = 0;
                for (int64_t i = 0; i < chains; ++i) {
                    got[size_t(i)] += p.of(i);
                    sum += p.of(i);
                }
                EXPECT_EQ(sum, count) << "a pass deals exactly its mutations";
                for (int64_t j = first; j < first + count; ++j) ++want[size_t(j % chains)];
                first += count;
            }
            EXPECT_EQ(got, want) << chains << " chains";
            for (int64_t i = 0; i < chains; ++i) EXPECT_EQ(got[size_t(i)], ChainShare(first, i, chains));
        }
    }
}

TEST(MetropolisDriver, RescaleAndMetadata) {
    EXPECT_EQ(MetropolisRescale(100, 100), 1);
    EXPECT_EQ(MetropolisRescale(100, 0), 1);  // nothing ran: nothing to scale
    EXPECT_EQ(MetropolisRescale(100, 80), 1.25);

    Image im(2, 1, {"R", "G", "B", "primal.R", "primal.G", "primal.B"});
    for (int x = 0; x < 2; ++x)
        for (int c = 0; c < 6; ++c) im.at(x, 0, c) = float(1 + c);
    ScaleMainImage(&im, 2);
    for (int x = 0; x < 2; ++x)
        for (int c = 0; c < 6; ++c) EXPECT_EQ(im.at(x, 0, c), float((1 + c) * (c < 3 ? 2 : 1))) << "channel " << c;

    Metadata m;
    WriteMetropolisMetadata(&m, "pmlt", 0.5, 42, 7, "");
    EXPECT_EQ(m["pmlt_b"].number(), 0.5);
    EXPECT_EQ(m["pmlt_mutations"].str(), "42");
    EXPECT_EQ(m["pmlt_chains"].str(), "7");
    EXPECT_EQ(m.count("pmlt_warning"), 0u);
    WriteMetropolisMetadata(&m, "pmlt", 0, 0, 0, "no light");
    EXPECT_EQ(m["pmlt_warning"].str(), "no light");
}

// Candidates of weights w (b = sum / divisor); each chain keeps its start's
// weight as its target I and splats b I / I with the expected-value weights
// a and 1 - a at a uniform pixel: b per mutation.
class ToyMetropolis : public MetropolisIntegrator {
  public:
    static constexpr uint32_t kMagic = 0x594f5431;
    ToyMetropolis(std::vector<double> w, double divisor, int chains, int inactive = -1)
        : MetropolisIntegrator("toy", kMagic, {11, 12, 13}),
          w_(std::move(w)),
          divisor_(divisor),
          chains_(chains),
          inactive_(inactive) {}
    std::string name() const override { return "toy"; }

    double sampleValue = -1;  // >= 0: each mutation adds an independent sample of this value to b
    bool running = true;      // runningNormalization()
    std::vector<double> I;                   // per chain
    std::vector<int64_t> start, mutations;  // per chain: its candidate, its mutations
    std::map<int64_t, int64_t> startCount;  // candidate -> chains started there

  protected:
    BootstrapWeights weighBootstrap(PassContext &, uint64_t) override { return {w_, divisor_, {}}; }
    std::string emptyBootstrapWarning() const override { return "toy: no weight"; }
    int chainsParameter() const override { return chains_; }
    bool runningNormalization() const override { return running; }
    bool allocateChains(uint64_t n) override {
        if (n > uint64_t(chains_)) return false;
        I.assign(size_t(n), 0.0);
        start.assign(size_t(n), -1);
        mutations.assign(size_t(n), 0);
        return true;
    }
    int64_t chainCount() const override { return int64_t(I.size()); }
    int64_t startChain(int64_t c, RNG &pick, uint64_t, Worker &) override {
        start[size_t(c)] = drawCandidate(pick);
        I[size_t(c)] = w_[size_t(start[size_t(c)])];
        return 0;
    }
    void releaseBootstrap() override {
        for (int64_t s : start) ++startCount[s];
    }
    int64_t mutateChain(PassContext &ctx, int64_t c, int64_t count, RNG &rng, SampleRecorder &rec,
                        Worker &) override {
        mutations[size_t(c)] += count;
        for (int64_t k = 0; sampleValue >= 0 && k < count; ++k) {
            independentSum(c).sum += sampleValue;
            independentSum(c).count += 1;
        }
        if (c == inactive_) return 0;
        const Bounds2i px = ctx.film().pixelBounds();
        const double i = I[size_t(c)];
        for (int64_t k = 0; k < count; ++k) {
            const Point2 p(px.pMin.x + rng.uniform() * px.width(), px.pMin.y + rng.uniform() * px.height());
            const double a = rng.uniform();
            rec.splat(p, Spectrum(Float(i)) * expectedValueScale(a, i));
            rec.splat(p, Spectrum(Float(i)) * expectedValueScale(1 - a, i));
        }
        return count;
    }
    void saveChain(int64_t c, std::string *s) const override {
        s->append(reinterpret_cast<const char *>(&I[size_t(c)]), sizeof(double));
    }
    bool loadChain(int64_t c, const std::string &s, size_t *at) override {
        if (s.size() - *at < sizeof(double)) return false;
        std::memcpy(&I[size_t(c)], s.data() + *at, sizeof(double));
        *at += sizeof(double);
        return true;
    }

  private:
    std::vector<double> w_;
    double divisor_;
    int chains_, inactive_;
};

struct ToyRender {
    Image image;
    std::unique_ptr<ToyMetropolis> toy;
};

std::unique_ptr<ToyMetropolis> Toy(const std::vector<double> &w, int chains, int inactive = -1) {
    return std::make_unique<ToyMetropolis>(w, 4, chains, inactive);
}

ToyRender RenderToy(std::unique_ptr<ToyMetropolis> toy, int spp, int sppPerPass) {
    BuildOptions bo;
    bo.sppOverride = spp;
    bo.seed = 3;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseString(BoxScene(MLTLine(""), 8)), bo);
    job.integrator = std::move(toy);
    RenderOptions ro;
    ro.spp = spp;
    ro.nthreads = 2;
    ro.quiet = true;
    ro.sppPerPass = sppPerPass;
    RenderResult res = RenderJobImage(job, ro);
    return {std::move(res.image), std::unique_ptr<ToyMetropolis>(static_cast<ToyMetropolis *>(job.integrator.release()))};
}

const std::vector<double> kWeights = {0, 2, 0, 1, 5, 0};  // b = 8 / 4 = 2

// b = sum / divisor; starts drawn in proportion to the weights (never at a
// zero weight); the image mean is b for any split into passes; every chain
// performs ChainShare of the render's mutations.
TEST(MetropolisDriver, BootstrapStartsAndNormalisation) {
    for (int perPass : {1, 2, 5}) {
        SCOPED_TRACE(std::to_string(perPass) + " spp per pass");
        const ToyRender r = RenderToy(Toy(kWeights, 600), 5, perPass);
        const ToyMetropolis &toy = *r.toy;
        EXPECT_EQ(toy.b(), 2);
        EXPECT_NEAR(MeanLum(r.image) / toy.b(), 1, 1e-6);
        const int64_t total = 5 * 64;
        for (int64_t c = 0; c < 600; ++c) EXPECT_EQ(toy.mutations[size_t(c)], ChainShare(total, c, 600));
        EXPECT_EQ(r.image.metadata.at("toy_mutations").str(), std::to_string(total));
        EXPECT_EQ(r.image.metadata.at("toy_chains").str(), "600");
        EXPECT_EQ(r.image.metadata.at("toy_b").number(), 2);
        // Starts: 600 draws with probabilities 2/8, 1/8, 5/8; each count within
        // 5 standard deviations (false-positive rate below 1e-6 per count; a
        // start at a zero weight, or uniform over the candidates, fails).
        int64_t n = 0;
        for (auto [k, count] : toy.startCount) {
            ASSERT_GT(kWeights[size_t(k)], 0) << "a chain started at zero-weight candidate " << k;
            const double p = kWeights[size_t(k)] / 8, mean = 600 * p, sd = std::sqrt(600 * p * (1 - p));
            EXPECT_LT(std::abs(double(count) - mean), 5 * sd) << "candidate " << k << ": " << count << " starts";
            n += count;
        }
        EXPECT_EQ(n, 600);
    }
}

// A chain that runs nothing is compensated at the end: issued / performed.
TEST(MetropolisDriver, InactiveChainIsCompensatedByTheRescale) {
    const ToyRender r = RenderToy(Toy(kWeights, 10, 0), 4, 1);
    const int64_t total = 4 * 64, performed = total - ChainShare(total, 0, 10);
    EXPECT_EQ(r.image.metadata.at("toy_mutations").str(), std::to_string(performed));
    EXPECT_NEAR(MeanLum(r.image) / r.toy->b(), 1, 1e-6);
}

TEST(MetropolisDriver, EmptyBootstrapGivesBlackImageAndWarning) {
    const ToyRender r = RenderToy(Toy({0, 0, 0}, 5), 2, 1);
    EXPECT_EQ(r.toy->b(), 0);
    EXPECT_EQ(r.toy->warning(), "toy: no weight");
    EXPECT_EQ(r.toy->I.size(), 0u) << "no chain runs";
    EXPECT_EQ(MeanLum(r.image), 0);
    EXPECT_EQ(r.image.metadata.at("toy_warning").str(), "toy: no weight");
}

// The running normalisation: b = (bootstrap sum + samples' sum) / (divisor +
// samples), applied by the film to every splat made so far (the image mean is
// the final b, whatever the pass split); "bootstrap" keeps the bootstrap's.
TEST(MetropolisDriver, RunningNormalisationScalesEverySplatByTheCurrentB) {
    for (int perPass : {1, 2, 5}) {
        auto toy = Toy(kWeights, 7);
        toy->sampleValue = 4;
        const ToyRender r = RenderToy(std::move(toy), 5, perPass);
        const double M = 5 * 64;  // one sample per mutation
        const double want = (8 + 4 * M) / (4 + M);
        EXPECT_DOUBLE_EQ(r.toy->bootstrapB(), 2);
        EXPECT_NEAR(r.toy->b(), want, 1e-12) << perPass << " spp per pass";
        EXPECT_EQ(r.toy->independentSamples(), int64_t(M));
        EXPECT_NEAR(MeanLum(r.image) / want, 1, 1e-6) << "the image carries the final b";
        EXPECT_EQ(r.image.metadata.at("toy_b").number(), r.toy->b());
        EXPECT_EQ(r.image.metadata.at("toy_b_bootstrap").number(), 2);
        EXPECT_EQ(r.image.metadata.at("toy_b_samples").str(), std::to_string(int64_t(M)));
        // A checkpoint restores the samples and with them b.
        ToyMetropolis back(kWeights, 4, 7);
        back.loadState(r.toy->saveState());
        EXPECT_EQ(back.b(), r.toy->b());
    }
    auto toy = Toy(kWeights, 7);
    toy->sampleValue = 4;
    toy->running = false;
    const ToyRender r = RenderToy(std::move(toy), 5, 2);
    EXPECT_EQ(r.toy->b(), 2);
    EXPECT_NEAR(MeanLum(r.image) / 2, 1, 1e-6);
}

// Checkpoints: magic, b, issued and performed mutations, the chains; any
// other bytes are refused with the integrator's state name.
TEST(MetropolisDriver, CheckpointFramingRoundTripsAndRefuses) {
    const ToyRender r = RenderToy(Toy(kWeights, 6), 3, 1);
    const ToyMetropolis &toy = *r.toy;
    const std::string s = toy.saveState();
    // magic, b0, issued, performed, one stratum (count, sum, count), the chain
    // count, per chain its samples (sum, count) and its I.
    EXPECT_EQ(s.size(), 4 + 8 + 8 + 8 + 8 + 16 + 8 + 6 * (16 + sizeof(double)));
    ToyMetropolis back(kWeights, 4, 6);
    back.loadState(s);
    EXPECT_EQ(back.b(), 2);
    EXPECT_EQ(back.I, toy.I);
    EXPECT_EQ(back.saveState(), s);
    auto refused = [&](const std::string &bytes) {
        ToyMetropolis t(kWeights, 4, 6);
        try {
            t.loadState(bytes);
        } catch (const Error &e) {
            EXPECT_NE(std::string(e.what()).find("checkpoint: toy state is inconsistent"), std::string::npos)
                << e.what();
            return true;
        }
        return false;
    };
    for (size_t n = 0; n < s.size(); ++n) EXPECT_TRUE(refused(s.substr(0, n))) << "truncated to " << n;
    EXPECT_TRUE(refused(s + "x")) << "trailing byte";
    std::string magic = s;
    magic[0] ^= 1;
    EXPECT_TRUE(refused(magic));
    ToyMetropolis fewer(kWeights, 4, 5);  // 6 chains stored, 5 allowed
    EXPECT_THROW(fewer.loadState(s), Error);
}

}  // namespace
}  // namespace gradus
