#include "integrators/mlt/mlt.h"

#include <cstring>

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "integrators/factories.h"
#include "render/state_bytes.h"

namespace gradus {

using mlt::PrimarySampler;

std::unique_ptr<Integrator> CreateMLTIntegrator(const EntityDesc &d) { return std::make_unique<MLTIntegrator>(d); }

namespace {

constexpr uint64_t kBootstrapTag = 0x6d6c740000000001ULL;
constexpr uint64_t kChainTag = 0x6d6c740000000002ULL;
constexpr uint64_t kMutationTag = 0x6d6c740000000003ULL;
constexpr uint32_t kMLTStateMagic = 0x544c4d33;  // "3MLT" (with the running normalisation)

ParamTable<MLTSettings> Table() {
    using S = MLTSettings;
    ParamTable<S> t("mlt");
    t.maxDepth(&S::maxDepth);
    t.integer("bootstrapsamples", &S::bootstrapSamples, 100000, "bootstrap states per depth (b and the chain starts)",
              AtLeast(1));
    t.integer("bootstrapvertices", &S::bootstrapVertices, 50000000,
              "cap on the bootstrap's path vertices: deep depths get fewer states (0: no cap, pbrt-v3's bootstrap)",
              AtLeast(0));
    t.integer("chains", &S::chains, 1000, "Markov chains", AtLeast(1));
    t.integer("mutationsperpixel", &S::mutationsPerPixel, 100, "mutations per pixel when --spp is not given",
              AtLeast(1));
    t.real("largestepprobability", &S::largeStepProbability, 0.3,
           "probability of a large step (independent proposal)", Range{0, 1});
    t.real("sigma", &S::sigma, 0.01, "standard deviation of a small step in primary sample space",
           Range{1e-7, 1, "a positive deviation within the unit interval"});
    t.boolean("largestepmis", &S::largeStepMIS, false,
              "count large steps also as independent samples (Kelemen et al. 2002, balance heuristic; mlt.h)");
    t.enumeration("normalization", &S::normalization, "running", {"running", "bootstrap"},
                  "b, the image's normalisation: running = the bootstrap's estimate refined by every large step "
                  "(its seed-to-seed spread shrinks with the render); bootstrap = the bootstrap's alone (pbrt-v3)");
    t.real("normalizationsamples", &S::normalizationSamples, 0,
           "independent all-strategy samples of b per mutation besides the large steps (running normalization)",
           Range{0, 1e6, "a rate in [0, 1e6]"});
    return t;
}

// The chains' target function I: luminance of the contribution (Kelemen et
// al. 2002; pbrt-v3 Sec. 16.4.3). Non-finite contributions count as 0 (and are
// counted); so do contributions of non-positive luminance, which no chain samples.
Float Target(const Spectrum &L, bool *nonFinite) {
    if (!L.isFinite()) {
        *nonFinite = true;
        return 0;
    }
    const double y = L.y();
    return y > 0 ? y : 0;
}

}  // namespace

std::vector<ParamInfo> MLTParameters() { return Table().describe(); }

MLTIntegrator::MLTIntegrator(const EntityDesc &desc)
    : MetropolisIntegrator("mlt", kMLTStateMagic, {kBootstrapTag, kChainTag, kMutationTag}),
      set_(Table().parse(desc)),
      loc_(desc.loc) {}

void MLTIntegrator::preprocess(const Scene &scene, Film &film) {
    MetropolisIntegrator::preprocess(scene, film);
    // Path vertices name media by a one-byte index (path_vertex.h).
    if (scene.features.media && scene.media.size() > 255)
        throw Error(loc_, "mlt supports at most 255 media (the scene has " + std::to_string(scene.media.size()) + ")");
    // N_d (mlt.h: bootstrapvertices): an equal share of the vertex cap per
    // depth, a state of depth d having d + 2 vertices.
    const int64_t depths = set_.maxDepth + 1;
    perDepth_.assign(size_t(depths), set_.bootstrapSamples);
    for (int64_t d = 0; d < depths; ++d)
        if (set_.bootstrapVertices > 0) {
            const int64_t share = int64_t(set_.bootstrapVertices) / (depths * (d + 2));
            perDepth_[size_t(d)] = std::min<int64_t>(set_.bootstrapSamples, std::max<int64_t>(1, share));
        }
    rowStart_.assign(size_t(perDepth_[0]) + 1, 0);
    for (int64_t k = 0, m = depths; k < perDepth_[0]; ++k) {
        while (m > 0 && perDepth_[size_t(m - 1)] <= k) --m;  // depths with N_d > k
        rowStart_[size_t(k) + 1] = rowStart_[size_t(k)] + m;
    }
    lightSampler_ = LightSampler(scene.lights, "power", loc_);
    ctx_.init(scene, lightSampler_, MISHeuristic::Balance);
    ctx_.rrDepth = -1;  // the depth of a state is fixed: subpaths have exactly s and t vertices
    pixels_ = film.pixelBounds();
    const Point2i full = film.fullResolution();
    splatScale_ = pixels_.area() > 0 ? Float(int64_t(full.x) * full.y) / Float(pixels_.area()) : 1;
    // largestepmis: the large steps' part of the image does not scale with b
    // (mlt.h): its own splats, part of the main image.
    if (set_.largeStepMIS) {
        largeLayer_ = film.addLayer("mlt.largesteps", LayerUse::Splats, false);
        film.addSplatsToMain(largeLayer_);
    }
}

void MLTIntegrator::scaleFilm(Film &film, double b, double rescale) const {
    MetropolisIntegrator::scaleFilm(film, b, rescale);
    if (largeLayer_ >= 0) film.setSplatScale(largeLayer_, rescale);
}

Spectrum MLTIntegrator::contribution(PrimarySampler &u, int depth, Arena &arena, Point2 *pRaster) const {
    // Strategy selection (Hachisuka et al. 2014, Sec. 4; pbrt-v3 Sec. 16.4.2):
    // the first number of the connection stream picks (s, t), s + t = depth + 2,
    // with probability 1 / (depth + 2); the estimate is divided by it. Depth 0
    // has the one strategy (0, 2): bdpt does not evaluate (1, 1) either.
    u.startStream(mlt::kConnectionStream);
    int nStrategies = 1, s = 0, t = 2;
    if (depth > 0) {
        nStrategies = depth + 2;
        s = std::min(int(u.get1D() * nStrategies), nStrategies - 1);
        t = nStrategies - s;
    }
    ConnectSamples cu;
    if (s == 1) {
        cu.uLightSelect = u.get1D();
        cu.uLight = u.get2D();
    }
    if (t == 1) cu.uLens = u.get2D();
    const int64_t connectAt = u.streamPosition();  // the transmittances continue the stream from here
    // Media (pbrt-v3's MLT): distances, delta and ratio tracking draw from the
    // primary samples of the stream in use, interleaved with the subpath's and
    // the connection's own numbers, so that small steps perturb them too.
    const UniformSource media = ctx_.scene->features.media ? UniformSource(u) : UniformSource();

    const int maxCam = set_.maxDepth + 2, maxLight = set_.maxDepth + 1;
    PathVertex *camV, *lightV;
    BSDF *camB, *lightB;
    AllocSubpath(arena, maxCam, &camV, &camB);
    AllocSubpath(arena, maxLight, &lightV, &lightB);

    // Camera stream: film position over the pixel bounds, lens, then the subpath.
    int nC = 1;
    Float w = 1;
    Point2 pFilm;
    if (t >= 2) {
        u.startStream(mlt::kCameraStream);
        Point2 uf = u.get2D();
        CameraSample cs;
        cs.pFilm = Point2(pixels_.pMin.x + uf.x * pixels_.width(), pixels_.pMin.y + uf.y * pixels_.height());
        cs.pLens = u.get2D();
        Ray ray;
        w = ctx_.camera->generateRay(cs, &ray);
        if (w == 0) return Spectrum(0);
        nC = GenerateCameraSubpath(ctx_, ray, u, arena, t, camV, camB, media);
        if (nC != t) return Spectrum(0);
        pFilm = cs.pFilm;
    } else {
        // t = 1 samples its lens point in the connection; the vertex is a placeholder.
        camV[0] = PathVertex();
        camV[0].type = VertexType::Camera;
    }
    // Light stream (s >= 2; s = 1 samples its light point in the connection).
    int nL = 0;
    if (s >= 2) {
        u.startStream(mlt::kLightStream);
        nL = GenerateLightSubpath(ctx_, u, arena, s, lightV, lightB, media);
        if (nL != s) return Spectrum(0);
    }
    u.startStream(mlt::kConnectionStream, connectAt);
    cu.rng = media;
    ConnectResult r;
    if (!ConnectBDPT(ctx_, SubpathView{lightV, lightB, nL}, SubpathView{camV, camB, nC}, s, t, cu, &r))
        return Spectrum(0);
    const Spectrum L = r.L * Float(nStrategies);
    if (r.splat) {
        *pRaster = r.pRaster;
        return L * splatScale_;
    }
    *pRaster = pFilm;
    return L * w;
}

double MLTIntegrator::allStrategies(PrimarySampler &u, int depth, Arena &arena) const {
    // Every (s, t) with s + t = depth + 2 on one camera subpath of depth + 2
    // vertices and one light subpath of depth + 1, each strategy on their
    // prefixes as bdpt does (its MIS weights need only the prefix). I of the
    // state that selects (s, t) is Target(nStrategies L_st); the mean over
    // the selection is sum_st Target(L_st) (Target is positively homogeneous),
    // so the sum below has the mean of I: b_d (mlt.h, normalizationsamples).
    const UniformSource media = ctx_.scene->features.media ? UniformSource(u) : UniformSource();
    const int maxCam = depth + 2, maxLight = depth + 1;
    PathVertex *camV, *lightV;
    BSDF *camB, *lightB;
    AllocSubpath(arena, maxCam, &camV, &camB);
    AllocSubpath(arena, maxLight, &lightV, &lightB);
    u.startStream(mlt::kCameraStream);
    CameraSample cs;
    const Point2 uf = u.get2D();
    cs.pFilm = Point2(pixels_.pMin.x + uf.x * pixels_.width(), pixels_.pMin.y + uf.y * pixels_.height());
    cs.pLens = u.get2D();
    Ray ray;
    const Float w = ctx_.camera->generateRay(cs, &ray);
    const int nC = w > 0 ? GenerateCameraSubpath(ctx_, ray, u, arena, maxCam, camV, camB, media) : 0;
    u.startStream(mlt::kLightStream);
    const int nL = depth > 0 ? GenerateLightSubpath(ctx_, u, arena, maxLight, lightV, lightB, media) : 0;
    u.startStream(mlt::kConnectionStream);
    double sum = 0;
    bool nonFinite = false;
    for (int s = 0; s <= depth + 1; ++s) {
        const int t = depth + 2 - s;
        if (depth == 0 && s > 0) break;  // depth 0: (0, 2) alone, as contribution()
        if (s > nL || (t >= 2 && t > nC)) continue;
        ConnectSamples cu;
        if (s == 1) {
            cu.uLightSelect = u.get1D();
            cu.uLight = u.get2D();
        }
        if (t == 1) cu.uLens = u.get2D();
        cu.rng = media;
        SubpathView cam{camV, camB, t >= 2 ? t : 1};
        if (t == 1) {
            // t = 1 samples its lens point in the connection: a placeholder
            // camera vertex, as contribution() passes.
            PathVertex *v0 = arena.make<PathVertex>();
            v0->type = VertexType::Camera;
            cam = SubpathView{v0, camB, 1};
        }
        ConnectResult r;
        if (!ConnectBDPT(ctx_, SubpathView{lightV, lightB, s}, cam, s, t, cu, &r)) continue;
        sum += Target(r.L * (r.splat ? splatScale_ : w), &nonFinite);  // non-finite: 0, as I
    }
    return sum;
}

double MLTIntegrator::independentSample(uint64_t key, int64_t n, int64_t c, Worker &wk) {
    PrimarySampler u(set_.sigma, set_.largeStepProbability);
    RNG rng(Hash(key, uint64_t(n)));
    u.restart(&rng);
    return allStrategies(u, chains_[size_t(c)].depth, wk.arena);
}

// ---------------------------------------------------------------- bootstrap and chain starts
int64_t MLTIntegrator::rowOf(int64_t i) const {
    return int64_t(std::upper_bound(rowStart_.begin(), rowStart_.end(), i) - rowStart_.begin()) - 1;
}

std::vector<double> MLTIntegrator::evaluateBootstrap(PassContext &ctx, uint64_t key) {
    // State (d, k) draws its numbers from key (seed, k x depths + d), its
    // index when every depth has the same N_d.
    const int64_t n = rowStart_.back();
    std::vector<double> I(size_t(n), 0.0);
    std::atomic<uint64_t> bad{0};
    ctx.parallelFor(n, 1024, [&](int64_t i0, int64_t i1, Worker &wk) {
        PrimarySampler u(set_.sigma, set_.largeStepProbability);
        uint64_t nonFinite = 0;
        int64_t k = rowOf(i0);
        for (int64_t i = i0; i < i1; ++i) {
            while (i >= rowStart_[size_t(k) + 1]) ++k;
            const int64_t d = i - rowStart_[size_t(k)];
            RNG rng(Hash(key, stateKey(d, k)));
            u.restart(&rng);
            Point2 p;
            bool nf = false;
            I[size_t(i)] = Target(contribution(u, int(d), wk.arena, &p), &nf);
            nonFinite += nf;
            wk.arena.reset();
        }
        bad += nonFinite;
    });
    ctx.addNonFinite(bad);
    nNonFinite_ += int64_t(bad.load());
    return I;
}

MetropolisIntegrator::BootstrapWeights MLTIntegrator::weighBootstrap(PassContext &ctx, uint64_t key) {
    bootstrapI_ = evaluateBootstrap(ctx, key);
    // b: the integral of I over all depths and primary sample space, estimated
    // by N_d uniform states per depth, b = sum_d (1 / N_d) sum_k I_dk (pbrt-v3
    // Sec. 16.4.5 with N_d = bootstrapsamples: the image is b / (mutations per
    // pixel) times the summed splats of L / I; Metropolis estimates of
    // integrals, Sec. 13.4.5). State (d, k) weighs I_dk / N_d.
    const int64_t depths = set_.maxDepth + 1;
    BootstrapWeights w;
    w.weights.resize(bootstrapI_.size());
    nBootstrapNonZero_ = 0;
    // The running b's strata: per depth the sum of I and N_d (metropolis.h).
    w.strata.assign(size_t(depths), RunningSum());
    for (int64_t d = 0; d < depths; ++d) w.strata[size_t(d)].count = double(perDepth_[size_t(d)]);
    std::vector<double> invN(static_cast<size_t>(depths));
    for (int64_t d = 0; d < depths; ++d) invN[size_t(d)] = 1.0 / double(perDepth_[size_t(d)]);
    bDepth_.assign(size_t(depths), 0.0);
    for (int64_t k = 0; k + 1 < int64_t(rowStart_.size()); ++k)
        for (int64_t i = rowStart_[size_t(k)]; i < rowStart_[size_t(k) + 1]; ++i) {
            const size_t d = size_t(i - rowStart_[size_t(k)]);
            w.weights[size_t(i)] = bootstrapI_[size_t(i)] * invN[d];
            bDepth_[d] += bootstrapI_[size_t(i)] * invN[d];
            w.strata[d].sum += bootstrapI_[size_t(i)];
            nBootstrapNonZero_ += bootstrapI_[size_t(i)] > 0;
        }
    return w;
}

std::string MLTIntegrator::emptyBootstrapWarning() const {
    return "mlt: none of the " + std::to_string(rowStart_.back()) +
           " bootstrap paths carries light (b = 0); no chains run and the image is black "
           "(raise \"bootstrapsamples\" if the light is hard to reach)";
}

bool MLTIntegrator::allocateChains(uint64_t n) {
    if (n != uint64_t(set_.chains) && n != 0) return false;
    chains_.clear();
    chains_.reserve(size_t(n));
    for (uint64_t c = 0; c < n; ++c) chains_.emplace_back(PrimarySampler(set_.sigma, set_.largeStepProbability));
    return true;
}

int64_t MLTIntegrator::startChain(int64_t c, RNG &pick, uint64_t key, Worker &wk) {
    // Chain starts: bootstrap state (d, k) with probability (I_dk / N_d) / b.
    // With b from the same samples, E[b g(X_0)] = sum_d (1 / N_d) sum_k E[I_dk g(x_dk)]
    // = the integral of I g for any g, and every later state keeps that (the
    // kernel leaves I invariant): no start-up bias (pbrt-v3 Secs. 13.4.3, 16.4.5).
    const int64_t k = drawCandidate(pick);
    Chain &ch = chains_[size_t(c)];
    const int64_t row = rowOf(k), d = k - rowStart_[size_t(row)];
    RNG rng(Hash(key, stateKey(d, row)));
    ch.u.restart(&rng);
    ch.depth = int(d);
    bool nf = false;
    ch.L = contribution(ch.u, ch.depth, wk.arena, &ch.pRaster);
    ch.I = Target(ch.L, &nf);
    ch.u.setRNG(nullptr);
    wk.arena.reset();
    // The re-evaluated start must be the bootstrap state itself.
    return ch.I != bootstrapI_[size_t(k)] ? 1 : 0;
}

// ---------------------------------------------------------------- checkpoints
// After the driver's framing: the counters, N_d's b_d, the warning; per
// chain its depth, contribution, luminance, raster position and sampler.
void MLTIntegrator::saveCounters(std::string *s) const {
    for (const auto *c : {&nSmall_, &nLarge_, &nSmallAccepted_, &nLargeAccepted_, &nZeroProposals_, &nNonFinite_,
                          &nStartMismatch_})
        PutBytes(s, int64_t(c->load()));
    PutBytes(s, nBootstrapNonZero_);
    PutBytes(s, uint64_t(bDepth_.size()));
    for (double v : bDepth_) PutBytes(s, v);
    PutBytes(s, uint64_t(warning_.size()));
    *s += warning_;
}

bool MLTIntegrator::loadCounters(const std::string &s, size_t *at) {
    for (auto *c : {&nSmall_, &nLarge_, &nSmallAccepted_, &nLargeAccepted_, &nZeroProposals_, &nNonFinite_,
                    &nStartMismatch_}) {
        int64_t v;
        if (!GetBytes(s, at, &v)) return false;
        c->store(v);
    }
    uint64_t n = 0;
    if (!GetBytes(s, at, &nBootstrapNonZero_) || !GetBytes(s, at, &n) || n > uint64_t(set_.maxDepth) + 1)
        return false;
    bDepth_.assign(size_t(n), 0.0);
    for (double &v : bDepth_)
        if (!GetBytes(s, at, &v)) return false;
    if (!GetBytes(s, at, &n) || n > s.size() - *at) return false;
    warning_ = s.substr(*at, n);
    *at += n;
    return true;
}

void MLTIntegrator::saveChain(int64_t c, std::string *s) const {
    const Chain &ch = chains_[size_t(c)];
    PutBytes(s, int32_t(ch.depth));
    PutBytes(s, ch.L);
    PutBytes(s, ch.I);
    PutBytes(s, ch.pRaster);
    ch.u.save(s);
}

bool MLTIntegrator::loadChain(int64_t c, const std::string &s, size_t *at) {
    Chain &ch = chains_[size_t(c)];
    int32_t depth;
    if (!GetBytes(s, at, &depth) || !GetBytes(s, at, &ch.L) || !GetBytes(s, at, &ch.I) ||
        !GetBytes(s, at, &ch.pRaster) || !ch.u.load(s, at))
        return false;
    if (depth < 0 || depth > set_.maxDepth) return false;  // chainsPerDepth() indexes by it
    ch.depth = depth;
    return true;
}

// ---------------------------------------------------------------- mutations
void MLTIntegrator::beginChains(PassContext &) {
    // largestepmis (mlt.h): the large steps' density per mutation at each depth,
    // q_d = largestepprobability x b_d / b, b_d / b being the probability that a
    // chain starts at depth d. The large steps' own estimate is normalised by
    // their realised count, M x largestepprobability x (chains at d) / chains.
    if (chains_.empty()) return;
    const double b = b0_;
    const int64_t nChains = int64_t(chains_.size());
    qLarge_.assign(size_t(set_.maxDepth) + 1, 0.0);
    largeNorm_.assign(qLarge_.size(), 0.0);
    if (set_.largeStepMIS) {
        const std::vector<int64_t> perDepth = chainsPerDepth();
        for (size_t d = 0; d < qLarge_.size() && d < bDepth_.size(); ++d) {
            qLarge_[d] = double(set_.largeStepProbability) * bDepth_[d] / b;
            if (perDepth[d] > 0)
                largeNorm_[d] = double(nChains) / (double(set_.largeStepProbability) * double(perDepth[d]));
        }
    }
}

int64_t MLTIntegrator::mutateChain(PassContext &ctx, int64_t i, int64_t count, RNG &rng, SampleRecorder &rec,
                                   Worker &wk) {
    Chain &c = chains_[size_t(i)];
    if (!(c.I > 0)) return 0;
    c.u.setRNG(&rng);
    StepCounts n;
    // The large steps are uniform states of the chain's depth: independent
    // samples of b_d (Kelemen et al. 2002; the running normalisation).
    RunningSum &large = independentSum(i);
    for (int64_t k = 0; k < count; ++k) mutate(c, rng, rec, wk.arena, &n, &large);
    c.u.setRNG(nullptr);
    nSmall_ += n.small;
    nLarge_ += n.large;
    nSmallAccepted_ += n.smallAccepted;
    nLargeAccepted_ += n.largeAccepted;
    nZeroProposals_ += n.zero;
    nNonFinite_ += n.nonFinite;
    ctx.addNonFinite(uint64_t(n.nonFinite));
    return count;
}

void MLTIntegrator::mutate(Chain &c, RNG &rng, SampleRecorder &rec, Arena &arena, StepCounts *n,
                           RunningSum *large) const {
    // 1. Proposal y (a small or large step of u) and its contribution.
    c.u.propose();
    const bool isLarge = c.u.largeStep();
    Point2 pY;
    const Spectrum LY = contribution(c.u, c.depth, arena, &pY);
    arena.reset();
    bool nf = false;
    const Float IY = Target(LY, &nf);
    n->nonFinite += nf;
    n->zero += IY == 0;
    if (isLarge) {
        large->sum += IY;
        large->count += 1;
    }
    // 2. Acceptance: Metropolis-Hastings a = min(1, I(y) T(y->x) / (I(x) T(x->y)))
    // (pbrt-v3 Sec. 13.4.1) with Kelemen et al.'s symmetric small and large
    // steps, T(x->y) = T(y->x): a = min(1, I(y) / I(x)). I(x) > 0 for every
    // chain state, and a zero or non-finite proposal has a = 0: no 0/0.
    const Float a = IY > 0 ? std::min<Float>(1, IY / c.I) : 0;
    // 3. Splats of y and x.
    splatMutation(c, LY, IY, pY, a, isLarge, rec);
    // 4. The step.
    (isLarge ? n->large : n->small) += 1;
    if (rng.uniform() < a) {
        c.u.accept();
        c.L = LY;
        c.I = IY;
        c.pRaster = pY;
        (isLarge ? n->largeAccepted : n->smallAccepted) += 1;
    } else {
        c.u.reject();
    }
}

void MLTIntegrator::splatMutation(const Chain &c, const Spectrum &LY, Float IY, Point2 pY, Float a, bool isLarge,
                                  SampleRecorder &rec) const {
    // Expected values (Veach and Guibas 1997, "use of expected values";
    // pbrt-v3 Sec. 13.4.1): the proposal y with weight a and the current
    // state x with 1 - a, each as b L / I (pbrt-v3 Sec. 16.4.5).
    if (set_.largeStepMIS) {
        // Kelemen et al. 2002, Sec. 4: balance heuristic of the chain (density
        // I / b) and the large steps (density q_d), weights w_c = (I/b) / (I/b + q_d)
        // and w_l = q_d / (I/b + q_d), with the bootstrap's b and b_d (a fixed
        // partition of unity). Chain states keep pbrt-v3's estimate b L / I
        // times w_c (expected values as below): L w_c / I = L / (I + b q_d) to
        // the main splats, which the film scales by the current b; a large step
        // adds L w_l / (its density per mutation at this depth, 1 / largeNorm),
        // which does not scale with b: to the large steps' layer.
        const double b = b0_;
        const size_t d = size_t(c.depth);
        const double q = qLarge_[d];
        if (IY > 0) {
            if (a > 0) rec.splat(pY, LY * Float(a / (IY + b * q)));
            if (isLarge) rec.splat(pY, LY * Float(largeNorm_[d] * q / (IY / b + q)), largeLayer_);
        }
        if (a < 1) rec.splat(c.pRaster, c.L * Float((1 - a) / (c.I + b * q)));
    } else {
        if (a > 0) rec.splat(pY, LY * expectedValueScale(a, IY));
        if (a < 1) rec.splat(c.pRaster, c.L * expectedValueScale(1 - a, c.I));
    }
}

void MLTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    // The film divides by the samples per pixel of the passes run; an
    // interrupt can skip chains of the last pass: scale by issued / performed.
    MetropolisIntegrator::finish(film, stats, out);
    out->metadata["mlt_bootstrap_nonzero"] = MetaValue::Int(nBootstrapNonZero_);
}

std::vector<int64_t> MLTIntegrator::chainsPerDepth() const {
    std::vector<int64_t> n(size_t(set_.maxDepth) + 1, 0);
    for (const Chain &c : chains_) ++n[size_t(c.depth)];
    return n;
}

std::string MLTIntegrator::statistics() const {
    auto rate = [](int64_t acc, int64_t n) {
        std::ostringstream o;
        if (n > 0)
            o << 100.0 * double(acc) / double(n) << "%";
        else
            o << "-";
        return o.str();
    };
    const int64_t depths = set_.maxDepth + 1;
    std::ostringstream o;
    o << "MLT:\n";
    int64_t firstCut = -1;
    for (size_t d = 0; d < perDepth_.size() && firstCut < 0; ++d)
        if (perDepth_[d] < set_.bootstrapSamples) firstCut = int64_t(d);
    o << "  bootstrap: " << (rowStart_.empty() ? 0 : rowStart_.back()) << " states (" << set_.bootstrapSamples
      << " per depth";
    if (firstCut >= 0)
        o << "; bootstrapvertices " << set_.bootstrapVertices << " gives " << perDepth_[size_t(firstCut)]
          << " at depth " << firstCut << " down to " << perDepth_.back() << " at depth " << depths - 1;
    o << "; " << nBootstrapNonZero_ << " carry light), b = " << b0_ << "\n";
    o << "  chains: " << chains_.size() << "; mutations: " << nMutations_ << "\n";
    if (!chains_.empty()) {
        o << "  chains per depth:";
        const std::vector<int64_t> n = chainsPerDepth();
        for (size_t d = 0; d < n.size(); ++d)
            if (n[d] > 0) o << " " << d << ":" << n[d];
        o << "\n";
    }
    o << "  acceptance: small steps " << rate(nSmallAccepted_, nSmall_) << " of " << nSmall_ << ", large steps "
      << rate(nLargeAccepted_, nLarge_) << " of " << nLarge_ << ", all "
      << rate(nSmallAccepted_ + nLargeAccepted_, nSmall_ + nLarge_) << "\n";
    o << "  proposals without contribution: " << nZeroProposals_ << "; non-finite contributions (rejected): "
      << nNonFinite_ << "\n";
    if (nStartMismatch_ > 0) o << "  chain starts differing from their bootstrap state: " << nStartMismatch_ << "\n";
    return o.str() + driverStatistics();
}

}  // namespace gradus
