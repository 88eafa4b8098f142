#include "integrators/gmlt/gmlt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#if defined(__x86_64__) || defined(__i386__)
#include <x86intrin.h>
#endif

#include "core/error.h"
#include "integrators/factories.h"
#include "render/state_bytes.h"
#include "samplers/rng_sampler.h"

namespace gradus {

using pmlt::MutationType;
using ShiftStatus = pmlt::Mutator::ShiftStatus;

namespace {

constexpr uint64_t kMutationTag = 0x676d6c7400000003ULL;
constexpr uint64_t kRouletteTag = 0x676d6c7400000004ULL;

ParamTable<GMLTSettings> Table() {
    using S = GMLTSettings;
    ParamTable<S> t("gmlt");
    t.append(PMLTParamTable());
    GradientParamOptions o;
    o.noFilmFilter = "is not supported by gmlt (a chain's splat lands in the pixel of its raster point, as pmlt's)";
    t.append(GradientParams(o));
    t.boolean("separated", &S::separated, true,
              "light through Dirac vertices only to the emitter (seen directly, in mirrors, through glass) goes "
              "around the reconstruction, as gpt's, gbdpt's and gvcm's (false: it is shifted and takes gradients)");
    t.boolean("statelayers", &S::stateLayers, false,
              "layers \"density\" (chain states per pixel per mutation per pixel) and \"irreversible\" "
              "(states whose shift has n = 1: the offset blocked or the shift failed)");
    return t;
}

// A cheap timestamp for the phase costs (the TSC: ~7 ns a read against
// the ~25 ns of the clock; a shift costs microseconds).
inline uint64_t Ticks() {
#if defined(__x86_64__) || defined(__i386__)
    return __rdtsc();
#else
    return uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
#endif
}
double ClockSeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Separated light: every vertex between the camera and the emitter x_{n-1}
// scatters through a Dirac lobe (none: the emitter seen directly).
bool SeparatedPath(const pmlt::Path &x) {
    const int n = x.size();
    if (n < 2) return false;
    for (int j = 1; j < n - 1; ++j)
        if (x.v[size_t(j)].type != VertexType::Surface || !x.v[size_t(j)].delta()) return false;
    return true;
}

// Luminance of the channel-wise absolute value (Eq. 11's norm of a signed spectrum).
double AbsLuminance(const Spectrum &s) { return Spectrum(std::abs(s.r), std::abs(s.g), std::abs(s.b)).y(); }

const char *ShiftStatusName(int s) {
    static const char *names[] = {"shifted", "offset blocked or black", "pattern changed", "walk failed or not reversible",
                                  "no shift for the pattern", "off the film"};
    return names[s];
}

}  // namespace

std::unique_ptr<Integrator> CreateGMLTIntegrator(const EntityDesc &d) { return std::make_unique<GMLTIntegrator>(d); }
std::vector<ParamInfo> GMLTParameters() { return Table().describe(); }

GMLTIntegrator::GMLTIntegrator(const EntityDesc &desc) : GMLTIntegrator(desc, Table().parse(desc)) {}

GMLTIntegrator::GMLTIntegrator(const EntityDesc &desc, const GMLTSettings &s)
    : PMLTIntegrator(desc, s, kMutationTag), gset_(s) {
    // Eq. 11 with alpha = 0 vanishes on paths whose gradient is 0, which the
    // chains could then never visit: the coarse primal would miss them.
    if (!(gset_.alpha > 0))
        throw Error(desc.loc, "gmlt: \"alpha\" must be positive (the target of Eq. 11 must not vanish where the "
                              "coarse primal's integrand does not)");
}

void GMLTIntegrator::preprocess(const Scene &scene, Film &film) {
    PMLTIntegrator::preprocess(scene, film);
    // The shift walks second chains whatever the manifold perturbation's weight.
    if (!mscene_) {
        mscene_ = std::make_unique<EmbreeManifoldScene>(scene);
        mset_.mscene = mscene_.get();
    }
    pmlt::MutationSettings ms = mset_;
    ms.shiftThreshold = gset_.shiftThreshold;  // near-specular vertices of the shift (Fig. 5a)
    mut_ = std::make_unique<pmlt::Mutator>(ctx_, film_, ms);
    // The chains only splat: no per-sample layers. The direct pass's G-PT
    // (PMLTIntegrator::preprocess) has added its per-sample layers; a
    // GradientFilm of the same arguments finds them (Film::addLayer by name).
    if (direct_) directFilm_.init(film, false, false, true);
    initGradients(film, false, true, false);
    separatedLayer_ = film.addLayer("gmlt.separated", LayerUse::Splats, false);
    ticks0_ = Ticks();
    clock0_ = ClockSeconds();
    if (gset_.stateLayers) {
        densityLayer_ = film.addLayer("gmlt.density");
        irreversibleLayer_ = film.addLayer("gmlt.irreversible");
    }
}

EntityDesc GMLTIntegrator::directDesc() const {
    // G-PT at maxdepth 1 (the paths the chains leave out: outsideTarget), its
    // samples in their own pixel as the chains' splats, the shift's threshold.
    EntityDesc d = PMLTIntegrator::directDesc();  // maxdepth 1 at the scene location
    d.type = "gpt";
    Param filter;
    filter.type = "string";
    filter.name = "pixelfilter";
    filter.strings = {"box"};
    d.params.add(filter);
    Param threshold;
    threshold.type = "float";
    threshold.name = "shiftthreshold";
    threshold.numbers = {double(gset_.shiftThreshold)};
    d.params.add(threshold);
    return d;
}

GMLTIntegrator::Target GMLTIntegrator::evaluate(const pmlt::State &xs, int dir, Arena &arena,
                                                pmlt::MutationStats *stats) const {
    Target t;
    // Separated light keeps Eq. 11's target (with f = alpha/4 Y(F) alone the
    // chains visited a directly seen emitter less and the image mean's sd
    // grew 2.6x: GMLTRender.LongChainsAgreeWithBdpt); only its splats differ.
    t.separated = gset_.separated && SeparatedPath(xs.x);
    const Point2i off = kNeighbourOffsets[dir];
    thread_local pmlt::State ys;  // the offset (its vectors reused: one evaluation per proposal)
    t.status = mut_->shift(xs, Point2(xs.e.pRaster.x + Float(off.x), xs.e.pRaster.y + Float(off.y)), arena, &ys,
                           &t.jacobian, stats);
    if (t.status == ShiftStatus::Shifted) {
        // f_{d}(x) = F(T_d x) |d mu(T_d x) / d mu(x)| (Eq. 7); both paths carry light: n = 1/2 (Eq. 9).
        t.offset = ys.e.F * Float(t.jacobian);
        t.n = 0.5;
    } else {
        t.jacobian = 0;  // offset blocked or shift failed: n = 1 (Eq. 9, Sec. 4.2.2)
    }
    t.diff = (t.offset - xs.e.F) * t.n;
    // Eq. 11: f(z) = ||f*(z)|| + alpha (1/4) ||f*(x)||.
    t.f = AbsLuminance(t.diff) + double(gset_.alpha) * 0.25 * double(xs.e.I);
    return t;
}

void GMLTIntegrator::prepareBootstrap(PassContext &ctx, uint64_t key) {
    // The roulette threshold: the mean candidate luminance of a pilot of the
    // bootstrap's first samples (a fixed range: thread-count independent).
    const int64_t P = std::min<int64_t>(bootstrapSampleCount(), 4096);
    std::vector<double> sum(size_t((P + 255) / 256), 0), count(sum.size(), 0);
    ctx.parallelFor(P, 256, [&](int64_t i0, int64_t i1, Worker &wk) {
        for (int64_t k = i0; k < i1; ++k) {
            forEachStrategy(key, k, wk.arena, [&](const Sample &, int, int, const ConnectSamples &, double lum) {
                sum[size_t(i0 / 256)] += lum;
                count[size_t(i0 / 256)] += 1;
            });
            wk.arena.reset();
        }
    });
    double S = 0, C = 0;
    for (size_t i = 0; i < sum.size(); ++i) S += sum[i], C += count[i];
    tau_ = C > 0 ? S / C : 0;
}

double GMLTIntegrator::candidateWeight(const Sample &smp, int64_t k, int s, int t, const ConnectSamples &cu,
                                       double lum, uint64_t key, Arena &arena) const {
    // Russian roulette on candidates below the pilot's mean luminance tau:
    // kept with probability lum / tau and weighted tau / lum (unbiased for b
    // and for the chain starts); the shift below is the bootstrap's main cost.
    double scale = 1;
    if (lum < tau_) {
        const double u = double(Hash(key ^ kRouletteTag, uint64_t(k), uint64_t(s), uint64_t(t)) >> 11) * 0x1.0p-53;
        if (u * tau_ >= lum) {
            ++nRouletteDropped_;
            return 0;
        }
        scale = tau_ / lum;
    }
    // C f(z) / I(x) re-weights the strategy's contribution C from pmlt's
    // target I to f (Eq. 11); 4 f(x, d) with one uniform d estimates the sum
    // of f over the four directions of the extended space (Eq. 8).
    ++nBootstrapShifted_;
    pmlt::State st;
    if (!strategyState(smp, s, t, cu, arena, &st)) {
        ++nBootstrapDropped_;
        return 0;
    }
    const Target tg = evaluate(st, CandidateDirection(key, k, s, t), arena);
    const double w = lum * scale * 4 * tg.f / double(st.e.I);
    return std::isfinite(w) ? w : 0;
}

int64_t GMLTIntegrator::runMutations(Chain &ch, int64_t count, pmlt::State &xs, Arena &cur, RNG &rng,
                                     SampleRecorder &rec, Worker &wk) {
    ChainWalk w(xs);
    w.dx = ch.dir;
    w.tx = evaluate(xs, w.dx, cur, &w.mst);
    ++w.shifts[int(w.tx.status)];
    if (!(w.tx.f > 0)) return 0;  // not reached: alpha > 0 and I(x) > 0
    RNGSampler u(rng);
    for (int64_t k = 0; k < count; ++k) mutate(w, u, rng, rec, cur, wk.arena);
    ch.dir = int8_t(w.dx);
    flushCounts(w.cnt, w.mst);
    for (int s = 0; s < kShiftStatuses; ++s) shiftCounts_[s] += w.shifts[s];
    nNearSpecular_ += w.mst.nearSpecularShifts;
    phases_.propose += w.ph.propose;
    phases_.shiftWalk += w.ph.shiftWalk;
    phases_.shiftJoin += w.ph.shiftJoin;
    phases_.rest += w.ph.rest;
    phases_.nWalkShifts += w.ph.nWalkShifts;
    phases_.nJoinShifts += w.ph.nJoinShifts;
    phases_.nWalkShiftFailures += w.ph.nWalkShiftFailures;
    phases_.nMutations += count;
    nSeparated_ += w.ph.nSeparated;
    return count;
}

void GMLTIntegrator::mutate(ChainWalk &w, Sampler &u, RNG &rng, SampleRecorder &rec, Arena &cur,
                            Arena &arena) const {
    // 1. A new base path by one of pmlt's mutations and a uniform direction:
    // a symmetric proposal of the direction (Sec. 4.2.1).
    const uint64_t t0 = Ticks();
    const Proposal p = proposeMutation(w.xs, rng, u, arena, &w.ys, &w.mst);
    const int dy = std::min(int(rng.uniform() * 4), 3);
    uint64_t t1 = Ticks();
    w.ph.propose += t1 - t0;
    // 2. Acceptance.
    Target ty;
    Float a = 0;
    if (p.res == pmlt::ProposalResult::Proposed && outsideTarget(w.ys)) {
        ++w.cnt.zero[p.type];  // outside the chains' target (directsamples)
    } else if (p.res == pmlt::ProposalResult::Proposed) {
        const int64_t walks = w.mst.walks, failures = w.mst.walkFailures;
        ty = evaluate(w.ys, dy, arena, &w.mst);
        w.ph.nSeparated += ty.separated;
        const uint64_t t2 = Ticks();
        if (w.mst.walks > walks) {
            w.ph.shiftWalk += t2 - t1;
            ++w.ph.nWalkShifts;
            w.ph.nWalkShiftFailures += w.mst.walkFailures - failures;
        } else {
            w.ph.shiftJoin += t2 - t1;
            ++w.ph.nJoinShifts;
        }
        t1 = t2;
        ++w.shifts[int(ty.status)];
        // Metropolis-Hastings on the extended space: pmlt's ratio is
        // I(y) T(y -> x) / (I(x) T(x -> y)); the target is f (Eq. 11).
        const double r = p.ratio * (double(w.xs.e.I) / double(w.ys.e.I)) * (ty.f / w.tx.f) *
                         SelectionRatio(*mut_, p.type, w.ys.x, weights_, p.wsum);
        a = std::isfinite(r) ? Float(std::min(1.0, r)) : 0;
    }
    w.cnt.record(p.type, p.res, a);
    // 3. Splats of y and z.
    splatState(rec, w.ys, dy, ty, a);
    splatState(rec, w.xs, w.dx, w.tx, 1 - a);
    // 4. The step, and the state layers of the chain's state after it.
    if (acceptStep(a, rng, w.xs, w.ys, cur)) {
        ++w.cnt.acc[p.type];
        w.tx = ty;
        w.dx = dy;
    }
    if (densityLayer_ >= 0) {
        rec.splat(w.xs.e.pRaster, Spectrum(1), densityLayer_);
        if (w.tx.n == 1) rec.splat(w.xs.e.pRaster, Spectrum(1), irreversibleLayer_);
    }
    arena.reset();
    w.ph.rest += Ticks() - t1;
}

void GMLTIntegrator::splatState(SampleRecorder &rec, const pmlt::State &s, int dir, const Target &t,
                                double w) const {
    // Splats of state z with weight w (expected values, as pmlt): the
    // gradient f*(z) into dx / dy by Eq. 10's extended filter (negative
    // directions land at the neighbour, sign flipped: GradientFilm), the
    // coarse primal (1/4) F(x) (Sec. 4.3), both times b w / f(z).
    if (!(w > 0)) return;
    GradientSplat g;
    g.pixel = Point2i{int(std::floor(s.e.pRaster.x)), int(std::floor(s.e.pRaster.y))};
    g.value.primal = s.e.F * 0.25;
    const Float scale = Float(expectedValueScale(w, t.f));
    if (t.separated) {
        // No gradient; the primal also to the separated layer (added after the solve).
        if (filmBounds_.inside(g.pixel) && g.value.primal.isFinite())
            rec.splat(Point2(g.pixel.x + 0.5, g.pixel.y + 0.5), g.value.primal * scale, separatedLayer_);
    } else {
        g.value.diff[dir] = t.diff;
        g.value.active[dir] = true;
    }
    gfilm_.splatLightTracing(rec, g, scale);
}

void GMLTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    rescale_ = rescale();
    // The chains' splats are without b (metropolis.h): the gradients and the
    // coarse primal by the same b; the direct pass's G-PT images (averaged
    // over its samples per pixel) added unscaled; then the reconstruction.
    GradientImages add;
    if (direct_) add = directFilm_.images(film, double(set_.directSamples));
    // The chains' separated light, times the same b (its primal is in the film's primal already).
    const Image sep = film.layerImage(separatedLayer_);
    add.width = sep.width();
    add.height = sep.height();
    if (add.separated.empty()) add.separated.assign(sep.data().size(), 0.f);
    for (size_t i = 0; i < sep.data().size(); ++i) add.separated[i] += float(sep.data()[i] * rescale_ * b_);
    finishGradients(film, stats, gset_.norm, gset_.alpha, out, rescale_ * b_, &add);
    if (densityLayer_ >= 0) {
        for (auto [idx, name] : {std::pair{densityLayer_, "density"}, std::pair{irreversibleLayer_, "irreversible"}}) {
            Image im = film.layerImage(idx);
            for (float &v : im.data()) v = float(v * rescale_);
            out->addChannels(Image::LayerRGBNames(name));
            out->setLayerRGB(name, im);
        }
    }
    WriteMetropolisMetadata(&out->metadata, name(), b_, nMutations_.load(), int64_t(chains_.size()), warning_);
    writeNormalizationMetadata(&out->metadata);
}

void GMLTIntegrator::saveCounters(std::string *s) const { PutBytes(s, tau_); }

bool GMLTIntegrator::loadCounters(const std::string &s, size_t *at) { return GetBytes(s, at, &tau_) && tau_ >= 0; }

std::string GMLTIntegrator::statistics() const {
    std::ostringstream o;
    o << "Gradient-domain MLT (alpha " << gset_.alpha << "):\n";
    int64_t total = 0;
    for (int s = 0; s < kShiftStatuses; ++s) total += shiftCounts_[s].load();
    o << "  shifts: " << total;
    if (total > 0) {
        o << " (reversible, n = 1/2: " << 100.0 * double(shiftCounts_[0].load()) / double(total) << "%)";
        for (int s = 1; s < kShiftStatuses; ++s)
            if (shiftCounts_[s].load() > 0) o << "; " << ShiftStatusName(s) << " " << shiftCounts_[s].load();
    }
    o << "\n";
    o << "  separated light (Dirac vertices only, no gradient): " << nSeparated_.load() << " proposals\n";
    o << "  shifts through near-specular vertices (roughness below shiftthreshold " << gset_.shiftThreshold
      << ", treated as specular: Fig. 5a): " << nNearSpecular_.load() << "\n";
    {
        // Thread-seconds per phase of the chains' mutations (TSC ticks at the
        // rate measured since preprocess).
        const double dt = ClockSeconds() - clock0_;
        const double perTick = dt > 0 ? dt / double(Ticks() - ticks0_) : 0;
        const int64_t M = phases_.nMutations.load(), nw = phases_.nWalkShifts.load(), nj = phases_.nJoinShifts.load();
        auto us = [&](uint64_t ticks, int64_t n) { return n > 0 ? 1e6 * double(ticks) * perTick / double(n) : 0.0; };
        const uint64_t total = phases_.propose + phases_.shiftWalk + phases_.shiftJoin + phases_.rest;
        o << "  cost per mutation (" << M << " mutations): " << us(total, M) << " us = proposal "
          << us(phases_.propose, M) << " + shift " << us(phases_.shiftWalk + phases_.shiftJoin, M)
          << " + acceptance and splats " << us(phases_.rest, M) << "\n";
        o << "  shifts of proposals: " << nw << " walked a second chain (" << us(phases_.shiftWalk, nw) << " us each, "
          << phases_.nWalkShiftFailures.load() << " walks failed or not reversible), " << nj << " joined or no walk ("
          << us(phases_.shiftJoin, nj) << " us each)\n";
    }
    o << "  bootstrap: " << nBootstrapShifted_.load() << " candidates re-weighted to f, " << nRouletteDropped_.load()
      << " left out by Russian roulette below the pilot's mean luminance " << tau_ << "\n";
    if (nBootstrapDropped_ > 0)
        o << "  bootstrap strategies whose path does not evaluate (left out of b): " << nBootstrapDropped_.load()
          << "\n";
    return withReconstructionReport(o.str() + PMLTIntegrator::statistics());
}

}  // namespace gradus
