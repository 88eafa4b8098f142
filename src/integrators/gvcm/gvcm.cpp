// G-VCM / G-PM estimator (derivation and notation in gvcm.h; equations of
// gradient-domain-vcm.md).
#include "integrators/gvcm/gvcm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/error.h"
#include "integrators/factories.h"
#include "render/params.h"
#include "samplers/rng.h"
#include "samplers/rng_sampler.h"

namespace gradus {

std::unique_ptr<Integrator> CreateGVCMIntegrator(const EntityDesc &d) { return std::make_unique<GVCMIntegrator>(d); }

namespace {

constexpr uint64_t kLightTag = 0x6776636d00000001ULL;

ParamTable<GVCMSettings> Table() {
    using S = GVCMSettings;
    ParamTable<S> t("gvcm");
    t.append(GBDPTParamTable());
    t.enumeration<bool>("mode", &S::mergeOnly, "vcm", {{"vcm", false}, {"mergeonly", true}},
                        "vcm (G-VCM) | mergeonly (G-PM: merges at the first connectable camera vertex only)");
    t.append(MergeRadiusParams());
    t.integer("case2budget", &S::case2Budget, 1,
              "case-2 shifts (through z'_b) per merge vertex and offset: K of the n photons found, chosen by "
              "systematic sampling, their differences weighted n/K (unbiased); 0: every photon",
              AtLeast(0));
    return t;
}

Float Remap(Float f) { return f != 0 ? f : Float(1); }

Float *AllocFloats(Arena &arena, int n) {
    return static_cast<Float *>(arena.alloc(sizeof(Float) * std::max(n, 1), alignof(Float)));
}

// A point at unit distance from p in direction d (for densities towards a direction).
PathVertex DirectionPoint(const Point3 &p, const Vec3 &d) {
    PathVertex v;
    v.type = VertexType::Surface;
    v.p = p + d;
    v.ng = Normal3(-d.x, -d.y, -d.z);
    v.ns = v.ng;
    return v;
}

}  // namespace

std::vector<ParamInfo> GVCMParameters() { return Table().describe(); }

GVCMIntegrator::GVCMIntegrator(const EntityDesc &desc) : GVCMIntegrator(desc, Table().parse(desc)) {}

GVCMIntegrator::GVCMIntegrator(const EntityDesc &desc, const GVCMSettings &set)
    : GBDPTIntegrator(desc, set), gset_(set) {
    connections_ = !gset_.mergeOnly;
    CheckMergeRadiusParams(desc, gset_);
}

void GVCMIntegrator::preprocess(const Scene &scene, Film &film) {
    GBDPTIntegrator::preprocess(scene, film);
    bounds_ = film.sampleBounds();
    const SceneFeatures &f = scene.features;
    merging_ = f.specularSurfaces || f.nearSpecularSurfaces || gset_.mergeOnly;
    skipped_ = merging_ ? "" : "no specular or near-specular surface: merging left out (no grid; gvcm = gbdpt)";
    radius1_ = gset_.radius > 0 ? gset_.radius : VCMFootprintRadius(scene, bounds_, gset_.radiusScale);
    GRADUS_CHECK(radius1_ > 0);
    if (merging_ && set_.maxDepth > 255) throw Error(loc_, "gvcm: maxdepth above 255 is not supported with merging");
    // Merges only at connectable vertices (Sec. 4), in the estimate and in every MIS sum,
    // with the kernel's eta per vertex (Sec. 6, merge_kernel.h).
    bctx_.strategies.merging = merging_ && connections_;
    bctx_.strategies.mergeRoughOnly = true;
    bctx_.strategies.mergeFactor = 0;
    bctx_.strategies.kernel = &kernel_;
}

void GVCMIntegrator::runPass(PassContext &ctx) {
    scene_ = &ctx.scene();
    radius_ = radiusAt(ctx.firstSample() + 1);
    kernel_ = VCMKernel(gset_, radius1_, ctx.firstSample() + 1, bounds_.area(), *scene_->camera, merging_);
    if (merging_) {
        lightPass(ctx);
        if (ctx.interrupted()) return;
        BuildLightVertexGrid(ctx, vertices_, radius_, &grid_);
        gridBytes_ = grid_.bytes();
        if (ctx.interrupted()) return;
    }
    ctx.forEachPixelSample(*this);
    ++passes_;
}

void GVCMIntegrator::regenerate(uint32_t j, int maxLight, Arena &arena, ShiftSubpath *L) const {
    // The light pass's RNG of item j (PassContext::forEachItem).
    RNG rng(Hash(lightKey_, uint64_t(lightPassIndex_), uint64_t(j)));
    RNGSampler smp(rng);
    AllocSubpath(arena, maxLight, &L->v, &L->b);
    L->deltaSample = static_cast<uint8_t *>(arena.alloc(maxLight));
    L->n = scene_->lights.empty() ? 0 : GenerateLightSubpath(bctx_, smp, arena, maxLight, L->v, L->b);
    PrepareSubpath(sctx_, L);
}

void GVCMIntegrator::lightPass(PassContext &ctx) {
    const int64_t N = bounds_.area();
    lightKey_ = ctx.seed() ^ kLightTag;
    lightPassIndex_ = ctx.pass();
    const VCMWeights weights{&kernel_, true, connections_ && set_.lightTracing, false, true};
    // Chunks gathered into vertices_ in subpath order as they merge (vcm's LightVertexGather).
    LightVertexGather gather(N, set_.maxDepth, &vertices_, &pathStart_);
    ctx.forEachItem(
        N, kLightTag,
        [&](int64_t item, RNG &, SampleRecorder &, Worker &wk) {
            ShiftSubpath L;
            regenerate(uint32_t(item), set_.maxDepth + 1, wk.arena, &L);  // the same RNG as forEachItem's (seed ^ tag, pass, item)
            gather.setCount(item, VCMLightVertices(bctx_, L.v, L.b, L.n, weights, &gather.buffer(item)));
        },
        gather.chunkMerged());
    nLightVertices_ += vertices_.size();
}

void GVCMIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    // The passes are over: the last pass's light vertices and grid are not part of the output
    // (the reconstruction would otherwise run beside them; bench/gvcm/MEMORY.md).
    std::vector<LightVertex>().swap(vertices_);
    std::vector<uint32_t>().swap(pathStart_);
    grid_ = PhotonGrid();
    GBDPTIntegrator::finish(film, stats, out);
}

// E(y_d -> dir): emission (times the emitter's cosine; a point light's
// intensity) or the BSDF times the shading cosine, and y_d's directional density.
Spectrum GVCMIntegrator::emitFrom(const ShiftSubpath &L, int d, const Vec3 &dir, Float *pdf) const {
    const PathVertex &yd = L.v[d];
    const PathVertex towards = DirectionPoint(yd.p, dir);
    if (d == 0) {
        const Light *light = EmitterOf(bctx_, yd);
        Float pdfPos = 0, pdfDir = 0;
        if (light) light->pdfLe(Ray(yd.p, dir), yd.ng, &pdfPos, &pdfDir);
        *pdf = pdfDir;
        return EmittedRadiance(bctx_, yd, towards) * (yd.isDeltaLight() ? Float(1) : AbsDot(Vec3(yd.ng), dir));
    }
    *pdf = L.b[d].pdf(Vec3(yd.wo), dir, TransportMode::Importance);
    return EvalBSDF(yd, L.b[d], towards, TransportMode::Importance) * AbsDot(Vec3(yd.ns), dir);
}

// The base's half of a case-2 offset (per photon; the four offsets share it):
// y_d, the chain y_d .. y_m and T(x) = E(y_d -> chain) G~ prod f|cos| (gvcm.h).
bool GVCMIntegrator::case2Base(const ShiftSubpath &L, int m, Arena &arena, Case2Base *cb) const {
    const Scene &scene = *scene_;
    cb->fcosX = Spectrum(1);  // no Dirac vertex (k = 0) unless the chain sets them
    cb->probX = 1;
    // y_d: the last connectable vertex before the photon (the light origin at the latest).
    int d = m - 1;
    while (d > 0 && L.v[d].delta()) --d;
    cb->d = d;
    const PathVertex &yd = L.v[d], &ym = L.v[m];
    auto fail = [&](Counter c) {
        cb->failure = c;
        return false;
    };
    if (d == 0 && yd.isInfiniteLight()) return fail(FallbackInfinite);
    const int k = m - 1 - d;  // chain interior y_{m-1} .. y_{d+1} (ideal specular)
    cb->k = k;
    for (int i = d + 1; i < m; ++i)
        if (!L.deltaSample[i]) return fail(FallbackGlossy);
    if (k + 2 > kMaxManifoldVertices) return fail(FallbackLong);
    if (k == 0) {
        // Eq. 18: y_s = y_d connectable (reconnected to z'_b per offset).
        const Vec3 dx = ym.p - yd.p;
        const Float d2x = dx.lengthSquared();
        if (!(d2x > 0)) return fail(FallbackBlocked);
        cb->dirX = dx / std::sqrt(d2x);
        cb->gX = AbsDot(Vec3(ym.ng), cb->dirX) / d2x;
    } else {
        // Eqs. 19-20: the chain y_d -> y_{d+1} .. y_{m-1} -> photon (JM12), built once.
        ChainInterior &in = cb->in;
        for (int j = 0; j < k; ++j) {
            const int i = d + 1 + j;
            const PathVertex &xv = L.v[i];
            if (!VertexInteraction(scene, xv, L.v[i - 1].p, &in.si[j])) return fail(FallbackWalk);
            in.bsdf[j] = &L.b[i];
            in.wo[j] = Normalize(L.v[i - 1].p - xv.p);  // towards y_d (the chain's start)
            in.wi[j] = Normalize(L.v[i + 1].p - xv.p);  // towards the photon
            in.transmit[j] = Transmits(in.wo[j], in.wi[j], Vec3(L.b[i].ns()));
            in.specular[j] = true;
            in.geomId[j] = xv.geomId;
        }
        // A point or spot light has no surface: any fixed normal (it cancels in G / cos_0).
        const Vec3 ngD = yd.ng.isZero() ? Normalize(L.v[d + 1].p - yd.p) : Vec3(yd.ng);
        WalkedInterior baseEval;
        if (!BuildChain(sctx_, EndpointSP(yd.p, ngD, yd.geomId), in, k, EndpointSP(ym.p, Vec3(ym.ng), ym.geomId),
                        &cb->chain) ||
            !EvaluateWalked(scene, cb->chain, ym.p, in.transmit, in.geomId, arena, TransportMode::Importance, &baseEval))
            return fail(FallbackWalk);
        cb->dirX = Normalize(cb->chain.v[1].sp.p - yd.p);
        // G~: solid angle at y_d per area at the photon end (JM12's G / cos_0).
        cb->gX = ChainSolidAnglePerArea(cb->chain);
        cb->fcosX = baseEval.factor;
        cb->probX = baseEval.prob;
    }
    if (!(cb->gX > 0)) return fail(FallbackWalk);
    cb->tX = emitFrom(L, d, cb->dirX, &cb->pX) * cb->fcosX * cb->gX;
    if (cb->tX.isBlack() || !(cb->pX > 0)) return fail(FallbackBlocked);
    cb->failure = NumCounters;
    return true;
}

bool GVCMIntegrator::case2(const ShiftSubpath &L, const Case2Base &cb, const CameraShift &sh, int u,
                           const LightVertex &lv, const VCMCameraTerms *terms, Float etaX, Arena &arena,
                           Offset *o) const {
    const Scene &scene = *scene_;
    const PathVertex &zo = sh.y.v[u];
    const BSDF &bo = sh.y.b[u];
    const int d = cb.d, k = cb.k;
    const PathVertex &yd = L.v[d];
    if (cb.failure != NumCounters) {
        if (cb.failure != FallbackInfinite && cb.failure != FallbackGlossy && cb.failure != FallbackLong)
            count(k == 0 ? Case2Empty : Case2Chain);
        count(cb.failure);
        return false;
    }
    // The offset's direction at y_d, its photon-side cosine and G~, the chain's Dirac factors.
    Vec3 dirY, wiY;  // wiY: at z'_b towards the chain (or y_d)
    Float gY;
    Spectrum fcosY(1);
    Float probY = 1;
    std::optional<WalkedInterior> walkedY;  // the offset chain's interior y'_{d+1} .. y'_{m-1} (k > 0)
    if (k == 0) {
        count(Case2Empty);
        // Eq. 18: y_s = y_d connectable, reconnected to z'_b.
        const Vec3 dy = zo.p - yd.p;
        const Float d2y = dy.lengthSquared();
        if (!(d2y > 0) || !EdgeConnectible(bctx_, yd, zo)) {
            count(FallbackBlocked);
            return false;
        }
        dirY = dy / std::sqrt(d2y);
        wiY = -dirY;
        gY = AbsDot(Vec3(zo.ng), dirY) / d2y;
        if (!(gY > 0) || !scene.unoccluded(AsInteraction(yd), AsInteraction(zo))) {
            count(FallbackBlocked);
            return false;
        }
    } else {
        count(Case2Chain);
        // Eqs. 19-20: the base chain walked so that its end moves to z'_b with y_d
        // and the half-vectors fixed (JM12; the walk's rays start at y_d and end on
        // z'_b's surface), the reversibility test of Sec. 4 (the walk may find
        // another solution), the offset interior evaluated and its classes kept.
        ManifoldWalkResult res;
        WalkedInterior &walked = walkedY.emplace();
        const ChainShiftFailure failure =
            ShiftChain(sctx_, scene, cb.chain, cb.chain.front().sp, EndpointSP(zo.p, Vec3(zo.ng), zo.geomId), cb.in,
                       TransportMode::Importance, arena, &res, &walked);
        walkStatus_[size_t(res.status)].fetch_add(1, std::memory_order_relaxed);
        if (failure != ChainShiftFailure::None) {
            count(FallbackWalk);
            return false;
        }
        const ManifoldChain &off = res.chain;
        dirY = Normalize(off.v[1].sp.p - yd.p);
        wiY = Normalize(off.v[k].sp.p - zo.p);
        gY = ChainSolidAnglePerArea(off);
        fcosY = walked.factor;
        probY = walked.prob;
    }
    if (!(gY > 0)) {
        count(FallbackWalk);
        return false;
    }
    Float pY;
    const Spectrum tY = emitFrom(L, d, dirY, &pY) * fcosY * gY;
    const Spectrum fz = bo.f(Vec3(zo.wo), wiY, TransportMode::Radiance);
    // f(x')/p'(x*) = beta_L(y_m) T(x')/T(x) f(z'_b) beta'_C / eta (gvcm.h; Eqs. 18-19), eta
    // the base's kernel at z_b.
    o->f = lv.throughput() * SafeDiv(tY, cb.tX) * fz * zo.throughput() / etaX;
    if (o->f.isBlack() || !(pY > 0)) {
        count(FallbackBlocked);
        return false;
    }
    // rho: the camera shift's, times the photon's area density ratio p_omega G~ prod prob
    // (and, with connections, the kernels' ratio: each merge's density with its own eta, Eqs. 22-23).
    o->rho = sh.rho[u] * (pY * gY * probY) / (cb.pX * cb.gX * cb.probX);
    if (terms) o->rho *= terms->etaU / etaX;
    o->w = 1;
    if (terms) o->w = case2Weight(L, d, k, walkedY ? &*walkedY : nullptr, pY, sh, u, arena);
    return true;
}

// w_y of a case-2 offset: Eq. 13 on the offset path itself, y_0 .. y_d, the
// walked y'_{d+1} .. y'_{m-1}, z'_u .. z'_0, with the offset's own kernel (Eq.
// 22), by the O(m + u) sums of MergeWeight. The offset changes the light
// side's densities from y_{d-1} on (the direction at y_d and every vertex
// after it), so the light pass's recursive B_m does not apply; with the
// budget's one case-2 offset per merge vertex this costs less than the walk.
Float GVCMIntegrator::case2Weight(const ShiftSubpath &L, int d, int k, const WalkedInterior *walked, Float pY,
                                  const CameraShift &sh, int u, Arena &arena) const {
    const int m = d + k + 1;  // light vertices y_0 .. y'_{m-1}; the merge's photon lands at z'_u
    PathVertex *P = ArenaArray<PathVertex>(arena, m);
    BSDF *PB = ArenaArray<BSDF>(arena, m);
    for (int i = 0; i <= d; ++i) P[i] = L.v[i], PB[i] = L.b[i];
    for (int j = 0; j < k; ++j) {
        // The base's vertex record (flags, medium, material) at the walked position; Dirac
        // densities 0, as GenerateLightSubpath stores them after and before a specular vertex.
        PathVertex &v = P[d + 1 + j];
        v = L.v[d + 1 + j];
        v.p = walked->si[j].p;
        v.ng = walked->si[j].n;
        v.ns = walked->bsdf[j].ns();
        v.wo = walked->si[j].wo;
        v.pdfFwd = v.pdfRev = 0;
        PB[d + 1 + j] = walked->bsdf[j];
    }
    if (k > 0) {
        // y'_{d+1} sampled from y_d along dirY (its directional density pY); y_d's own
        // reverse density is 0 (sampled from the Dirac y'_{d+1}), y_{d-1}'s from y_d
        // given the offset's direction. (With k = 0 both are the junction's: MergeWeight's.)
        P[d + 1].pdfFwd = ConvertDensity(pY, P[d], P[d + 1]);
        P[d].pdfRev = 0;
        if (d >= 1)
            P[d - 1].pdfRev = PdfArea(bctx_, P[d], &PB[d], &P[d + 1], P[d - 1], TransportMode::Radiance);
    }
    return MergeWeight(bctx_, bctx_.strategies, SubpathView{P, PB, m}, SubpathView{sh.y.v, sh.y.b, u + 1}, m, u + 1);
}

Float GVCMIntegrator::mergeWeight(const VCMCameraTerms &t, const PathVertex &z, const PathVertex &zPrev,
                                  const BSDF &bz, const LightVertex &lv, const VCMWeights &W) {
    // w_VM = eta_u o(z_u) / (c + S_L(m-1) + S_C(u)) (vcm.h; S_L's junction eta_u sigma(z_u)).
    const Vec3 wi = lv.wo;  // towards y_{m-1}
    const Float oz = Remap(lv.pdfFwd);
    const Float cRef = VCMPrevConnectible(lv) ? 1 : 0;  // the connection of y_{m-1} and z_u
    const Float om1 = bz.pdf(Vec3(z.wo), wi, TransportMode::Radiance) * lv.prevGeom;
    const Float oPrev = ConvertDensity(bz.pdf(wi, Vec3(z.wo), TransportMode::Importance), z, zPrev);
    return t.etaU * oz / (cRef + VCMLightPrevSum(lv, om1, t.H, W) + VCMCameraSum(t, oz, oPrev, true, false, W));
}

// One camera sample's merges: the base's eta_u and B_u, the offsets' (their
// own kernels, for their weights) when a merge first needs them.
struct GVCMIntegrator::SampleMerges {
    const CameraState &st;
    const VCMWeights W;
    Float *etaX = nullptr, *Bx = nullptr;
    Float *By[kNumNeighbours] = {}, *etaY[kNumNeighbours] = {};
    uint64_t merges = 0;
};

// The merges at one camera vertex z_u: its eta and camera terms, the offsets'
// terms (once per vertex, when first needed) and the case-2 budget's sample.
struct GVCMIntegrator::VertexMerges {
    int u = 0;
    Float etaU = 0;
    VCMCameraTerms terms;
    VCMCameraTerms ty[kNumNeighbours];
    bool tyDone[kNumNeighbours] = {};
    bool thin = false;
    Float stride = 1;
    Case2Base cb;  // one photon's at a time (large: built once per vertex, filled by case2Base)
};

// The photon's light subpath for case 2, regenerated at most once per merge.
struct GVCMIntegrator::PhotonSubpath {
    ShiftSubpath L;
    bool have = false, bad = false;
};

const Float *GVCMIntegrator::offsetB(SampleMerges &sm, int k) const {
    if (!sm.By[k]) {
        const CameraShift &sh = sm.st.shifts[k];
        const int n = std::min(sh.y.n, sh.validUpTo + 1);
        sm.By[k] = AllocFloats(*sm.st.arena, n);
        sm.etaY[k] = AllocFloats(*sm.st.arena, n);
        VCMCameraEta(sm.W, sh.y.v, sh.y.b, n, sm.etaY[k]);
        VCMCameraB(bctx_, sh.y.v, sh.y.b, n, sm.W, sm.etaY[k], sm.By[k]);
    }
    return sm.By[k];
}

const VCMCameraTerms *GVCMIntegrator::offsetTerms(SampleMerges &sm, VertexMerges &vm, int k) const {
    if (!vm.tyDone[k]) {
        const Float *B = offsetB(sm, k);
        const CameraShift &sh = sm.st.shifts[k];
        vm.ty[k] = VCMCameraAt(bctx_, sh.y.v, sh.y.b, vm.u, B[vm.u], sm.etaY[k], sm.W);
        vm.tyDone[k] = true;
    }
    return &vm.ty[k];
}

void GVCMIntegrator::addStrategies(const CameraState &st, GradientSample *out) const {
    if (!merging_ || kernel_.piN <= 0) return;
    const ShiftSubpath &cam = *st.cam;
    // `connecting` gates only the light-tracing (t = 1) terms of the camera-side sums.
    SampleMerges sm{st, VCMWeights{&kernel_, true, connections_ && set_.lightTracing, false, true}};
    // The base's eta_u (Sec. 6: its own footprint and shrink) and B_u.
    sm.etaX = AllocFloats(*st.arena, cam.n);
    sm.Bx = AllocFloats(*st.arena, cam.n);
    VCMCameraEta(sm.W, cam.v, cam.b, cam.n, sm.etaX);
    if (connections_) VCMCameraB(bctx_, cam.v, cam.b, cam.n, sm.W, sm.etaX, sm.Bx);
    bool specularChain = true;  // z_1 .. z_{u-1} all specular
    for (int u = 1; u < cam.n; ++u) {
        const PathVertex &zu = cam.v[u];
        const BSDF &bu = cam.b[u];
        if (!connections_ && specularChain) chainEmission(st, u, out);
        if (zu.type != VertexType::Surface || !bu) break;
        if (!sm.W.mergeable(zu, &bu)) {
            specularChain = specularChain && zu.delta();
            continue;
        }
        if (!mergesAt(sm, u, out)) continue;
        if (!connections_) break;  // G-PM: the first connectable vertex only
    }
    count(Merges, sm.merges);
}

void GVCMIntegrator::chainEmission(const CameraState &st, int u, GradientSample *out) const {
    // G-PM: emission through a specular chain (s = 0, the only strategy of its path).
    const PathVertex &zu = st.cam->v[u], &zp = st.cam->v[u - 1];
    const Spectrum Le = EmittedRadiance(bctx_, zu, zp);
    if (Le.isBlack()) return;
    const Spectrum fx = zu.throughput() * Le * st.w;
    out->primal += fx;
    if (DiracCameraChain(*st.cam, u - 1)) {  // separated light: no gradients (subpath_shift.h)
        out->separated += fx;
        return;
    }
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!st.inside[k]) continue;
        const CameraShift &sh = st.shifts[k];
        Spectrum fy(0);
        if (u <= sh.validUpTo) fy = sh.y.v[u].throughput() * EmittedRadiance(bctx_, sh.y.v[u], sh.y.v[u - 1]) * st.w;
        if (!fy.isBlack())
            out->diff[k] += (fy - fx) * CombinedWeight(1, 1, sh.rho[u]);
        else
            out->diff[k] += fx * -1;
    }
}

bool GVCMIntegrator::mergesAt(SampleMerges &sm, int u, GradientSample *out) const {
    // Merges at z_u with every light vertex within r (Eq. 11, Algorithm 1 lines 19-24).
    const ShiftSubpath &cam = *sm.st.cam;
    VertexMerges vm;
    vm.u = u;
    vm.etaU = sm.etaX[u];
    if (!(vm.etaU > 0)) return false;
    vm.terms = connections_ ? VCMCameraAt(bctx_, cam.v, cam.b, u, sm.Bx[u], sm.etaX, sm.W) : VCMCameraTerms();
    // The photons of the kernel (Algorithm 1, line 20), in the grid's order.
    thread_local Found found;
    gatherPhotons(cam.v[u], cam.b[u], u, vm.etaU, &found);
    // Case-2 budget: at most K photons of the n found are shifted through z'_b,
    // chosen by systematic sampling (one uniform offset in [0, n/K), then steps
    // of n/K: each photon is chosen with probability K/n) and their differences
    // weighted n/K, an unbiased estimate of the sum over all n (the primal and
    // case 1 keep every photon).
    const int n = int(found.size()), K = gset_.case2Budget;
    vm.thin = K > 0 && n > K;
    vm.stride = vm.thin ? Float(n) / K : 1;
    const Float start = vm.thin ? sm.st.sampler->get1D() * vm.stride : 0;
    int nextPick = 0;  // the next chosen position: floor(start + j stride)
    for (int i = 0; i < n; ++i) {
        bool chosen = true;
        if (vm.thin) {
            chosen = nextPick < K && int(start + nextPick * vm.stride) == i;
            if (chosen) ++nextPick;
        }
        mergePhoton(sm, vm, found[size_t(i)].first, found[size_t(i)].second, chosen, out);
    }
    return true;
}

void GVCMIntegrator::gatherPhotons(const PathVertex &zu, const BSDF &bu, int u, Float etaU, Found *found) const {
    found->clear();
    ForEachMergeCandidate(grid_, vertices_, zu, std::sqrt(etaU / kernel_.piN), gset_.normalFilter,
                          [&](uint32_t idx, const LightVertex &lv) {
        if (int(lv.depth) + u - 1 > set_.maxDepth) return;
        const Spectrum f = bu.f(Vec3(zu.wo), lv.wo, TransportMode::Radiance);
        if (!f.isBlack()) found->emplace_back(idx, f);
    });
}

void GVCMIntegrator::mergePhoton(SampleMerges &sm, VertexMerges &vm, uint32_t idx, const Spectrum &f, bool chosen,
                                 GradientSample *out) const {
    const CameraState &st = sm.st;
    const int u = vm.u;
    const PathVertex &zu = st.cam->v[u], &zp = st.cam->v[u - 1];
    const BSDF &bu = st.cam->b[u];
    const LightVertex &lv = vertices_[idx];
    ++sm.merges;
    // Eq. 13: the base's w_VM (with connections; G-PM's merges are the only strategy).
    const Float wx = connections_ ? mergeWeight(vm.terms, zu, zp, bu, lv, sm.W) : 1;
    // Eq. 5 with the uniform kernel: beta_L f beta_C / (pi r_u^2 N), N folded into w_VM.
    const Spectrum fx = zu.throughput() * f * lv.throughput() * (st.w / vm.etaU);
    out->primal += fx * wx;
    PhotonSubpath ph;
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!st.inside[k]) continue;
        const CameraShift &sh = st.shifts[k];
        const bool isCase1 = sh.r >= 0 && u >= sh.r;
        Offset o;
        bool ok = false;
        if (u > sh.validUpTo) {
            count(FallbackShift);
        } else if (isCase1) {
            ok = case1(sh, u, bu, lv, f, st.w, vm.etaU, connections_ ? offsetTerms(sm, vm, k) : nullptr, sm.W, &o);
        } else if (!chosen) {
            count(Case2Skipped);
            continue;  // not in the budget's sample: no difference from this photon
        } else {
            ok = case2Offset(sm, vm, k, idx, &ph, &o);
        }
        // Eq. 23; a case-2 difference of the budget's sample times n/K.
        const Float scale = vm.thin && u <= sh.validUpTo && !isCase1 ? vm.stride : Float(1);
        if (ok)
            out->diff[k] += (o.f - fx) * (CombinedWeight(wx, o.w, o.rho) * scale);
        else
            out->diff[k] += fx * (-wx * scale);  // zero offset, the base's weight
    }
}

bool GVCMIntegrator::case1(const CameraShift &sh, int u, const BSDF &bu, const LightVertex &lv, const Spectrum &f,
                           Float w, Float etaX, const VCMCameraTerms *terms, const VCMWeights &W, Offset *o) const {
    // Case 1 (Eqs. 16-17): the same z_u, kernel and light vertex; only the
    // camera prefix (and at u = r the direction towards z'_{u-1}) differs.
    count(Case1);
    const PathVertex &yu = sh.y.v[u], &yp = sh.y.v[u - 1];
    const Spectrum fo = u == sh.r ? bu.f(Vec3(yu.wo), Vec3(lv.wo), TransportMode::Radiance) : f;
    // The estimate keeps the base's kernel; the weight takes the offset's own
    // eta (Eq. 22), and so does rho = |T'| p_VM(y) / p_VM(x) (Eq. 23).
    o->f = yu.throughput() * fo * lv.throughput() * (w / etaX);
    o->rho = sh.rho[u];
    if (terms) {
        o->w = mergeWeight(*terms, yu, yp, bu, lv, W);
        o->rho *= terms->etaU / etaX;
    }
    const bool ok = !o->f.isBlack() && o->w > 0;
    count(ok ? Case1Shifted : FallbackBlocked);
    return ok;
}

bool GVCMIntegrator::case2Offset(SampleMerges &sm, VertexMerges &vm, int k, uint32_t idx, PhotonSubpath *ph,
                                 Offset *o) const {
    // Case 2: the offset is a physical path through z'_b (Eqs. 18-20).
    count(Case2);
    const LightVertex &lv = vertices_[idx];
    Arena &arena = *sm.st.arena;
    if (!ph->have) {
        // The photon's light subpath, regenerated to the photon's depth (its
        // prefix is the light pass's: the RNG is consumed vertex by vertex),
        // and the base's half of the shift, once for all offsets.
        ph->have = true;
        const uint32_t j =
            uint32_t(std::upper_bound(pathStart_.begin(), pathStart_.end(), idx) - pathStart_.begin() - 1);
        regenerate(j, int(lv.depth) + 1, arena, &ph->L);
        count(Regenerated);
        ph->bad = int(lv.depth) >= ph->L.n || Distance(ph->L.v[lv.depth].p, lv.p) > 1e-5 * (1 + Vec3(lv.p).length());
        if (ph->bad)
            count(FallbackMismatch);
        else
            case2Base(ph->L, lv.depth, arena, &vm.cb);
    }
    if (ph->bad) return false;
    const bool ok = case2(ph->L, vm.cb, sm.st.shifts[k], vm.u, lv, connections_ ? offsetTerms(sm, vm, k) : nullptr,
                          vm.etaU, arena, o) &&
                    o->w > 0;
    if (ok) {
        o->f *= sm.st.w;
        count(Case2Shifted);
    }
    return ok;
}

std::string GVCMIntegrator::statistics() const {
    auto c = [&](Counter k) { return (unsigned long long)counters_[k].load(); };
    char buf[1536];
    std::snprintf(buf, sizeof buf,
                  "gvcm: mode %s, kernel %s, initial radius %.4g (last %.4g), %d iterations, %.3g light vertices per iteration "
                  "(%zu bytes each, grid %.1f MB), %llu merges%s%s\n"
                  "  merge offsets: case 1 (shared kernel) %llu, shifted %llu; case 2 (through z'_b) %llu: "
                  "empty chain %llu, specular chain %llu, shifted %llu; left out by the budget %llu; light subpaths regenerated %llu\n"
                  "  merge fallbacks (zero offset, base weight): camera shift failed %llu, light at infinity %llu, "
                  "glossy chain %llu, long chain %llu, walk failed %llu, occluded or black %llu, regeneration mismatch %llu\n",
                  gset_.mergeOnly ? "mergeonly (G-PM)" : "vcm", KernelName(gset_).c_str(), radius1_, radius_, passes_,
                  passes_ ? double(nLightVertices_) / passes_ : 0.0, sizeof(LightVertex), gridBytes_ / 1e6,
                  c(Merges), skipped_.empty() ? "" : "; ", skipped_.c_str(), c(Case1), c(Case1Shifted), c(Case2),
                  c(Case2Empty), c(Case2Chain), c(Case2Shifted), c(Case2Skipped), c(Regenerated), c(FallbackShift),
                  c(FallbackInfinite), c(FallbackGlossy), c(FallbackLong), c(FallbackWalk), c(FallbackBlocked),
                  c(FallbackMismatch));
    std::string walks = "  case-2 chain walks by status:";
    for (size_t i = 0; i < size_t(ManifoldStatus::Count); ++i)
        if (walkStatus_[i].load())
            walks += std::string(" ") + ToString(ManifoldStatus(i)) + " " + std::to_string(walkStatus_[i].load()) + ";";
    return std::string(buf) + walks + "\n" + GBDPTIntegrator::statistics();
}

}  // namespace gradus
