#include "integrators/pmlt/pmlt.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <functional>
#include <sstream>

#include "core/error.h"
#include "integrators/factories.h"
#include "render/state_bytes.h"
#include "samplers/rng_sampler.h"
#include "integrators/registry.h"

namespace gradus {

using pmlt::MutationType;

std::unique_ptr<Integrator> CreatePMLTIntegrator(const EntityDesc &d) { return std::make_unique<PMLTIntegrator>(d); }

namespace {

constexpr uint64_t kBootstrapTag = 0x706d6c7400000001ULL;
constexpr uint64_t kChainTag = 0x706d6c7400000002ULL;
constexpr uint64_t kMutationTag = 0x706d6c7400000003ULL;
constexpr uint64_t kConnectTag = 0x706d6c7400000004ULL;
constexpr uint64_t kDirectionTag = 0x706d6c7400000005ULL;
constexpr uint32_t kPMLTStateMagic = 0x334c4d50;  // "PML3" (chains with their direction; the running b)

}  // namespace

ParamTable<PMLTSettings> PMLTParamTable() {
    using S = PMLTSettings;
    ParamTable<S> t("pmlt");
    t.maxDepth(&S::maxDepth);
    t.integer("bootstrapsamples", &S::bootstrapSamples, 100000,
              "bidirectional samples of the bootstrap (b and the chain starts)", AtLeast(1));
    t.integer("bootstrapconnections", &S::bootstrapConnections, 0,
              "cap on the bootstrap's connections, ~(maxdepth + 2)^2 / 2 per sample without Russian roulette "
              "(0: no cap; at least 1000 samples)",
              AtLeast(0));
    t.integer("chains", &S::chains, 1000, "Markov chains", AtLeast(1));
    t.integer("mutationsperpixel", &S::mutationsPerPixel, 100, "mutations per pixel when --spp is not given",
              AtLeast(1));
    t.integer("directsamples", &S::directSamples, 0,
              "direct light (at most one scattering vertex) by this many samples per pixel in the first pass "
              "instead of the chains (0: the chains render it)",
              AtLeast(0));
    t.real("normalizationsamples", &S::normalizationSamples, 0.005,
           "bidirectional samples per mutation drawn beside the chains to refine b, the image's normalisation "
           "(0: b from the bootstrap alone)",
           Range{0, 1e6});
    t.integer("rrdepth", &S::rrDepth, 3,
              "Russian roulette in the bootstrap's bidirectional subpaths after this many bounces (-1: off), "
              "as bdpt's default; an unbiased weighting of the candidates that keeps the bootstrap's cost "
              "that of bdpt samples at any maxdepth",
              AtLeast(-1));
    t.real("bidirectional", &S::bidirectional, 1, "selection weight of the bidirectional mutation",
           Range{0, 1e9});
    t.real("lens", &S::lens, 1, "selection weight of the lens perturbation", Range{0, 1e9});
    t.real("caustic", &S::caustic, 1, "selection weight of the caustic perturbation", Range{0, 1e9});
    t.real("multichain", &S::multiChain, 1, "selection weight of the multi-chain perturbation", Range{0, 1e9});
    t.real("manifold", &S::manifold, 1, "selection weight of the manifold perturbation", Range{0, 1e9});
    return t;
}

namespace {

// Connection numbers of strategy (s, t) of bootstrap sample k (reproducible
// when a chain starts there).
ConnectSamples ConnectNumbers(uint64_t key, int64_t k, int s, int t) {
    RNG rng(Hash(key, uint64_t(k), uint64_t(s), uint64_t(t)));
    ConnectSamples cu;
    cu.uLightSelect = Float(rng.uniform());
    cu.uLight = Point2(Float(rng.uniform()), Float(rng.uniform()));
    cu.uLens = Point2(Float(rng.uniform()), Float(rng.uniform()));
    return cu;
}

}  // namespace

std::vector<ParamInfo> PMLTParameters() { return PMLTParamTable().describe(); }

PMLTIntegrator::PMLTIntegrator(const EntityDesc &desc)
    : PMLTIntegrator(desc, PMLTParamTable().parse(desc), kMutationTag) {}

PMLTIntegrator::PMLTIntegrator(const EntityDesc &desc, const PMLTSettings &set, uint64_t mutationTag)
    : MetropolisIntegrator("pmlt", kPMLTStateMagic, {kBootstrapTag, kChainTag, mutationTag}),
      set_(set),
      loc_(desc.loc) {
    if (!(set_.bidirectional > 0))
        throw Error(loc_, "pmlt: \"bidirectional\" must be positive (the perturbations alone are not ergodic)");
    for (int k = 0; k < pmlt::kMutationTypes; ++k) weights_[k] = set_.weight(MutationType(k));
}

void PMLTIntegrator::preprocess(const Scene &scene, Film &film) {
    MetropolisIntegrator::preprocess(scene, film);
    ResetManifoldStats();
    lights_.clear();
    for (const auto &l : scene.lights) lights_.push_back(l.get());
    lightSampler_ = LightSampler(scene.lights, "power", loc_);
    ctx_.init(scene, lightSampler_, MISHeuristic::Balance);
    // Russian roulette only in the bootstrap's subpaths (makeSample); the
    // mutations build paths of a chosen length and never use it.
    ctx_.rrDepth = set_.rrDepth;
    film_.pixels = film.pixelBounds();
    const Point2i full = film.fullResolution();
    film_.scale = film_.pixels.area() > 0 ? Float(int64_t(full.x) * full.y) / Float(film_.pixels.area()) : 1;
    mset_.maxDepth = set_.maxDepth;
    if (set_.directSamples > 0) {
        direct_ = CreateIntegrator(directDesc());
        direct_->preprocess(scene, film);
    }
    if (set_.manifold > 0) {
        mscene_ = std::make_unique<EmbreeManifoldScene>(scene);
        mset_.mscene = mscene_.get();
    }
    mut_ = std::make_unique<pmlt::Mutator>(ctx_, film_, mset_);
}

EntityDesc PMLTIntegrator::directDesc() const {
    EntityDesc d;
    d.type = "path";
    d.loc = loc_;
    Param depth;
    depth.type = "integer";
    depth.name = "maxdepth";
    depth.numbers = {1};
    d.params.add(depth);
    return d;
}

bool PMLTIntegrator::makeSample(uint64_t key, int64_t k, Arena &arena, Sample *s) const {
    RNG rng(Hash(key, uint64_t(k)));
    RNGSampler u(rng);
    CameraSample cs;
    cs.pFilm = film_.sample(u.get2D());
    cs.pLens = u.get2D();
    Ray ray;
    s->w = ctx_.camera->generateRay(cs, &ray);
    if (s->w == 0) return false;
    AllocSubpath(arena, set_.maxDepth + 2, &s->cv, &s->cb);
    AllocSubpath(arena, set_.maxDepth + 1, &s->lv, &s->lb);
    s->nC = GenerateCameraSubpath(ctx_, ray, u, arena, set_.maxDepth + 2, s->cv, s->cb);
    s->nL = GenerateLightSubpath(ctx_, u, arena, set_.maxDepth + 1, s->lv, s->lb);
    return true;
}

double PMLTIntegrator::candidateWeight(const Sample &, int64_t, int, int, const ConnectSamples &, double lum,
                                       uint64_t, Arena &) const {
    return lum;
}

int PMLTIntegrator::CandidateDirection(uint64_t key, int64_t k, int s, int t) {
    return int(Hash(key ^ kDirectionTag, uint64_t(k), uint64_t(s), uint64_t(t)) & 3);
}

int64_t PMLTIntegrator::bootstrapSampleCount() const {
    // Fixed by the parameters alone (not by the samples' work), so b stays an
    // unbiased mean for any cap.
    const int64_t n = set_.maxDepth + 2, perSample = std::max<int64_t>(1, n * n / 2);
    if (set_.bootstrapConnections <= 0) return set_.bootstrapSamples;
    return std::min<int64_t>(set_.bootstrapSamples,
                             std::max<int64_t>(1000, int64_t(set_.bootstrapConnections) / perSample));
}

uint64_t PMLTIntegrator::forEachStrategy(uint64_t key, int64_t k, Arena &arena,
                                         const std::function<void(const Sample &, int, int, const ConnectSamples &,
                                                                  double)> &fn) const {
    Sample smp;
    if (!makeSample(key, k, arena, &smp)) return 0;
    const uint64_t ckey = key ^ kBootstrapTag ^ kConnectTag;  // the seed's connection key
    uint64_t nonFinite = 0;
    for (int t = 1; t <= smp.nC; ++t)
        // s = 1 samples its own light point: it runs even with an empty light subpath (bdpt.cpp).
        for (int s = 0; s <= std::max(smp.nL, ctx_.scene->lights.empty() ? 0 : 1); ++s) {
            const int depth = s + t - 2;
            if (depth < 0 || depth > set_.maxDepth || (s == 1 && t == 1)) continue;
            if (direct_ && s + t <= 3) continue;  // rendered by renderDirect
            ConnectResult r;
            const ConnectSamples cu = ConnectNumbers(ckey, k, s, t);
            if (!ConnectBDPT(ctx_, SubpathView{smp.lv, smp.lb, s}, SubpathView{smp.cv, smp.cb, t}, s, t, cu, &r))
                continue;
            if (r.splat && !film_.contains(r.pRaster)) continue;
            const Spectrum L = r.L * (r.splat ? film_.scale : smp.w);
            if (!L.isFinite()) {
                ++nonFinite;
                continue;
            }
            if (L.y() > 0) fn(smp, s, t, cu, L.y());
        }
    return nonFinite;
}

bool PMLTIntegrator::strategyState(const Sample &smp, int s, int t, const ConnectSamples &cu, Arena &arena,
                                   pmlt::State *st) const {
    if (!pmlt::StrategyPath(ctx_, SubpathView{smp.lv, smp.lb, s}, SubpathView{smp.cv, smp.cb, t}, s, t, cu, &st->x))
        return false;
    pmlt::BuildBSDFs(ctx_, st->x, arena, &st->bsdf);
    return pmlt::Evaluate(ctx_, film_, st->x, st->bsdf.data(), &st->e);
}

// ---------------------------------------------------------------- bootstrap and chain starts
MetropolisIntegrator::BootstrapWeights PMLTIntegrator::weighBootstrap(PassContext &ctx, uint64_t key) {
    const int64_t N = bootstrapSampleCount();
    prepareBootstrap(ctx, key);
    // Every strategy with a positive weight is a candidate, in sample order.
    struct Weighted {
        Candidate c;
        double w;
    };
    constexpr int64_t kGrain = 256;
    std::vector<std::vector<Weighted>> chunks(size_t((N + kGrain - 1) / kGrain));
    std::atomic<uint64_t> bad{0};
    ctx.parallelFor(N, kGrain, [&](int64_t i0, int64_t i1, Worker &wk) {
        std::vector<Weighted> &out = chunks[size_t(i0 / kGrain)];
        uint64_t nonFinite = 0;
        for (int64_t k = i0; k < i1; ++k) {
            nonFinite += forEachStrategy(key, k, wk.arena,
                                         [&](const Sample &smp, int s, int t, const ConnectSamples &cu, double lum) {
                                             const double y = candidateWeight(smp, k, s, t, cu, lum, key, wk.arena);
                                             if (y > 0) out.push_back(Weighted{Candidate{k, int8_t(s), int8_t(t)}, y});
                                         });
            wk.arena.reset();
        }
        bad += nonFinite;
    });
    ctx.addNonFinite(bad);
    BootstrapWeights w;
    candidates_.clear();
    for (const auto &c : chunks)
        for (const Weighted &cd : c) {
            candidates_.push_back(cd.c);
            w.weights.push_back(cd.w);
        }
    nBootstrapSamples_ = N;
    w.divisor = double(N);  // b = (sum of the luminances) / samples (pmlt.h)
    return w;
}

double PMLTIntegrator::independentSample(uint64_t key, int64_t n, int64_t, Worker &wk) {
    // A bidirectional sample drawn and weighed as the bootstrap's (its own
    // key): an independent estimate of b (pmlt.h).
    double sum = 0;
    forEachStrategy(key, n, wk.arena, [&](const Sample &smp, int s, int t, const ConnectSamples &cu, double lum) {
        sum += candidateWeight(smp, n, s, t, cu, lum, key, wk.arena);
    });
    return sum;
}

std::string PMLTIntegrator::emptyBootstrapWarning() const {
    return "pmlt: none of the " + std::to_string(nBootstrapSamples_) +
           " bootstrap samples carries light (b = 0); no chains run and the image is black" +
           std::string(direct_ ? " but for the direct light" : "") +
           " (raise \"bootstrapsamples\" if the light is hard to reach)";
}

bool PMLTIntegrator::allocateChains(uint64_t n) {
    if (n > uint64_t(set_.chains)) return false;
    chains_.assign(size_t(n), Chain());
    return true;
}

int64_t PMLTIntegrator::startChain(int64_t c, RNG &pick, uint64_t key, Worker &wk) {
    // Chain starts in proportion to the candidates' weights (pmlt.h).
    const uint64_t ckey = key ^ kBootstrapTag ^ kConnectTag;  // the seed's connection key
    Chain &ch = chains_[size_t(c)];
    ch.I = 0;
    int64_t mismatch = 0;
    // A start whose path does not evaluate (a strategy the bdpt estimator
    // evaluated but Evaluate rejects: float hit points on very short
    // edges) is counted and replaced by another draw; its share of b is
    // below the counted fraction.
    for (int attempt = 0; attempt < 16 && !(ch.I > 0); ++attempt) {
        const Candidate &cd = candidates_[size_t(drawCandidate(pick))];
        Sample smp;
        pmlt::State st;
        if (makeSample(key, cd.sample, wk.arena, &smp) &&
            strategyState(smp, cd.s, cd.t, ConnectNumbers(ckey, cd.sample, cd.s, cd.t), wk.arena, &st)) {
            ch.x = st.x;
            ch.F = st.e.F;
            ch.I = st.e.I;
            ch.pRaster = st.e.pRaster;
            ch.dir = int8_t(CandidateDirection(key, cd.sample, cd.s, cd.t));
        } else {
            ++mismatch;
        }
        wk.arena.reset();
    }
    return mismatch;
}

void PMLTIntegrator::releaseBootstrap() {
    // The candidates serve the chain starts only (up to millions of entries).
    if (!chains_.empty()) nCandidates_ = int64_t(candidates_.size());
    std::vector<Candidate>().swap(candidates_);
}

// ---------------------------------------------------------------- a pass
void PMLTIntegrator::beginChains(PassContext &ctx) {
    if (direct_ && ctx.pass() == 0) renderDirect(ctx);
}

void PMLTIntegrator::renderDirect(PassContext &ctx) {
    const auto &est = dynamic_cast<const SampleEstimator &>(*direct_);
    direct_->beginPass(ctx);
    const int N = set_.directSamples;
    // N samples per pixel of the scene's sampler (indices 0 .. N-1), the
    // camera sample drawn as the loop's per-pixel work draws it.
    ctx.forEachTile([&](int, const Bounds2i &tb, FilmTile &tile, Worker &w) {
        uint64_t nonFinite = 0;
        for (int y = tb.pMin.y; y < tb.pMax.y; ++y)
            for (int x = tb.pMin.x; x < tb.pMax.x; ++x)
                for (int j = 0; j < N; ++j) {
                    Sampler &sampler = *w.sampler;
                    const Point2i pixel{x, y};
                    sampler.startPixelSample(pixel, j);
                    CameraSample cs;
                    const Point2 u = sampler.get2D();
                    cs.pFilm = Point2(x + u.x, y + u.y);
                    cs.pLens = sampler.get2D();
                    SampleRecorder rec(tile, pixel, cs.pFilm);
                    est.estimate(cs, sampler, w.arena, rec);
                    tile.addCount(pixel, 1);  // per-sample layers (gmlt's G-PT) average by it
                    nonFinite += rec.nonFinite;
                    w.arena.reset();
                }
        ctx.addNonFinite(nonFinite);
    });
}

int64_t PMLTIntegrator::mutateChain(PassContext &, int64_t i, int64_t count, RNG &rng, SampleRecorder &rec,
                                    Worker &wk) {
    // The chain's state x rebuilt (BSDFs in `cur`), mutated, stored back.
    Chain &ch = chains_[size_t(i)];
    if (!(ch.I > 0)) return 0;
    thread_local Arena cur;
    cur.reset();
    pmlt::State xs;
    xs.x = ch.x;
    pmlt::BuildBSDFs(ctx_, xs.x, cur, &xs.bsdf);
    if (!pmlt::Evaluate(ctx_, film_, xs.x, xs.bsdf.data(), &xs.e)) return 0;
    const int64_t ran = runMutations(ch, count, xs, cur, rng, rec, wk);
    ch.x = xs.x;
    ch.F = xs.e.F;
    ch.I = xs.e.I;
    ch.pRaster = xs.e.pRaster;
    return ran;
}

PMLTIntegrator::Proposal PMLTIntegrator::proposeMutation(const pmlt::State &xs, RNG &rng, Sampler &u, Arena &arena,
                                                         pmlt::State *ys, pmlt::MutationStats *mst) const {
    Proposal p;
    p.type = SelectMutation(*mut_, xs.x, weights_, rng.uniform(), &p.wsum);
    p.res = mut_->propose(MutationType(p.type), xs, u, arena, ys, &p.ratio, mst);
    return p;
}

bool PMLTIntegrator::acceptStep(Float a, RNG &rng, pmlt::State &xs, pmlt::State &ys, Arena &cur) const {
    if (!(a > 0 && rng.uniform() < a)) return false;
    std::swap(xs, ys);
    cur.reset();
    pmlt::BuildBSDFs(ctx_, xs.x, cur, &xs.bsdf);
    return true;
}

int64_t PMLTIntegrator::runMutations(Chain &, int64_t count, pmlt::State &xs, Arena &cur, RNG &rng,
                                     SampleRecorder &rec, Worker &wk) {
    pmlt::State ys;
    RNGSampler u(rng);
    pmlt::MutationStats mst;
    ItemCounts cnt;
    for (int64_t k = 0; k < count; ++k) {
        // 1. A mutation and its proposal y.
        const Proposal p = proposeMutation(xs, rng, u, wk.arena, &ys, &mst);
        // 2. Acceptance (Metropolis-Hastings with the selection ratio).
        Float a = 0;
        if (p.res == pmlt::ProposalResult::Proposed && outsideTarget(ys)) {
            ++cnt.zero[p.type];  // outside the chains' target (directsamples)
        } else if (p.res == pmlt::ProposalResult::Proposed) {
            a = Float(std::min(1.0, p.ratio * SelectionRatio(*mut_, p.type, ys.x, weights_, p.wsum)));
        }
        cnt.record(p.type, p.res, a);
        // 3. Expected values (Veach and Guibas 1997, "expected values"): the proposal with weight a,
        // the current state with 1 - a, each as b F / I.
        if (a > 0) rec.splat(ys.e.pRaster, ys.e.F * Float(expectedValueScale(a, ys.e.I)));
        if (a < 1) rec.splat(xs.e.pRaster, xs.e.F * Float(expectedValueScale(1 - a, xs.e.I)));
        // 4. The step.
        if (acceptStep(a, rng, xs, ys, cur)) ++cnt.acc[p.type];
        wk.arena.reset();
    }
    flushCounts(cnt, mst);
    return count;
}

int PMLTIntegrator::SelectMutation(const pmlt::Mutator &mut, const pmlt::Path &x, const Float *weights, double u,
                                   double *wsum) {
    double cdf[pmlt::kMutationTypes], sum = 0;
    for (int t = 0; t < pmlt::kMutationTypes; ++t)
        cdf[t] = (sum += mut.applies(MutationType(t), x) ? weights[t] : 0);
    const double r = u * sum;
    int type = 0;
    while (type + 1 < pmlt::kMutationTypes && r >= cdf[type]) ++type;
    *wsum = sum;
    return type;
}

void PMLTIntegrator::flushCounts(const ItemCounts &cnt, const pmlt::MutationStats &mst) {
    nWalks_ += mst.walks;
    nWalkFailures_ += mst.walkFailures;
    for (int k = 0; k < pmlt::kMutationTypes; ++k) {
        AtomicCounts &c = typeCounts_[k];
        c.proposed += cnt.prop[k];
        c.accepted += cnt.acc[k];
        c.notApplicable += cnt.na[k];
        c.zero += cnt.zero[k];
        c.acceptMicro += cnt.accMicro[k];
    }
}

PMLTIntegrator::TypeCounts PMLTIntegrator::counts(MutationType t) const {
    const AtomicCounts &c = typeCounts_[int(t)];
    TypeCounts r;
    r.proposed = c.proposed;
    r.accepted = c.accepted;
    r.notApplicable = c.notApplicable;
    r.zero = c.zero;
    r.acceptSum = double(c.acceptMicro.load()) * 1e-6;
    return r;
}

std::string PMLTIntegrator::statistics() const {
    std::ostringstream o;
    o << "Path-space MLT:\n";
    o << "  bootstrap: " << nBootstrapSamples_ << " bidirectional samples, " << nCandidates_
      << " contributing strategies, b = " << b0_ << "\n";
    int64_t active = 0;
    for (const Chain &c : chains_) active += c.I > 0;
    o << "  chains: " << chains_.size() << " (" << active << " active); mutations: " << nMutations_ << "\n";
    for (int k = 0; k < pmlt::kMutationTypes; ++k) {
        const TypeCounts c = counts(MutationType(k));
        const int64_t tried = c.proposed + c.zero + c.notApplicable;
        o << "  " << pmlt::MutationName(MutationType(k)) << ": " << tried << " selected, " << c.notApplicable
          << " not applicable, " << c.zero << " without contribution, " << c.proposed << " proposed, "
          << c.accepted << " accepted";
        if (c.proposed > 0) o << " (mean acceptance " << 100.0 * c.acceptSum / double(c.proposed) << "%)";
        o << "\n";
    }
    o << "  manifold walks: " << nWalks_ << ", failed or not reversible: " << nWalkFailures_ << "\n";
    // Process-wide walk counters (manifold.h): iterations and the reasons of the failures.
    o << FormatManifoldStats(GetManifoldStats(), "  ");
    if (nStartMismatch_ > 0)
        o << "  chain starts that could not be rebuilt (drawn again): " << nStartMismatch_ << "\n";
    return o.str() + driverStatistics();
}

// ---------------------------------------------------------------- checkpoints
// After the driver's framing, per chain: F, I, the raster position, the
// direction and the path's vertices.
void PMLTIntegrator::saveChain(int64_t i, std::string *s) const {
    const Chain &c = chains_[size_t(i)];
    PutBytes(s, c.F);
    PutBytes(s, c.I);
    PutBytes(s, c.pRaster);
    PutBytes(s, c.dir);
    PutBytes(s, uint32_t(c.x.v.size()));
    for (PathVertex v : c.x.v) {
        // Pointers are stored as the light's index (light vertices) and
        // rebuilt from the geometry record (surface vertices).
        int32_t light = -1;
        if (v.type == VertexType::Light && v.light)
            light = int32_t(std::find(lights_.begin(), lights_.end(), v.light) - lights_.begin());
        v.material = nullptr;
        PutBytes(s, v);
        PutBytes(s, light);
    }
}

bool PMLTIntegrator::loadChain(int64_t i, const std::string &s, size_t *at) {
    Chain &c = chains_[size_t(i)];
    uint32_t nv = 0;
    if (!GetBytes(s, at, &c.F) || !GetBytes(s, at, &c.I) || !GetBytes(s, at, &c.pRaster) ||
        !GetBytes(s, at, &c.dir) || c.dir < 0 || c.dir > 3 || !GetBytes(s, at, &nv) ||
        nv > uint32_t(set_.maxDepth) + 2)
        return false;
    c.x.v.resize(nv);
    for (PathVertex &v : c.x.v) {
        int32_t light = -1;
        if (!GetBytes(s, at, &v) || !GetBytes(s, at, &light)) return false;
        if (v.type == VertexType::Surface) {
            if (v.geomId < 0 || size_t(v.geomId) >= ctx_.scene->geometry.size()) return false;
            v.material = ctx_.scene->geometry[size_t(v.geomId)].material;
        } else {
            if (light >= int32_t(lights_.size())) return false;
            v.light = light >= 0 ? lights_[size_t(light)] : nullptr;
        }
    }
    return true;
}

}  // namespace gradus
