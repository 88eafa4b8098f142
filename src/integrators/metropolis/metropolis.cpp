#include "integrators/metropolis/metropolis.h"

#include <algorithm>
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
    b_ = accumulateWeights(weighBootstrap(ctx, key));
    if (!(b_ > 0)) {
        b_ = 0;
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
    beginChains(ctx);
    if (chainCount() == 0) return;
    const PassMutations pass = scheduleMutations(ctx);
    ctx.forEachItem(pass.chains, tags_.mutation, [&](int64_t i, RNG &rng, SampleRecorder &rec, Worker &wk) {
        const int64_t count = pass.of(i);
        if (count > 0) nMutations_ += mutateChain(ctx, i, count, rng, rec, wk);
    });
}

// ---------------------------------------------------------------- 3. end of the render
void MetropolisIntegrator::finish(const Film &, const RenderStats &, Image *out) {
    rescale_ = rescale();
    if (rescale_ != 1) ScaleMainImage(out, rescale_);
    WriteMetropolisMetadata(&out->metadata, name(), b_, nMutations_.load(), chainCount(), warning_);
}

std::string MetropolisIntegrator::driverStatistics() const {
    std::ostringstream o;
    if (rescale_ != 1) o << "  interrupted pass: image scaled by " << rescale_ << " (mutations issued / run)\n";
    if (!warning_.empty()) o << "  " << warning_ << "\n";
    return o.str();
}

// ---------------------------------------------------------------- 4. checkpoints
std::string MetropolisIntegrator::saveState() const {
    std::string s;
    PutBytes(&s, magic_);
    PutBytes(&s, b_);
    PutBytes(&s, mutationsIssued_);
    PutBytes(&s, int64_t(nMutations_.load()));
    saveCounters(&s);
    const int64_t n = chainCount();
    PutBytes(&s, uint64_t(n));
    for (int64_t c = 0; c < n; ++c) saveChain(c, &s);
    return s;
}

void MetropolisIntegrator::refuse() const { throw Error("checkpoint: " + stateName_ + " state is inconsistent"); }

void MetropolisIntegrator::loadState(const std::string &s) {
    size_t at = 0;
    uint32_t magic = 0;
    int64_t performed = 0;
    if (!GetBytes(s, &at, &magic) || magic != magic_ || !GetBytes(s, &at, &b_) ||
        !GetBytes(s, &at, &mutationsIssued_) || !GetBytes(s, &at, &performed))
        refuse();
    nMutations_ = performed;
    uint64_t n = 0;
    if (!loadCounters(s, &at) || !GetBytes(s, &at, &n) || !allocateChains(n)) refuse();
    for (int64_t c = 0; c < int64_t(n); ++c)
        if (!loadChain(c, s, &at)) refuse();
    if (at != s.size()) refuse();
}

}  // namespace gradus
