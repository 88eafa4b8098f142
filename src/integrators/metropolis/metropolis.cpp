#include "integrators/metropolis/metropolis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "render/state_bytes.h"

namespace gradus {

double MetropolisRescale(int64_t issued, int64_t performed) {
    return performed > 0 && performed != issued ? double(issued) / double(performed) : 1;
}

void ScaleMainImage(Image *out, double rescale) {
    const auto &names = out->channelNames();
    for (int ch = 0; ch < out->numChannels(); ++ch) {
        if (names[size_t(ch)] != "R" && names[size_t(ch)] != "G" && names[size_t(ch)] != "B") continue;
        for (int y = 0; y < out->height(); ++y)
            for (int x = 0; x < out->width(); ++x) out->at(x, y, ch) = float(out->at(x, y, ch) * rescale);
    }
}

void WriteMetropolisMetadata(Metadata *m, const std::string &prefix, double b, int64_t performed, int64_t chains,
                             const std::string &warning) {
    (*m)[prefix + "_b"] = MetaValue::Double(b);
    (*m)[prefix + "_mutations"] = MetaValue::Int(performed);
    (*m)[prefix + "_chains"] = MetaValue::Int(chains);
    if (!warning.empty()) (*m)[prefix + "_warning"] = warning;
}

// ---------------------------------------------------------------- 1. bootstrap
void MetropolisIntegrator::beginPass(PassContext &ctx) {
    if (ctx.pass() == 0) bootstrap(ctx);
}

void MetropolisIntegrator::bootstrap(PassContext &ctx) {
    const uint64_t key = ctx.seed() ^ tags_.bootstrap;
    // 1a. The integrator's candidates and b.
    BootstrapWeights w = weighBootstrap(ctx, key);
    strata_ = std::move(w.strata);
    const double divisor = w.divisor;
    b_ = b0_ = accumulateWeights(std::move(w));
    if (strata_.empty()) strata_.push_back({cdf_.empty() ? 0 : cdf_.back(), divisor});
    if (!(b_ > 0)) {
        b_ = b0_ = 0;
        warning_ = emptyBootstrapWarning();
        std::fprintf(stderr, "warning: %s\n", warning_.c_str());
        cdf_.clear();
        releaseBootstrap();
        return;
    }
    // 1b. Chain starts in proportion to the weights.
    startChains(ctx, key);
    std::vector<double>().swap(cdf_);
    releaseBootstrap();
}

double MetropolisIntegrator::accumulateWeights(BootstrapWeights w) {
    double sum = 0;
    for (double &v : w.weights) {
        sum += v;
        v = sum;
    }
    cdf_ = std::move(w.weights);
    return sum / w.divisor;
}

void MetropolisIntegrator::startChains(PassContext &ctx, uint64_t key) {
    allocateChains(uint64_t(chainsParameter()));
    chainSamples_.assign(size_t(chainCount()), RunningSum());
    const uint64_t chainKey = ctx.seed() ^ tags_.chain;
    std::atomic<int64_t> mismatch{0};
    ctx.parallelFor(chainCount(), 8, [&](int64_t c0, int64_t c1, Worker &wk) {
        for (int64_t c = c0; c < c1; ++c) {
            RNG pick(Hash(chainKey, uint64_t(c)));
            mismatch += startChain(c, pick, key, wk);
        }
    });
    nStartMismatch_ += mismatch.load();
}

int64_t MetropolisIntegrator::drawCandidate(RNG &pick) const {
    const double x = pick.uniform() * cdf_.back();
    const int64_t i = std::upper_bound(cdf_.begin(), cdf_.end(), x) - cdf_.begin();
    return std::min(i, int64_t(cdf_.size()) - 1);
}

// ---------------------------------------------------------------- 2. chains
PassMutations MetropolisIntegrator::scheduleMutations(const PassContext &ctx) {
    PassMutations p;
    p.first = mutationsIssued_;
    p.count = int64_t(ctx.sampleCount()) * ctx.film().pixelBounds().area();
    p.chains = chainCount();
    mutationsIssued_ += p.count;
    return p;
}

void MetropolisIntegrator::runPass(PassContext &ctx) {
    film_ = &ctx.film();
    beginChains(ctx);
    if (chainCount() == 0) return;
    const PassMutations pass = scheduleMutations(ctx);
    const bool independent = independentRate() > 0 && runningNormalization();
    const uint64_t key = Hash(ctx.seed() ^ tags_.bootstrap, uint64_t(0x696e646570656e64));  // "independ"
    ctx.forEachItem(pass.chains, tags_.mutation, [&](int64_t i, RNG &rng, SampleRecorder &rec, Worker &wk) {
        const int64_t count = pass.of(i);
        if (count <= 0) return;
        nMutations_ += mutateChain(ctx, i, count, rng, rec, wk);
        if (independent) drawIndependent(i, pass, key, wk);
    });
    updateNormalization();
}

void MetropolisIntegrator::drawIndependent(int64_t i, const PassMutations &pass, uint64_t key, Worker &wk) {
    // Chain i's mutations of the pass are j = i + chains m (ChainShare); the
    // samples n with floor(j r) <= n < floor((j + 1) r) are its. Drawn whether
    // or not the chain is active: they are independent of it.
    const double r = independentRate();
    const int64_t m0 = ChainShare(pass.first, i, pass.chains), m1 = ChainShare(pass.first + pass.count, i, pass.chains);
    RunningSum &acc = independentSum(i);
    for (int64_t m = m0; m < m1; ++m) {
        const int64_t j = i + pass.chains * m;
        const int64_t n0 = int64_t(std::floor(double(j) * r)), n1 = int64_t(std::floor(double(j + 1) * r));
        for (int64_t k = n0; k < n1; ++k) {
            acc.sum += independentSample(key, k, i, wk);
            acc.count += 1;
            wk.arena.reset();
        }
    }
}

void MetropolisIntegrator::updateNormalization() {
    // 4. b = sum over strata of (bootstrap + samples) sums / counts; the
    // chains add in index order (deterministic).
    if (runningNormalization() && b0_ > 0) {
        std::vector<RunningSum> s = strata_;
        for (int64_t c = 0; c < int64_t(chainSamples_.size()); ++c) {
            const size_t k = size_t(chainStratum(c));
            if (k >= s.size()) continue;  // not reached: strata cover the chains' strata
            s[k].sum += chainSamples_[size_t(c)].sum;
            s[k].count += chainSamples_[size_t(c)].count;
        }
        double b = 0;
        for (const RunningSum &r : s)
            if (r.count > 0) b += r.sum / r.count;
        b_ = b;
    } else {
        b_ = b0_;
    }
    if (film_) scaleFilm(*film_, b_, rescale());
}

int64_t MetropolisIntegrator::independentSamples() const {
    double n = 0;
    for (const RunningSum &r : chainSamples_) n += r.count;
    return int64_t(n);
}

// ---------------------------------------------------------------- 3. end of the render
void MetropolisIntegrator::finish(const Film &, const RenderStats &, Image *out) {
    // The film's splat scale carries b and issued / performed (updateNormalization).
    rescale_ = rescale();
    WriteMetropolisMetadata(&out->metadata, name(), b_, nMutations_.load(), chainCount(), warning_);
    writeNormalizationMetadata(&out->metadata);
}

void MetropolisIntegrator::writeNormalizationMetadata(Metadata *m) const {
    (*m)[name() + "_b_bootstrap"] = MetaValue::Double(b0_);
    (*m)[name() + "_b_samples"] = MetaValue::Int(runningNormalization() ? independentSamples() : 0);
}

std::string MetropolisIntegrator::driverStatistics() const {
    std::ostringstream o;
    o << "  normalisation: b = " << b_;
    if (runningNormalization())
        o << " (running: the bootstrap's " << b0_ << " and " << independentSamples() << " independent samples)\n";
    else
        o << " (the bootstrap's)\n";
    if (rescale_ != 1) o << "  interrupted pass: image scaled by " << rescale_ << " (mutations issued / run)\n";
    if (!warning_.empty()) o << "  " << warning_ << "\n";
    return o.str();
}

// ---------------------------------------------------------------- 4. checkpoints
std::string MetropolisIntegrator::saveState() const {
    std::string s;
    PutBytes(&s, magic_);
    PutBytes(&s, b0_);
    PutBytes(&s, mutationsIssued_);
    PutBytes(&s, int64_t(nMutations_.load()));
    PutBytes(&s, uint64_t(strata_.size()));
    for (const RunningSum &r : strata_) PutBytes(&s, r);
    saveCounters(&s);
    const int64_t n = chainCount();
    PutBytes(&s, uint64_t(n));
    for (int64_t c = 0; c < n; ++c) {
        PutBytes(&s, chainSamples_[size_t(c)]);
        saveChain(c, &s);
    }
    return s;
}

void MetropolisIntegrator::refuse() const { throw Error("checkpoint: " + stateName_ + " state is inconsistent"); }

void MetropolisIntegrator::loadState(const std::string &s) {
    size_t at = 0;
    uint32_t magic = 0;
    int64_t performed = 0;
    uint64_t strata = 0;
    if (!GetBytes(s, &at, &magic) || magic != magic_ || !GetBytes(s, &at, &b0_) ||
        !GetBytes(s, &at, &mutationsIssued_) || !GetBytes(s, &at, &performed) || !GetBytes(s, &at, &strata) ||
        strata > (s.size() - at) / sizeof(RunningSum))
        refuse();
    nMutations_ = performed;
    strata_.assign(size_t(strata), RunningSum());
    for (RunningSum &r : strata_)
        if (!GetBytes(s, &at, &r)) refuse();
    uint64_t n = 0;
    if (!loadCounters(s, &at) || !GetBytes(s, &at, &n) || !allocateChains(n)) refuse();
    chainSamples_.assign(size_t(n), RunningSum());
    for (int64_t c = 0; c < int64_t(n); ++c)
        if (!GetBytes(s, &at, &chainSamples_[size_t(c)]) || !loadChain(c, s, &at)) refuse();
    if (at != s.size()) refuse();
    for (int64_t c = 0; c < int64_t(n); ++c)
        if (size_t(chainStratum(c)) >= strata_.size()) refuse();
    updateNormalization();
}

}  // namespace gradus
