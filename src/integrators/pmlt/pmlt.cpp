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

PMLTIntegrator::PMLTIntegrator(const EntityDesc &desc) : PMLTIntegrator(desc, PMLTParamTable().parse(desc)) {}

PMLTIntegrator::PMLTIntegrator(const EntityDesc &desc, const PMLTSettings &set) : set_(set), loc_(desc.loc) {
    if (!(set_.bidirectional > 0))
        throw Error(loc_, "pmlt: \"bidirectional\" must be positive (the perturbations alone are not ergodic)");
}

void PMLTIntegrator::preprocess(const Scene &scene, Film &film) {
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
        EntityDesc d;
        d.type = "path";
        d.loc = loc_;
        Param depth;
        depth.type = "integer";
        depth.name = "maxdepth";
        depth.numbers = {1};
        d.params.add(depth);
        direct_ = CreateIntegrator(d);
        direct_->preprocess(scene, film);
    }
    if (set_.manifold > 0) {
        mscene_ = std::make_unique<EmbreeManifoldScene>(scene);
        mset_.mscene = mscene_.get();
    }
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
        for (int s = 0; s <= smp.nL; ++s) {
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

void PMLTIntegrator::bootstrap(PassContext &ctx) {
    const int64_t N = bootstrapSampleCount();
    const uint64_t key = ctx.seed() ^ kBootstrapTag, ckey = ctx.seed() ^ kConnectTag;
    prepareBootstrap(ctx, key);
    constexpr int64_t kGrain = 256;
    std::vector<std::vector<Candidate>> chunks(size_t((N + kGrain - 1) / kGrain));
    std::atomic<uint64_t> bad{0};
    ctx.parallelFor(N, kGrain, [&](int64_t i0, int64_t i1, Worker &wk) {
        std::vector<Candidate> &out = chunks[size_t(i0 / kGrain)];
        uint64_t nonFinite = 0;
        for (int64_t k = i0; k < i1; ++k) {
            nonFinite += forEachStrategy(key, k, wk.arena,
                                         [&](const Sample &smp, int s, int t, const ConnectSamples &cu, double lum) {
                                             const double y = candidateWeight(smp, k, s, t, cu, lum, key, wk.arena);
                                             if (y > 0) out.push_back(Candidate{k, int8_t(s), int8_t(t), y});
                                         });
            wk.arena.reset();
        }
        bad += nonFinite;
    });
    ctx.addNonFinite(bad);
    candidates_.clear();
    double sum = 0;
    for (auto &c : chunks)
        for (Candidate &cd : c) {
            sum += cd.cdf;
            cd.cdf = sum;
            candidates_.push_back(cd);
        }
    nBootstrapSamples_ = N;
    b_ = sum / double(N);
    if (!(b_ > 0)) {
        b_ = 0;
        warning_ = "pmlt: none of the " + std::to_string(N) +
                   " bootstrap samples carries light (b = 0); no chains run and the image is black" +
                   std::string(direct_ ? " but for the direct light" : "") +
                   " (raise \"bootstrapsamples\" if the light is hard to reach)";
        std::fprintf(stderr, "warning: %s\n", warning_.c_str());
        candidates_.clear();
        return;
    }
    // Chain starts in proportion to the candidates' luminance (pmlt.h).
    chains_.assign(size_t(set_.chains), Chain());
    const uint64_t chainKey = ctx.seed() ^ kChainTag;
    std::atomic<int64_t> mismatch{0};
    ctx.parallelFor(set_.chains, 8, [&](int64_t c0, int64_t c1, Worker &wk) {
        for (int64_t c = c0; c < c1; ++c) {
            RNG pick(Hash(chainKey, uint64_t(c)));
            Chain &ch = chains_[size_t(c)];
            ch.I = 0;
            // A start whose path does not evaluate (a strategy the bdpt estimator
            // evaluated but Evaluate rejects: float hit points on very short
            // edges) is counted and replaced by another draw; its share of b is
            // below the counted fraction.
            for (int attempt = 0; attempt < 16 && !(ch.I > 0); ++attempt) {
                const double xr = pick.uniform() * sum;
                size_t i = size_t(std::upper_bound(candidates_.begin(), candidates_.end(), xr,
                                                   [](double v, const Candidate &cd) { return v < cd.cdf; }) -
                                  candidates_.begin());
                i = std::min(i, candidates_.size() - 1);
                const Candidate &cd = candidates_[i];
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
        }
    });
    nStartMismatch_ += mismatch.load();
    // The candidates serve the chain starts only (up to millions of entries).
    nCandidates_ = int64_t(candidates_.size());
    std::vector<Candidate>().swap(candidates_);
}

void PMLTIntegrator::beginPass(PassContext &ctx) {
    if (ctx.pass() == 0) bootstrap(ctx);
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
                    nonFinite += rec.nonFinite;
                    w.arena.reset();
                }
        ctx.addNonFinite(nonFinite);
    });
}

void PMLTIntegrator::runChains(PassContext &ctx, uint64_t tag, const ChainFn &fn) {
    if (direct_ && ctx.pass() == 0) renderDirect(ctx);
    if (chains_.empty()) return;
    const int64_t nChains = int64_t(chains_.size());
    const int64_t M = int64_t(ctx.sampleCount()) * film_.pixels.area();
    const int64_t first = mutationsIssued_;
    mutationsIssued_ += M;
    ctx.forEachItem(nChains, tag, [&](int64_t i, RNG &rng, SampleRecorder &rec, Worker &wk) {
        const int64_t count = ChainShare(first + M, i, nChains) - ChainShare(first, i, nChains);
        Chain &ch = chains_[size_t(i)];
        if (count == 0 || !(ch.I > 0)) return;
        thread_local Arena cur;
        cur.reset();
        pmlt::State xs;
        xs.x = ch.x;
        pmlt::BuildBSDFs(ctx_, xs.x, cur, &xs.bsdf);
        if (!pmlt::Evaluate(ctx_, film_, xs.x, xs.bsdf.data(), &xs.e)) return;
        fn(ch, count, xs, cur, rng, rec, wk);
        ch.x = xs.x;
        ch.F = xs.e.F;
        ch.I = xs.e.I;
        ch.pRaster = xs.e.pRaster;
    });
}

void PMLTIntegrator::selectionWeights(Float *weights) const {
    for (int k = 0; k < pmlt::kMutationTypes; ++k) weights[k] = set_.weight(MutationType(k));
}

void PMLTIntegrator::runPass(PassContext &ctx) {
    Float weights[pmlt::kMutationTypes];
    selectionWeights(weights);
    const double b = b_;
    const pmlt::Mutator mut(ctx_, film_, mset_);
    runChains(ctx, kMutationTag, [&](Chain &, int64_t count, pmlt::State &xs, Arena &cur, RNG &rng,
                                     SampleRecorder &rec, Worker &wk) {
        pmlt::State ys;
        RNGSampler u(rng);
        pmlt::MutationStats mst;
        ItemCounts cnt;
        for (int64_t k = 0; k < count; ++k) {
            double wsum = 0;
            const int type = SelectMutation(mut, xs.x, weights, rng.uniform(), &wsum);
            double ratio = 0;
            const pmlt::ProposalResult res = mut.propose(MutationType(type), xs, u, wk.arena, &ys, &ratio, &mst);
            Float a = 0;
            if (res == pmlt::ProposalResult::Proposed && direct_ && ys.x.size() <= 3) {
                ++cnt.zero[type];  // outside the chains' target (directsamples)
            } else if (res == pmlt::ProposalResult::Proposed) {
                a = Float(std::min(1.0, ratio * SelectionRatio(mut, type, ys.x, weights, wsum)));
            }
            cnt.record(type, res, a);
            // Expected values (Veach and Guibas 1997, "expected values"): the proposal with weight a,
            // the current state with 1 - a, each as b F / I.
            if (a > 0) rec.splat(ys.e.pRaster, ys.e.F * Float(b * a / ys.e.I));
            if (a < 1) rec.splat(xs.e.pRaster, xs.e.F * Float(b * (1 - a) / xs.e.I));
            if (a > 0 && rng.uniform() < a) {
                ++cnt.acc[type];
                std::swap(xs, ys);
                cur.reset();
                pmlt::BuildBSDFs(ctx_, xs.x, cur, &xs.bsdf);
            }
            wk.arena.reset();
        }
        flushCounts(cnt, mst, count);
    });
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

void PMLTIntegrator::flushCounts(const ItemCounts &cnt, const pmlt::MutationStats &mst, int64_t mutations) {
    nMutations_ += mutations;
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

void PMLTIntegrator::finish(const Film &, const RenderStats &, Image *out) {
    rescale_ = FinishMetropolisImage(out, "pmlt", b_, mutationsIssued_, nMutations_.load(), int64_t(chains_.size()),
                                     warning_);
}

std::string PMLTIntegrator::statistics() const {
    std::ostringstream o;
    o << "Path-space MLT:\n";
    o << "  bootstrap: " << nBootstrapSamples_ << " bidirectional samples, " << nCandidates_
      << " contributing strategies, b = " << b_ << "\n";
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
    if (rescale_ != 1) o << "  interrupted pass: image scaled by " << rescale_ << " (mutations issued / run)\n";
    if (!warning_.empty()) o << "  " << warning_ << "\n";
    return o.str();
}

// ---------------------------------------------------------------- checkpoints
namespace {
constexpr uint32_t kPMLTStateMagic = 0x324c4d50;  // "PML2" (chains with their direction)
}  // namespace

std::string PMLTIntegrator::saveState() const {
    std::string s;
    PutBytes(&s, kPMLTStateMagic);
    PutBytes(&s, b_);
    PutBytes(&s, mutationsIssued_);
    PutBytes(&s, int64_t(nMutations_.load()));
    PutBytes(&s, uint64_t(chains_.size()));
    for (const Chain &c : chains_) {
        PutBytes(&s, c.F);
        PutBytes(&s, c.I);
        PutBytes(&s, c.pRaster);
        PutBytes(&s, c.dir);
        PutBytes(&s, uint32_t(c.x.v.size()));
        for (PathVertex v : c.x.v) {
            // Pointers are stored as the light's index (light vertices) and
            // rebuilt from the geometry record (surface vertices).
            int32_t light = -1;
            if (v.type == VertexType::Light && v.light)
                light = int32_t(std::find(lights_.begin(), lights_.end(), v.light) - lights_.begin());
            v.material = nullptr;
            PutBytes(&s, v);
            PutBytes(&s, light);
        }
    }
    return s;
}

void PMLTIntegrator::loadState(const std::string &s) {
    size_t at = 0;
    uint32_t magic = 0;
    auto bad = [] { throw Error("checkpoint: pmlt state is inconsistent"); };
    int64_t done = 0;
    uint64_t n = 0;
    if (!GetBytes(s, &at, &magic) || magic != kPMLTStateMagic || !GetBytes(s, &at, &b_) || !GetBytes(s, &at, &mutationsIssued_) ||
        !GetBytes(s, &at, &done) || !GetBytes(s, &at, &n) || n > uint64_t(set_.chains))
        bad();
    nMutations_ = done;
    chains_.assign(size_t(n), Chain());
    for (Chain &c : chains_) {
        uint32_t nv = 0;
        if (!GetBytes(s, &at, &c.F) || !GetBytes(s, &at, &c.I) || !GetBytes(s, &at, &c.pRaster) || !GetBytes(s, &at, &c.dir) || c.dir < 0 || c.dir > 3 ||
            !GetBytes(s, &at, &nv) ||
            nv > uint32_t(set_.maxDepth) + 2)
            bad();
        c.x.v.resize(nv);
        for (PathVertex &v : c.x.v) {
            int32_t light = -1;
            if (!GetBytes(s, &at, &v) || !GetBytes(s, &at, &light)) bad();
            if (v.type == VertexType::Surface) {
                if (v.geomId < 0 || size_t(v.geomId) >= ctx_.scene->geometry.size()) bad();
                v.material = ctx_.scene->geometry[size_t(v.geomId)].material;
            } else {
                if (light >= int32_t(lights_.size())) bad();
                v.light = light >= 0 ? lights_[size_t(light)] : nullptr;
            }
        }
    }
    if (at != s.size()) bad();
}

}  // namespace gradus
