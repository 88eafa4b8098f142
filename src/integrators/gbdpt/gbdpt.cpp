#include "integrators/gbdpt/gbdpt.h"

#include <tbb/enumerable_thread_specific.h>

#include <cstdio>

#include "core/error.h"
#include "integrators/factories.h"

namespace gradus {

std::unique_ptr<Integrator> CreateGBDPTIntegrator(const EntityDesc &d) { return std::make_unique<GBDPTIntegrator>(d); }

namespace {
// Why a gradient sample fell back to a zero offset with the base's BDPT weight.
enum Fallback {
    FallbackShift,         // the camera-subpath shift failed at or before the connection vertex
    FallbackOffsetZero,    // the offset's connection is occluded or carries nothing
    FallbackLightTracing,  // the light-tracing-path shift failed (case iii)
    NumFallbacks
};
const char *const kFallbackNames[NumFallbacks] = {"camera-subpath shift failed before the connection",
                                                  "offset connection occluded or black",
                                                  "light-tracing path shift failed"};
}  // namespace

struct GBDPTIntegrator::ThreadState {
    SubpathShiftStats shift;
    // By case (i), (ii), (iii): base connections, gradient samples, shifted ones.
    uint64_t cases[3] = {}, caseAttempts[3] = {}, caseSuccesses[3] = {};
    uint64_t fallbacks[NumFallbacks] = {};
    uint64_t incrementalWeights = 0;  // offset BDPT weights from the base's MISSplit (O(1))
};
struct GBDPTIntegrator::Store {
    tbb::enumerable_thread_specific<ThreadState> threads;
};

GBDPTIntegrator::~GBDPTIntegrator() = default;

GBDPTIntegrator::ThreadState &GBDPTIntegrator::local() const {
    return store_->threads.local();
}

ParamTable<GBDPTSettings> GBDPTParamTable() {
    using S = GBDPTSettings;
    ParamTable<S> t("gbdpt");
    BidirParamOptions b;
    b.strategyLayers = false;  // Eq. 8 uses the balance heuristic
    t.append(BidirParams(b));  // rrdepth 3 as bdpt: offsets reuse the base's roulette (camera_shift.cpp)
    t.append(GradientParams());  // pixelfilter film (the scene's filter, as bdpt) or box
    t.enumeration<bool>("shift", &S::manifold, "manifold", {{"manifold", true}, {"halfvector", false}},
                        "camera subpath shift: manifold walk (Sec. 3.1) or half-vector copy (Kettunen et al. 2015)");
    // Default by bench/manifold/RESULTS.md: on every harvested scene Newton's
    // successes are within a point of Ceres', with fewer traces, 1.8-8x fewer
    // iteration caps and 5-35% less time per walk.
    t.enumeration<ManifoldSolver>("manifoldsolver", &S::solver, "newton",
                                  {{"ceres", ManifoldSolver::CeresTiny}, {"newton", ManifoldSolver::Newton}},
                                  "solver of the manifold walks: ceres::TinySolver (Levenberg-Marquardt) or the "
                                  "direct Newton walk (the same residual and Jacobian)");
    t.boolean("lighttracing", &S::lightTracing, true,
              "false: no light-tracing paths, in no MIS weight either (Table 1 \"w/o LTP\")");
    t.enumeration<S::MIS>("mis", &S::mis, "combined", {{"combined", S::GBDPTSettings::MIS::Combined}, {"simple", S::MIS::Simple}},
                          "gradient MIS: combined (Eq. 8) or simple (Eq. 9)");
    t.integer("separatedsamples", &S::separatedSamples, 0,
              "extra camera walks through Dirac scattering only per camera sample, for the separated light "
              "(scenes without media)",
              AtLeast(0));
    return t;
}

std::vector<ParamInfo> GBDPTParameters() { return GBDPTParamTable().describe(); }

GBDPTIntegrator::GBDPTIntegrator(const EntityDesc &desc) : GBDPTIntegrator(desc, GBDPTParamTable().parse(desc)) {}

GBDPTIntegrator::GBDPTIntegrator(const EntityDesc &desc, const GBDPTSettings &set)
    : set_(set), loc_(desc.loc), store_(new Store) {}

void GBDPTIntegrator::preprocess(const Scene &scene, Film &film) {
    ResetManifoldStats();
    scene_ = &scene;
    lightSampler_ = LightSampler(scene.lights, set_.lightStrategy, loc_);
    bctx_.init(scene, lightSampler_, MISHeuristic::Balance);  // Eq. 8 uses the balance heuristic
    // "lighttracing false": the t = 1 strategies are neither sampled nor in any MIS sum.
    bctx_.strategies.lightTracing = set_.lightTracing;
    bctx_.rrDepth = set_.rrDepth;
    mscene_ = std::make_unique<EmbreeManifoldScene>(scene);
    sctx_.bidir = &bctx_;
    sctx_.mscene = mscene_.get();
    sctx_.threshold = set_.shiftThreshold;
    sctx_.manifold = set_.manifold;
    // No specular or near-specular surface: no chain can be non-empty, no walk is attempted.
    sctx_.trySpecular = scene.features.specularSurfaces || scene.features.nearSpecularSurfaces;
    sctx_.media = scene.features.media;  // medium vertices on both subpaths (gbdpt.h "Participating media")
    // Walks converge to the default 1e-7 of the scene scale (hits are refined in
    // double). A looser 1e-5 let a round trip through a glass sphere land 1e-5 away
    // with the chain Jacobians' product 1% off 1 (tests/gbdpt invertibility).
    sctx_.walk.solver = set_.solver;
    // Light-tracing (case iii) primal and gradients are GradientFilm splats:
    // merged in tile order, so images do not depend on the thread count.
    // Camera samples go through the scene's pixel filter (pixelfilter "film",
    // as bdpt); light-tracing splats land in the pixel of their raster point,
    // exactly like bdpt's (the film does not filter splats).
    if (set_.separatedSamples > 0 && scene.features.media)
        throw Error(loc_, name() + ": \"separatedsamples\" needs a scene without media");
    initGradients(film, set_.filmFilter, connections_ && set_.lightTracing);  // no splat layers without light tracing
    splatScale_ = LightTracingSplatScale(film);
    store_->threads.clear();
}

void GBDPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    bool inside[kNumNeighbours];
    Point2i p = rec.pixel();
    // Box: only pairs of film pixels need gradients. Film filter: samples of
    // pixels around the film reach it too (targets outside are dropped).
    for (int k = 0; k < kNumNeighbours; ++k) inside[k] = set_.filmFilter || pairInside(p, k);
    std::vector<GradientSplat> splats;
    GradientSample s = sample(cs, sampler, arena, inside, &splats);
    const int K = set_.separatedSamples;
    shareSeparated(&s, K);
    gfilm_.record(rec, s);
    if (K > 0) separatedWalks(bctx_, K, set_.maxDepth, cs, sampler, arena, rec);
    // Light-tracing values are normalised like BDPT's splats (line 16).
    for (const GradientSplat &sp : splats) gfilm_.splatLightTracing(rec, sp, splatScale_);
}

namespace {
// Index of the second diffuse vertex c of the camera subpath (-1: none): a
// base path whose camera part reaches c is case (i), else case (ii).
int SecondDiffuseVertex(const SubpathShiftContext &sctx, const ShiftSubpath &cam) {
    int b = -1, c = -1;
    for (int i = 1; i < cam.n; ++i)
        if (IsDiffuseVertex(sctx, cam.v[i], &cam.b[i])) {
            if (b < 0)
                b = i;
            else {
                c = i;
                break;
            }
        }
    return c;
}
}  // namespace

// One camera sample of Algorithm 1: the subpaths, their shifts and the state
// its strategies share; each stage below is a numbered step of the algorithm.
struct GBDPTIntegrator::SampleRun {
    // A base path of strategy (s, t) (step 6).
    struct Base {
        ConnectResult r;
        LightPoint lp;
        bool useLp = false;
        MISSplit parts;
        Spectrum fx;  // unweighted contribution times the camera ray weight
        Float wx;     // BDPT weight
    };

    SampleRun(const GBDPTIntegrator &gi, const CameraSample &cs, Sampler &sampler, Arena &arena,
              const bool inside[kNumNeighbours], Float w, std::vector<GradientSplat> *splats)
        : gi(gi), set(gi.set_), sctx(gi.sctx_), bctx(gi.bctx_), ts(gi.local()), st(ts.shift), cs(cs),
          sampler(sampler), arena(arena), inside(inside), w(w), splats(splats), maxCam(set.maxDepth + 2),
          maxLight(set.maxDepth + 1), dims(AllocSubpaths(arena, maxCam, maxLight, &cam, &light, sampler)) {
        if (sctx.media) {
            // Media: distances and transmittances from a per-sample RNG (as bdpt).
            mediaRng = CameraSampleMediaRNG(sampler, cs);
            mrng = &mediaRng;
            cam.segFactor = ArenaArray<Spectrum>(arena, maxCam);
        }
    }

    // Arena storage of both subpaths, then the dimension blocks from the
    // sampler's current dimension (as bdpt).
    static BidirDimensions AllocSubpaths(Arena &arena, int maxCam, int maxLight, ShiftSubpath *cam,
                                         ShiftSubpath *light, Sampler &sampler) {
        AllocSubpath(arena, maxCam, &cam->v, &cam->b);
        AllocSubpath(arena, maxLight, &light->v, &light->b);
        cam->deltaSample = static_cast<uint8_t *>(arena.alloc(maxCam));
        light->deltaSample = static_cast<uint8_t *>(arena.alloc(maxLight));
        return BidirDimensions(sampler, maxCam, maxLight);  // fixed blocks of dimensions (bidir.h)
    }

    // [1] camera and light subpaths.
    void traceSubpaths(const Ray &ray) {
        cam.n = GenerateCameraSubpath(bctx, ray, sampler, arena, maxCam, cam.v, cam.b, mrng, cam.segFactor);
        dims.startLightSubpath(sampler);
        light.n = gi.scene_->lights.empty() || !gi.connections_
                      ? 0
                      : GenerateLightSubpath(bctx, sampler, arena, maxLight, light.v, light.b, mrng);
        PrepareSubpath(sctx, &cam);
        PrepareSubpath(sctx, &light);
        camView = cam.view();
        lightView = light.view();
    }

    // [2-5] shift the camera subpath once per neighbour (Eqs. 6 and 7).
    void shiftCameraSubpath() {
        if (cam.n >= 2)
            for (int k = 0; k < kNumNeighbours; ++k)
                if (inside[k]) ShiftCameraSubpath(sctx, cam, cs, kNeighbourOffsets[k], arena, &shifts[k], &st, mrng);
        c = SecondDiffuseVertex(sctx, cam);
        // Incremental offset weights (bidir.h MISSplit): the offsets reconnect at
        // the same vertex r (c, or the half-vector shift's first diffuse pair, a
        // function of the base), share the base's vertices from r on and its
        // densities from r + 2 on; for kc >= r + 3 an offset's BDPT weight is
        // 1 / (1 + shared + product Q_y) with the base's parts split at r + 1 and
        // the offset's prefix sum Q_y, computed once per offset.
        for (int k = 0; k < kNumNeighbours; ++k)
            if (inside[k] && shifts[k].r >= 0) rShared = shifts[k].r;
        // With merging (G-VCM) the prefix sum takes the merges at z'_1 .. z'_{r+1}
        // too, for a kernel with one eta at every vertex (SplitSupported).
        misSplit = rShared >= 0 && SplitSupported(bctx.strategies) ? rShared + 1 : -1;
        lens = cam.v[0];
        lens.setThroughput(Spectrum(1));
        lens.pdfFwd = 1;
    }

    bool diffuseAt(const ShiftSubpath &p, int i) const { return IsDiffuseVertex(sctx, p.v[i], &p.b[i]); }

    // Strategy (s, t): its connection numbers, then the base path and its shifts.
    void strategy(int s, int t, GradientSample *out) {
        int depth = s + t - 2;
        if ((s == 1 && t == 1) || depth < 0 || depth > set.maxDepth) return;
        ConnectSamples u;
        dims.startConnection(sampler, s, t);
        if (s == 1) {
            u.uLightSelect = sampler.get1D();
            u.uLight = sampler.get2D();
        }
        if (t == 1) u.uLens = sampler.get2D();
        u.rng = mrng;
        if (t == 1 && !set.lightTracing) return;  // no light-tracing paths (Table 1, "w/o LTP")
        // Sec. 3.2: no connections at vertices classified specular.
        if (s >= 1 && t >= 2 && !diffuseAt(cam, t - 1)) return;
        if (s >= 2 && !diffuseAt(light, s - 1)) return;
        if (t == 1 && !diffuseAt(light, s - 1)) return;

        Base base;
        if (!connectBase(s, t, &u, &base)) return;  // blocked or black base path: nothing to shift (Sec. 4)
        if (t == 1) {
            shiftLightTracingPath(s, base);
            return;
        }
        // [15] primal with the usual BDPT weight.
        primal += base.fx * base.wx;
        if (s == 0 && DiracCameraChain(cam, t - 2)) {
            // Separated light (DiracCameraChain): no gradients, for the base nor its offsets.
            separated += base.fx * base.wx;
            return;
        }
        const int kc = t - 1;  // last camera vertex of the base path
        const int cas = (c >= 0 && kc >= c) ? 0 : 1;
        ++ts.cases[cas];
        // [12-14] offsets from the shifted camera subpaths.
        for (int k = 0; k < kNumNeighbours; ++k) {
            if (!inside[k]) continue;
            ++ts.caseAttempts[cas];
            out->diff[k] += offsetDifference(s, t, k, u, base, cas);
        }
    }

    // [6] base path.
    bool connectBase(int s, int t, ConnectSamples *u, Base *base) {
        ConnectResult &r = base->r;
        bool ok;
        u->misSplit = misSplit;
        u->misParts = &base->parts;
        if (s == 1) {
            ok = SampleLightPoint(sctx, cam.v[t - 1], u->uLightSelect, u->uLight, &base->lp);
            if (ok && !base->lp.infinite) {
                base->useLp = true;
                ok = ConnectLightPoint(sctx, base->lp, camView, t, &r, false, misSplit, &base->parts, mrng);
            } else {
                ok = ConnectBDPT(bctx, lightView, camView, s, t, *u, &r);
            }
        } else {
            ok = ConnectBDPT(bctx, lightView, camView, s, t, *u, &r);
        }
        u->misParts = nullptr;
        if (!ok) return false;
        base->fx = r.unweighted * w;
        // BDPT weight over the strategies in play (bctx.strategies: without
        // light tracing the t = 1 terms are left out of every sum).
        base->wx = r.weight;
        return true;
    }

    // [8-11] light-tracing path (case (iii)): shifted one by one.
    void shiftLightTracingPath(int s, const Base &base) {
        const ConnectResult &r = base.r;
        const Float wx = base.wx;
        ++ts.cases[2];
        GradientSplat sp;
        GradientSample &g = sp.value;
        sp.pixel = Point2i{int(std::floor(r.pRaster.x)), int(std::floor(r.pRaster.y))};
        g.primal = r.L;
        for (int k = 0; k < kNumNeighbours; ++k) {
            if (!gi.pairInside(sp.pixel, k)) continue;
            Point2i off = kNeighbourOffsets[k];
            g.active[k] = true;
            Spectrum fy;
            Float wy = 0, rho = 0;
            ++ts.caseAttempts[2];
            bool shifted = ShiftLightTracingPath(sctx, light, s, lens, r.pRaster, r.unweighted, off, arena, &fy, &wy,
                                                 &rho, &st, mrng);
            if (shifted) {
                ++ts.caseSuccesses[2];
                Float wg = set.mis == GBDPTSettings::MIS::Combined ? CombinedWeight(wx, wy, rho) : 0.5 * wx;  // Eq. 8 / Eq. 9
                g.diff[k] = (fy - r.unweighted) * wg;
            } else {
                ++ts.fallbacks[FallbackLightTracing];
                g.diff[k] = r.unweighted * -wx;  // fallback: zero offset, BDPT weight
            }
        }
        splats->push_back(sp);
    }

    // [12-14] the difference of neighbour k's offset for base path (s, t), t >= 2.
    Spectrum offsetDifference(int s, int t, int k, const ConnectSamples &u, const Base &base, int cas) {
        const CameraShift &sh = shifts[k];
        const int kc = t - 1;
        const Spectrum &fx = base.fx;
        const Float wx = base.wx;
        ConnectResult ry;
        bool oky = false;
        // Next-event estimation of an infinite light: the offset samples the
        // light with the base's numbers, which give the same light and
        // direction from any point (the light choice is position-free):
        // the environment shift, |T'| = 1, equal light densities, so rho
        // is the camera subpath's (as for a shared light point).
        const bool envNEE = s == 1 && !base.useLp;
        if (kc > sh.validUpTo) ++ts.fallbacks[FallbackShift];
        const bool reuse = kc <= sh.validUpTo && sh.r >= 0 && kc > sh.r;
        const bool incremental = reuse && base.parts.valid && sh.r == rShared;
        if (reuse && (incremental || !envNEE)) {
            oky = reuseBaseConnection(s, t, k, base, incremental, &ry);
        } else if (kc <= sh.validUpTo) {
            SubpathView yv = sh.y.view();
            // At and after the reconnection vertex (kc >= r) the offset's
            // vertex is the base's and so is the connection edge: the
            // base's shadow ray already found it unoccluded.
            ConnectSamples uy = u;
            // With media the edge's transmittance is estimated again (knownVisible would drop it).
            uy.knownVisible = sh.r >= 0 && kc >= sh.r && !sctx.media;
            if (base.useLp)
                oky = ConnectLightPoint(sctx, base.lp, yv, t, &ry, uy.knownVisible, -1, nullptr, mrng);
            else
                oky = ConnectBDPT(bctx, lightView, yv, s, t, uy, &ry);
            oky = oky && !ry.unweighted.isBlack() && ry.weight > 0;
            if (!oky) ++ts.fallbacks[FallbackOffsetZero];
        }
        if (oky) {
            ++ts.caseSuccesses[cas];
            Spectrum fy = ry.unweighted * w;
            Float wg = set.mis == GBDPTSettings::MIS::Combined ? CombinedWeight(wx, ry.weight, sh.rho[kc]) : 0.5 * wx;
            return (fy - fx) * wg;
        }
        return fx * -wx;
    }

    // Past the reconnection the offset's connection is the base's (same
    // vertices, same light sample, same shadow ray): only the camera-side
    // throughput and the offset's MIS densities differ.
    bool reuseBaseConnection(int s, int t, int k, const Base &base, bool incremental, ConnectResult *ry) {
        const CameraShift &sh = shifts[k];
        const int kc = t - 1;
        SubpathView yv = sh.y.view();
        ry->unweighted = base.r.unweighted * SafeDiv(sh.y.v[kc].throughput(), cam.v[kc].throughput());
        if (incremental) {
            if (!havePrefix[k]) {
                prefixY[k] = CameraPrefixSum(bctx, bctx.strategies, yv, misSplit);
                havePrefix[k] = true;
            }
            ry->weight = base.parts.weight(prefixY[k]);
            ++ts.incrementalWeights;
        } else if (base.useLp) {
            PathVertex sv = base.lp.v;
            sv.pdfFwd = PdfLightOrigin(bctx, sv, sh.y.v[kc]);
            ry->weight = MISWeight(bctx, SubpathView{&sv, nullptr, 1}, yv, 1, t, &sv);
        } else {
            ry->weight = MISWeight(bctx, lightView, yv, s, t, nullptr);
        }
        return !ry->unweighted.isBlack() && ry->weight > 0;
    }

    const GBDPTIntegrator &gi;
    const GBDPTSettings &set;
    const SubpathShiftContext &sctx;
    const BidirContext &bctx;
    ThreadState &ts;
    SubpathShiftStats &st;
    const CameraSample &cs;
    Sampler &sampler;
    Arena &arena;
    const bool *inside;
    const Float w;  // camera ray weight
    std::vector<GradientSplat> *splats;
    const int maxCam, maxLight;
    ShiftSubpath cam, light;
    BidirDimensions dims;
    SubpathView camView, lightView;
    CameraShift shifts[kNumNeighbours];
    int c = -1;        // second diffuse camera vertex (case (i) from there on)
    int rShared = -1;  // reconnection vertex shared by the offsets
    int misSplit = -1;
    Float prefixY[kNumNeighbours];
    bool havePrefix[kNumNeighbours] = {};
    PathVertex lens;  // the base's lens vertex with unit throughput (light-tracing shifts)
    RNG mediaRng;
    RNG *mrng = nullptr;  // scenes with media: the sample's media RNG
    Spectrum primal = Spectrum(0);
    Spectrum separated = Spectrum(0);  // the part of primal separated from the reconstruction
};

GradientSample GBDPTIntegrator::sample(const CameraSample &cs, Sampler &sampler, Arena &arena,
                                       const bool inside[kNumNeighbours], std::vector<GradientSplat> *splats) const {
    GradientSample out;
    Ray ray;
    Float w = scene_->camera->generateRay(cs, &ray);
    if (w == 0) return out;
    for (int k = 0; k < kNumNeighbours; ++k) out.active[k] = inside[k];
    SampleRun run(*this, cs, sampler, arena, inside, w, splats);
    run.traceSubpaths(ray);
    run.shiftCameraSubpath();
    for (int t = 1; t <= (connections_ ? run.cam.n : 0); ++t)
        // s = 1 samples its own light point: it runs even with an empty light subpath (bdpt.cpp).
        for (int s = 0; s <= std::max(run.light.n, scene_->lights.empty() ? 0 : 1); ++s) run.strategy(s, t, &out);
    out.primal = run.primal;
    out.separated = run.separated;
    addStrategies(CameraState{&run.cam, run.shifts, inside, w, &arena, &sampler}, &out);
    return out;
}

void GBDPTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    finishGradients(film, stats, set_.norm, set_.alpha, out);
}

std::string GBDPTIntegrator::statistics() const {
    SubpathShiftStats tot;
    uint64_t cases[3] = {}, attempts[3] = {}, successes[3] = {}, fallbacks[NumFallbacks] = {}, incremental = 0;
    for (const ThreadState &t : store_->threads) {
        tot.add(t.shift);
        incremental += t.incrementalWeights;
        for (int i = 0; i < NumFallbacks; ++i) fallbacks[i] += t.fallbacks[i];
        for (int i = 0; i < 3; ++i) {
            cases[i] += t.cases[i];
            attempts[i] += t.caseAttempts[i];
            successes[i] += t.caseSuccesses[i];
        }
    }
    ShiftStats ss;
    ss.add(tot.shift);
    std::string s = ss.format(std::string("G-BDPT shifts (") + (set_.manifold ? "manifold" : "halfvector") +
                              (set_.manifold ? (set_.solver == ManifoldSolver::CeresTiny ? " walk, ceres" : " walk, newton") : "") +
                              ", threshold " + std::to_string(set_.shiftThreshold) + ")");
    char buf[256];
    const char *names[3] = {"(i)   camera subpath, both chains", "(ii)  camera subpath, first chain",
                            "(iii) light-tracing path"};
    for (int i = 0; i < 3; ++i) {
        std::snprintf(buf, sizeof buf, "  case %s: base paths %llu, gradient samples %llu, shifted %llu (%.2f%%)\n",
                      names[i], (unsigned long long)cases[i], (unsigned long long)attempts[i],
                      (unsigned long long)successes[i], attempts[i] ? 100.0 * successes[i] / attempts[i] : 0.0);
        s += buf;
    }
    std::snprintf(buf, sizeof buf, "  offset BDPT weights from the base's split sums (O(1), kc >= r + 3): %llu\n",
                  (unsigned long long)incremental);
    s += buf;
    s += "  fallbacks (zero offset, BDPT weight) by cause:\n";
    for (int i = 0; i < NumFallbacks; ++i) {
        std::snprintf(buf, sizeof buf, "    %-58s %llu\n", kFallbackNames[i], (unsigned long long)fallbacks[i]);
        s += buf;
    }
    s += tot.formatWalks(sctx_.trySpecular);
    s += FormatManifoldStats(GetManifoldStats(), "  ");  // every walk of the render (process-wide counters)
    if (!set_.lightTracing) s += "  light-tracing paths not shifted (lighttracing false)\n";
    return withReconstructionReport(s);
}

}  // namespace gradus
