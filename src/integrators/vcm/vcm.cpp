// VCM estimator and its recursive MIS (derivation in vcm.h; strategy
// notation of common/bidir.h).
#include "integrators/vcm/vcm.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <unistd.h>

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"
#include "samplers/rng_sampler.h"

namespace gradus {

std::unique_ptr<Integrator> CreateVCMIntegrator(const EntityDesc &d) { return std::make_unique<VCMIntegrator>(d); }

namespace {

constexpr uint64_t kLightTag = 0x76636d0000000001ULL;
constexpr uint64_t kMediaTag = 0x76636d0000000002ULL;  // the light subpaths' media RNG

}  // namespace

ParamTable<MergeRadiusSettings> MergeRadiusParams() {
    using S = MergeRadiusSettings;
    ParamTable<S> t("merging radius");
    t.real("radius", &S::radius, 0, "initial merging radius in scene units (0: from the pixel footprint)", AtLeast(0));
    t.real("radiusscale", &S::radiusScale, 1, "the footprint radius in pixels (radius 0)", Range{1e-3, 1e3});
    t.real("radiusalpha", &S::radiusAlpha, 0.75,
           "radius reduction: r_i^2 = r_1^2 i^(alpha - 1) (radiusschedule area) | r_i = r_1 i^(alpha - 1) "
           "(radiusschedule radius; default 0.9 there)",
           Range{1e-3, 1});
    t.enumeration<RadiusSchedule>("radiusschedule", &S::schedule, "area",
                                  {{"area", RadiusSchedule::Area}, {"radius", RadiusSchedule::Radius}},
                                  "area: r_i^2 = r_1^2 i^(alpha - 1) (Knaus and Zwicker) | radius: r_i = r_1 "
                                  "i^(alpha - 1) (the G-VCM authors' code, radiusalpha 0.9 unless given)")
        .thenWithParams([](S &s, const ParamSet &ps, const FileLoc &) {
            if (s.schedule == RadiusSchedule::Radius && !ps.has("radiusalpha")) s.radiusAlpha = 0.9;
        });
    t.enumeration<bool>("kernel", &S::adaptiveKernel, "fixed", {{"fixed", false}, {"adaptive", true}},
                        "fixed (r_1 at every vertex) | adaptive (G-VCM Sec. 6: r_j = 0.5^(kernelshrink tau) r_{j-1})");
    t.real("kernelshrink", &S::kernelShrink, 10,
           "adaptive: r_j = 0.5^(kernelshrink tau) r_{j-1} (tau: roughness at the previous vertex)", Range{0, 100});
    t.enumeration<bool>("footprint", &S::pathFootprint, "median", {{"median", false}, {"path", true}},
                        "radius 0: r_1 from the median pixel footprint of the primary hits | from each path's "
                        "pixel width at its first mergeable vertex (G-VCM Sec. 6), at most 2 r_i");
    t.boolean("normalfilter", &S::normalFilter, false,
              "merge only photons whose geometric normal n_y has n_y . n_z >= 0.1 with the camera vertex's n_z "
              "(the G-VCM authors' code)");
    return t;
}

namespace {

ParamTable<VCMSettings> Table() {
    using S = VCMSettings;
    ParamTable<S> t("vcm");
    t.append(BidirParams());  // rrdepth 3
    t.enumeration<VCMMode>("mode", &S::mode, "vcm", {{"vcm", VCMMode::VCM}, {"vc", VCMMode::VC}, {"vm", VCMMode::VM}},
                           "vcm | vc (connections only: BDPT) | vm (merging only: progressive photon mapping)");
    t.append(MergeRadiusParams());
    t.integer("numiterations", &S::iterations, 0,
              "iterations (samples per pixel) unless --spp is given; 0: the sampler's (pbrt-v3 sppm)", AtLeast(0));
    t.integer("photonsperiteration", &S::photonsPerIteration, -1,
              "pbrt-v3 sppm: light subpaths per iteration; only -1 (one per sampled pixel)",
              Range{-1, -1, "vcm traces one light subpath per sampled pixel"});
    t.integer("imagewritefrequency", &S::imageWriteFrequency, 0,
              "pbrt-v3 sppm: accepted; intermediate images are not written");
    return t;
}

Float Remap(Float f) { return f != 0 ? f : Float(1); }

Float Mis(Float x, bool power) { return power ? x * x : x; }

PathVertex AsPathVertex(const Scene &scene, const LightVertex &lv) {
    PathVertex v;
    v.type = lv.inMedium() ? VertexType::Medium : VertexType::Surface;
    CopyVertexCore(lv, v);
    if (lv.inMedium()) v.medium = MediumAt(scene, lv.mediumIndex);
    v.pdfFwd = lv.pdfFwd;
    v.primId = lv.primId;
    v.b1 = lv.b1;
    v.b2 = lv.b2;
    if (lv.flags & LightVertex::kSpawnOffset) v.flags |= VERTEX_SPAWN_OFFSET;
    return v;
}

}  // namespace

// ---------------------------------------------------------------- recursive MIS (vcm.h)
int VCMLightVertices(const BidirContext &ctx, const PathVertex *v, const BSDF *b, int n, const VCMWeights &w,
                     std::vector<LightVertex> *out) {
    const size_t before = out->size();
    // B_0 = 0, B_1 = c_{-1} (s' = 0: the emitter can be hit unless it is a delta light),
    // B_{m+2} = c_m + eta g_m other(v_m) + R_m B_{m+1}, in the parts Bc + h^beta Be (vcm.h).
    Float Bc = n > 0 && !v[0].isDeltaLight() ? 1 : 0, Be = 0;  // B_1
    for (int i = 1; i < n; ++i) {
        // Here (Bc, Be) = B_i. c_{i-1}: light endpoint y_{i-1}, camera endpoint y_i.
        const bool prevDelta = i - 1 >= 1 && v[i - 1].delta();
        const bool edgeOK = EdgeConnectible(ctx, v[i - 1], v[i]);
        const bool prevMerge = w.merging && i - 1 >= 1 && w.mergeable(v[i - 1], &b[i - 1]);
        if (w.mergeable(v[i], &b[i]) || v[i].inMedium()) {
            LightVertex lv;
            CopyVertexCore(v[i], lv);
            lv.primId = v[i].primId;
            lv.b1 = v[i].b1;
            lv.b2 = v[i].b2;
            lv.pdfFwd = v[i].pdfFwd;
            lv.prevPdfFwd = v[i - 1].pdfFwd;
            lv.prevGeom = ConvertDensity(1, v[i], v[i - 1]);
            lv.B = Bc;
            lv.Be = float(Be);
            GRADUS_CHECK(i < 256);
            lv.depth = uint8_t(i);
            lv.flags = uint8_t((prevDelta ? LightVertex::kPrevDelta : 0) | (prevMerge ? LightVertex::kPrevMergeable : 0) |
                               (edgeOK ? LightVertex::kPrevEdgeOK : 0) | (v[i].inMedium() ? LightVertex::kMedium : 0) |
                               ((v[i].flags & VERTEX_SPAWN_OFFSET) ? LightVertex::kSpawnOffset : 0));
            out->push_back(lv);
        }
        // B_{i+1} = c_{i-1} + eta g_{i-1} other(y_{i-1}) + R_{i-1} B_i, other(y_{i-1}) = pdfRev (exact);
        // y_i is not an endpoint of c_{i-1} here, so its own lobe counts too.
        const Float c = !prevDelta && edgeOK && !v[i].delta() ? 1 : 0;
        const Float Rm = Mis(Remap(v[i - 1].pdfRev) / Remap(v[i - 1].pdfFwd), w.power);
        // Bc_{i+1} = c_{i-1} + R_{i-1} Bc_i; Be_{i+1} = sigma_i^beta (g_{i-1} o_{i-1}^beta + R_{i-1} Be_i).
        Bc = c + Rm * Bc;
        Be = Mis(w.sigma(&b[i]), w.power) * ((prevMerge ? Mis(Remap(v[i - 1].pdfRev), w.power) : 0) + Rm * Be);
    }
    return int(out->size() - before);
}

Float VCMLightPrevSum(const LightVertex &lv, Float oim1, Float h, const VCMWeights &w) {
    // S_L(i-1) = h g_{i-1} o_{i-1} + R_{i-1} B_i, B_i = Bc_i + h^beta Be_i (h = eta at y_{i-1}).
    const bool gim1 = lv.flags & LightVertex::kPrevMergeable;
    return (gim1 ? Mis(h * Remap(oim1), w.power) : 0) +
           Mis(Remap(oim1) / Remap(lv.prevPdfFwd), w.power) * (lv.B + Mis(h, w.power) * Float(lv.Be));
}

bool VCMPrevConnectible(const LightVertex &lv) {
    return !(lv.flags & LightVertex::kPrevDelta) && (lv.flags & LightVertex::kPrevEdgeOK);
}

Float VCMLightSum(const LightVertex &lv, Float oi, Float oim1, Float h, Float sigmaI, const VCMWeights &w) {
    // S_L(i) = h g_i o_i + R_i (c_{i-1} + S_L(i-1)), eta at y_{i-1} = h sigma(y_i); g_i = 0 in a medium.
    return (w.merging && !lv.inMedium() ? Mis(h * Remap(oi), w.power) : 0) +
           Mis(Remap(oi) / Remap(lv.pdfFwd), w.power) *
               ((VCMPrevConnectible(lv) ? 1 : 0) + VCMLightPrevSum(lv, oim1, h * sigmaI, w));
}

void VCMCameraEta(const VCMWeights &w, const PathVertex *z, const BSDF *zb, int nC, Float *eta) {
    if (!w.merging || !w.kernel) {
        std::fill(eta, eta + std::max(nC, 0), Float(0));
        return;
    }
    PathMergeEta(*w.kernel, nC, [&](int j) -> const PathVertex & { return z[j]; },
                 [&](int j) -> const BSDF * { return z[j].type == VertexType::Surface ? &zb[j] : nullptr; },
                 [&](int j) { return w.mergeable(z[j], &zb[j]); }, eta);
}

void VCMCameraB(const BidirContext &ctx, const PathVertex *z, const BSDF *zb, int nC, const VCMWeights &w,
                const Float *eta, Float *B) {
    // B_0 = 0, B_1 = 0 (t' = 0 is no strategy), B_{m+2} = c_m + eta g_m other(z_m) + R_m B_{m+1}.
    for (int u = 0; u < nC; ++u) {
        if (u < 2) {
            B[u] = 0;
            continue;
        }
        const int m = u - 2;
        // m = 0 is light tracing; impossible for a ray through the filter margin
        // (z_1's pdfFwd 0, GenerateCameraSubpath).
        const bool cm = (m == 0 ? w.connecting && z[1].pdfFwd != 0 : !z[m].delta()) && !z[m + 1].delta() &&
                        EdgeConnectible(ctx, z[m], z[m + 1]);
        const bool gm = w.merging && m >= 1 && w.mergeable(z[m], &zb[m]);
        B[u] = (cm ? 1 : 0) + (gm ? Mis(eta[m] * Remap(z[m].pdfRev), w.power) : 0) +
               Mis(Remap(z[m].pdfRev) / Remap(z[m].pdfFwd), w.power) * B[u - 1];
    }
}

VCMCameraTerms VCMCameraAt(const BidirContext &ctx, const PathVertex *z, const BSDF *zb, int u, Float Bu,
                           const Float *eta, const VCMWeights &w) {
    const PathVertex &zu = z[u], &zp = z[u - 1];
    VCMCameraTerms c;
    // c_{u-1}: camera endpoint z_{u-1}, light endpoint z_u. For u = 1 it is light
    // tracing, which with z_u as the light origin would be (1, 1): not a strategy.
    const bool edge = EdgeConnectible(ctx, zp, zu);
    c.cPrev = (u - 1 == 0 ? w.connecting && zu.pdfFwd != 0 : !zp.delta()) && edge;
    c.cPrevEmitter = u - 1 != 0 && c.cPrev;
    c.gPrev = w.merging && u - 1 >= 1 && w.mergeable(zp, &zb[u - 1]);
    c.ownU = Remap(zu.pdfFwd);
    c.ownPrev = Remap(zp.pdfFwd);
    c.B = Bu;
    c.etaU = eta[u];
    c.etaPrev = eta[u - 1];
    // At a medium vertex (fixed kernels only: VCMIntegrator::rendersMedia) the kernel's one eta.
    c.H = zu.type == VertexType::Surface                ? eta[u] * w.sigma(&zb[u])
          : zu.type == VertexType::Medium && w.kernel ? w.kernel->piN * w.kernel->r2
                                                      : 0;
    return c;
}

Float VCMCameraSum(const VCMCameraTerms &c, Float oz, Float oPrev, bool gu, bool emitter, const VCMWeights &w) {
    // S_C(u) = eta_u g_u o_u + R_u (c_{u-1} + eta_{u-1} g_{u-1} o_{u-1} + R_{u-1} B_u).
    const Float Ru = Mis(Remap(oz) / c.ownU, w.power), Rp = Mis(Remap(oPrev) / c.ownPrev, w.power);
    const bool cPrev = emitter ? c.cPrevEmitter : c.cPrev;
    return (gu ? Mis(c.etaU * Remap(oz), w.power) : 0) +
           Ru * ((cPrev ? 1 : 0) + (c.gPrev ? Mis(c.etaPrev * Remap(oPrev), w.power) : 0) + Rp * c.B);
}

std::vector<ParamInfo> VCMParameters() { return Table().describe(); }

VCMIntegrator::VCMIntegrator(const EntityDesc &desc) : BidirFamily("vcm", 1), set_(Table().parse(desc)), loc_(desc.loc) {
    if (set_.visStrategies || set_.visWeights)
        throw Error(desc.params.locOf(set_.visStrategies ? "visualizestrategies" : "visualizeweights", desc.loc),
                    "strategy layers are not supported by vcm");
    CheckMergeRadiusParams(desc, set_);
}

void CheckMergeRadiusParams(const EntityDesc &desc, const MergeRadiusSettings &s) {
    // A setting that the other choices would silently ignore is an error (a
    // default value changes nothing and passes).
    if (!s.adaptiveKernel && desc.params.has("kernelshrink") && s.kernelShrink != 10)
        throw Error(desc.params.locOf("kernelshrink", desc.loc), "\"kernelshrink\" needs \"kernel\" \"adaptive\"");
    if (s.pathFootprint && s.radius > 0)
        throw Error(desc.params.locOf("footprint", desc.loc), "\"footprint\" \"path\" needs \"radius\" 0");
}

Float VCMFootprintRadius(const Scene &scene, const Bounds2i &bounds, Float scale) {
    // Median pixel footprint at the primary hits of a 16 x 16 grid of pixels.
    std::vector<Float> fp;
    const int dx = bounds.width(), dy = bounds.height();
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i) {
            CameraSample cs;
            cs.pFilm = Point2(bounds.pMin.x + (i + 0.5) * dx / 16, bounds.pMin.y + (j + 0.5) * dy / 16);
            cs.pLens = Point2(0.5, 0.5);
            Ray r0, r1;
            if (scene.camera->generateRay(cs, &r0) == 0) continue;
            cs.pFilm.x += 1;
            if (scene.camera->generateRay(cs, &r1) == 0) continue;
            SurfaceInteraction si;
            if (!scene.intersect(r0, &si)) continue;
            Float t = (si.p - r0.o).length() / r0.d.length();
            Float w = ((si.p) - (r1.o + r1.d * t)).length();
            if (std::isfinite(w) && w > 0) fp.push_back(w);
        }
    if (!fp.empty()) {
        std::nth_element(fp.begin(), fp.begin() + fp.size() / 2, fp.end());
        return fp[fp.size() / 2] * scale;
    }
    Point3 c;
    Float rad = 1;
    scene.bounds.boundingSphere(&c, &rad);
    return std::isfinite(rad) && rad > 0 ? 1e-3 * rad : 1e-3;
}

LightVertexGather::LightVertexGather(int64_t subpaths, int maxDepth, std::vector<LightVertex> *vertices,
                                     std::vector<uint32_t> *pathStart)
    : chunks_(size_t((subpaths + PassContext::kItemChunk - 1) / PassContext::kItemChunk)), n_(subpaths),
      vertices_(vertices), pathStart_(pathStart) {
    pathStart->assign(size_t(subpaths) + 1, 0);
    vertices->clear();  // keeps the capacity of the last pass (pages already resident)
    // At most maxDepth stored vertices per subpath (y_1 .. y_maxDepth): reserved as
    // address space when that is a small part of the memory, so appending never
    // reallocates (a reallocation would hold two copies).
    static const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
    const double bound = double(subpaths) * std::max(1, maxDepth);
    if (bound > double(vertices->capacity()) && bound * sizeof(LightVertex) < physical / 4)
        vertices->reserve(size_t(bound));
}

void LightVertexGather::merged(int64_t c) {
    // Counts to offsets for this chunk's subpaths, then its vertices to the end of the pass's.
    const int64_t j0 = c * PassContext::kItemChunk, j1 = std::min(n_, j0 + PassContext::kItemChunk);
    std::vector<uint32_t> &start = *pathStart_;
    for (int64_t j = j0; j < j1; ++j) start[size_t(j) + 1] += start[size_t(j)];
    std::vector<LightVertex> &chunk = chunks_[size_t(c)];
    GRADUS_CHECK(size_t(start[size_t(j1)]) == vertices_->size() + chunk.size());
    vertices_->insert(vertices_->end(), chunk.begin(), chunk.end());
    std::vector<LightVertex>().swap(chunk);
}

void BuildLightVertexGrid(PassContext &ctx, const std::vector<LightVertex> &vertices, Float radius, PhotonGrid *grid) {
    grid->build(vertices.size(), [&](size_t i) { return vertices[i].p; }, radius,
                [&](int64_t n, int64_t grain, const std::function<void(int64_t, int64_t)> &fn) {
        ctx.parallelFor(n, grain, [&](int64_t b, int64_t e, Worker &) { fn(b, e); });
    });
}

Float VCMRadius(Float r1, Float alpha, int iteration, RadiusSchedule schedule) {
    // Area: r_i^2 = r_1^2 i^(alpha - 1); Radius: r_i = r_1 i^(alpha - 1) (vcm.h).
    const Float e = schedule == RadiusSchedule::Radius ? alpha - 1 : Float(0.5) * (alpha - 1);
    return r1 * std::pow(Float(std::max(iteration, 1)), e);
}

MergeKernel VCMKernel(const MergeRadiusSettings &s, Float r1, int iteration, int64_t nLight, const Camera &camera,
                      bool merging) {
    MergeKernel k;
    const Float ri = VCMRadius(r1, s.radiusAlpha, iteration, s.schedule);
    // eta_VCM = pi r^2 N_light (G-VCM Eq. 12: N p_VM with N light subpaths merged).
    k.piN = merging ? Pi * Float(nLight) : 0;
    k.r2 = ri * ri;
    // Sec. 6: the shrink along the camera subpath, and r_1 from the path's pixel footprint.
    if (s.adaptiveKernel) k.shrink = s.kernelShrink;
    if (s.pathFootprint && s.radius <= 0) {
        const Float scale = s.radiusScale * VCMRadius(1, s.radiusAlpha, iteration, s.schedule);  // radiusscale times the schedule
        k.footprint2 = scale * scale;
        k.r2Max = 4 * k.r2;  // the grid (built for r_i) answers queries up to 2 r_i
        k.pixels = Float(camera.fullResolution.x) * Float(camera.fullResolution.y);
        k.camera = &camera;
    }
    return k;
}

std::string KernelName(const MergeRadiusSettings &s) {
    char shrink[48] = "fixed";
    if (s.adaptiveKernel) std::snprintf(shrink, sizeof shrink, "adaptive (shrink %g)", s.kernelShrink);
    const char *r1 = s.radius > 0       ? "r_1 = radius"
                     : s.pathFootprint ? "r_1 from each path's footprint (at most 2 r_i)"
                                       : "r_1 from the median footprint";
    std::string name = std::string(shrink) + ", " + r1;
    if (s.schedule == RadiusSchedule::Radius) {
        char b[64];
        std::snprintf(b, sizeof b, ", r_i = r_1 i^(%g - 1)", s.radiusAlpha);
        name += b;
    }
    if (s.normalFilter) name += ", photon-normal filter";
    return name;
}

Float VCMIntegrator::radiusAt(int iteration) const {
    return VCMRadius(radius1_, set_.radiusAlpha, iteration, set_.schedule);
}

void VCMIntegrator::preprocess(const Scene &scene, Film &film) {
    preprocessBidir(scene, film, set_, loc_);
    bounds_ = film.sampleBounds();
    const SceneFeatures &f = scene.features;
    merging_ = set_.mode != VCMMode::VC;
    connecting_ = set_.mode != VCMMode::VM;
    if (set_.mode == VCMMode::VCM && !f.specularSurfaces && !f.nearSpecularSurfaces) {
        merging_ = false;
        skipped_ = "no specular or near-specular surface: merging left out (no grid)";
    }
    if (merging_ && set_.maxDepth > 255) throw Error(loc_, "vcm: maxdepth above 255 is not supported with merging");
    radius1_ = set_.radius > 0 ? set_.radius : VCMFootprintRadius(scene, bounds_, set_.radiusScale);
    GRADUS_CHECK(radius1_ > 0);
}

void VCMIntegrator::runPass(PassContext &ctx) {
    scene_ = &ctx.scene();
    const int iteration = ctx.firstSample() + 1;
    radius_ = radiusAt(iteration);
    kernel_ = VCMKernel(set_, radius1_, iteration, bounds_.area(), *ctx.scene().camera, merging_);
    lightPass(ctx);
    if (ctx.interrupted()) return;
    if (merging_) {
        BuildLightVertexGrid(ctx, vertices_, radius_, &grid_);
    }
    if (ctx.interrupted()) return;
    ctx.forEachPixelSample(*this);
    ++passes_;
}

// ---------------------------------------------------------------- light pass
void VCMIntegrator::lightPass(PassContext &ctx) {
    const int64_t N = bounds_.area();
    const int iteration = ctx.firstSample() + 1;
    const int maxLight = set_.maxDepth + 1;
    const VCMWeights weights{merging_ ? &kernel_ : nullptr, merging_, connecting_, ctx_.heuristic == MISHeuristic::Power};
    LightVertexGather gather(N, set_.maxDepth, &vertices_, &pathStart_);
    const Scene &scene = ctx.scene();
    ctx.forEachItem(N, kLightTag, [&](int64_t item, RNG &rng, SampleRecorder &rec, Worker &wk) {
        if (scene.lights.empty()) return;
        PathVertex *v;
        BSDF *b;
        AllocSubpath(wk.arena, maxLight, &v, &b);
        RNGSampler smp(rng);
        // Media: distances and transmittances from their own stream, keyed by (seed, pass, subpath).
        RNG mediaRng;
        RNG *mrng = scene.features.media
                        ? &(mediaRng = RNG(Hash(ctx.seed(), kMediaTag, uint64_t(iteration), uint64_t(item))))
                        : nullptr;
        const int n = GenerateLightSubpath(ctx_, smp, wk.arena, maxLight, v, b, mrng);
        std::vector<LightVertex> &dst = gather.buffer(item);
        const size_t first = dst.size();
        gather.setCount(item, VCMLightVertices(ctx_, v, b, n, weights, &dst));
        for (size_t k = first; k < dst.size(); ++k) {
            const LightVertex &lv = dst[k];
            const int i = lv.depth;
            // Light tracing (t = 1) from y_i, depth i: w = 1 / (1 + S_L(i)), S_C(0) = 0 (vcm.h).
            if (!connecting_ || i > set_.maxDepth) continue;
            PathVertex lens;
            CameraWiSample cws;
            if (!SampleLensVertex(ctx_, v[i], smp.get2D(), &lens, &cws) || !EdgeConnectible(ctx_, v[i], lens)) continue;
            Spectrum L = v[i].throughput() * EvalBSDF(v[i], b[i], lens, TransportMode::Importance) *
                         (cws.We / cws.pdf) * ScatterCos(v[i], cws.wi);
            if (L.isBlack()) continue;
            L *= Transmittance(ctx_, v[i], AsInteraction(v[i]), cws.pLens, mrng);
            if (L.isBlack()) continue;
            // o_i: camera density of y_i; o_{i-1}: y_i's BSDF from the lens towards y_{i-1}.
            const Float oi = PdfArea(ctx_, lens, nullptr, nullptr, v[i], TransportMode::Radiance);
            const Float oim1 = ScatterPdf(v[i], b[i], cws.wi, Vec3(v[i].wo), TransportMode::Radiance) * lv.prevGeom;
            // eta at y_i: the footprint of y_i's pixel (the first mergeable vertex from the camera).
            Float h = 0;
            if (merging_) {
                const Vec3 d = v[i].p - lens.p;
                const Float len = d.length();
                h = kernel_.firstEta(lens.p, d / len, len);
            }
            rec.splat(cws.pRaster, L * (splatScale_ / (1 + VCMLightSum(lv, oi, oim1, h, weights.sigma(&b[i]), weights))));
        }
    }, gather.chunkMerged());
    nLightVertices_ += vertices_.size();
}

// ---------------------------------------------------------------- camera pass
// One camera sample (step 3): the camera subpath with its eta and B_u, then
// at each vertex z_u the strategies that end there, each adding to L.
struct VCMIntegrator::CameraPath {
    CameraPath(const VCMIntegrator &in, const CameraSample &cs, const Ray &ray, Sampler &sampler, Arena &arena,
               Point2i pixel)
        : in(in), ctx(in.ctx_), sampler(sampler), arena(arena), maxCam(in.set_.maxDepth + 2) {
        AllocSubpath(arena, maxCam, &z, &zb);
        mrng = in.scene_->features.media ? &(mediaRng = CameraSampleMediaRNG(sampler, cs)) : nullptr;
        nC = GenerateCameraSubpath(ctx, ray, sampler, arena, maxCam, z, zb, mrng);
        power = ctx.heuristic == MISHeuristic::Power;
        own = int64_t(pixel.y - in.bounds_.pMin.y) * in.bounds_.width() + (pixel.x - in.bounds_.pMin.x);
        weights = VCMWeights{in.merging_ ? &in.kernel_ : nullptr, in.merging_, in.connecting_, power};
        Bc = static_cast<Float *>(arena.alloc(sizeof(Float) * maxCam, alignof(Float)));
        eta = static_cast<Float *>(arena.alloc(sizeof(Float) * maxCam, alignof(Float)));
        VCMCameraEta(weights, z, zb, nC, eta);
        VCMCameraB(ctx, z, zb, nC, weights, eta, Bc);
    }

    Float SC(const VCMCameraTerms &terms, Float oz, Float oPrev, bool gu, bool emitter = false) const {
        return VCMCameraSum(terms, oz, oPrev, gu, emitter, weights);
    }

    // s = 0: z_u is an emitter (or the infinite lights).
    void emission(int u, const VCMCameraTerms &terms, bool specularChain) {
        const PathVertex &zu = z[u], &zp = z[u - 1];
        const int depthHere = u - 1;  // edges from the camera to z_u, minus 1
        if (depthHere > in.set_.maxDepth) return;
        Spectrum Le = EmittedRadiance(ctx, zu, zp);
        if (Le.isBlack()) return;
        Float weight;
        if (!in.connecting_) {
            weight = specularChain ? 1 : 0;  // vm: emission only through specular chains
        } else {
            // z_u as the light origin: other(z_u) = PdfLightOrigin, other(z_{u-1}) = PdfLightDirection; no merge at x_0.
            weight = 1 / (1 + SC(terms, PdfLightOrigin(ctx, zu, zp), PdfLightDirection(ctx, zu, zp), false, true));
        }
        L += zu.throughput() * Le * weight;
    }

    // s = 1: next-event estimation (as ConnectBDPT), depth u.
    void nextEvent(int u, const VCMCameraTerms &terms, bool gu) {
        const PathVertex &zu = z[u], &zp = z[u - 1];
        const BSDF &bu = zb[u];
        Float uSel = sampler.get1D();
        Point2 uLight = sampler.get2D();
        PathVertex y0;
        LightLiSample ls;
        Spectrum Lw;
        if (u <= in.set_.maxDepth && SampleLightVertex(ctx, zu, uSel, uLight, &y0, &ls, &Lw) &&
            EdgeConnectible(ctx, y0, zu)) {
            Spectrum c = zu.throughput() * EvalBSDF(zu, bu, y0, TransportMode::Radiance) * Lw * ScatterCos(zu, ls.wi);
            if (!c.isBlack()) c *= Transmittance(ctx, zu, AsInteraction(zu), ls.pLight, mrng);
            if (!c.isBlack()) {
                // S_L(0) = R_0 c_{-1}; S_C(u) with other(z_u) = emission density, other(z_{u-1}) from y_0.
                const Float o0 = PdfArea(ctx, zu, &bu, &zp, y0, TransportMode::Radiance);
                const Float SL = y0.isDeltaLight() ? 0 : Mis(Remap(o0) / Remap(y0.pdfFwd), power);
                const Float oz = PdfLightDirection(ctx, y0, zu);
                const Float oPrev = PdfArea(ctx, zu, &bu, &y0, zp, TransportMode::Importance);
                L += c / (1 + SL + SC(terms, oz, oPrev, gu));
            }
        }
    }

    // s >= 2: connections to the own light subpath's vertices y_i (depth i + u).
    void connectOwnLightSubpath(int u, const VCMCameraTerms &terms, bool gu) {
        const std::vector<uint32_t> &pathStart = in.pathStart_;
        if (!(own >= 0 && own + 1 < int64_t(pathStart.size()))) return;
        for (uint32_t k = pathStart[own]; k < pathStart[own + 1]; ++k) connect(u, terms, gu, in.vertices_[k]);
    }

    void connect(int u, const VCMCameraTerms &terms, bool gu, const LightVertex &lv) {
        const PathVertex &zu = z[u], &zp = z[u - 1];
        const BSDF &bu = zb[u];
        if (int(lv.depth) + u > in.set_.maxDepth) return;
        const PathVertex y = AsPathVertex(*in.scene_, lv);
        if (!EdgeConnectible(ctx, y, zu)) return;
        BSDF by = RebuildBSDF(ctx, y, TransportMode::Importance, arena);
        if (!by && !y.inMedium()) return;
        Spectrum c = lv.throughput() * EvalBSDF(y, by, zu, TransportMode::Importance) *
                     EvalBSDF(zu, bu, y, TransportMode::Radiance) * zu.throughput();
        if (c.isBlack()) return;
        Vec3 d = y.p - zu.p;
        const Float d2 = d.lengthSquared();
        d = d / std::sqrt(d2);
        c *= ScatterCos(y, d) * ScatterCos(zu, d) / d2;
        if (c.isBlack()) return;
        ++connections;
        c *= Transmittance(ctx, y, AsInteraction(y), AsInteraction(zu), mrng);
        if (c.isBlack()) return;
        // Light side: o_i from z_u, o_{i-1} from y_i's BSDF with z_u as its successor.
        const Float oi = PdfArea(ctx, zu, &bu, &zp, y, TransportMode::Radiance);
        const Float oim1 = ScatterPdf(y, by, -d, Vec3(y.wo), TransportMode::Radiance) * lv.prevGeom;
        const Float SL = VCMLightSum(lv, oi, oim1, terms.H, weights.sigma(&by), weights);
        // Camera side: other(z_u) from y_i's BSDF, other(z_{u-1}) from z_u's BSDF with y_i as predecessor.
        const Float oz = ConvertDensity(ScatterPdf(y, by, Vec3(y.wo), -d, TransportMode::Importance), y, zu);
        const Float oPrev = PdfArea(ctx, zu, &bu, &y, zp, TransportMode::Importance);
        L += c / (1 + SL + SC(terms, oz, oPrev, gu));
    }

    // Merges at z_u with every light vertex within r (Eq. 11).
    void merge(int u, const VCMCameraTerms &terms) {
        const PathVertex &zu = z[u], &zp = z[u - 1];
        const BSDF &bu = zb[u];
        Spectrum Lm(0);
        const Float etaU = eta[u];
        ForEachMergeCandidate(in.grid_, in.vertices_, zu, std::sqrt(etaU / in.kernel_.piN), in.set_.normalFilter,
                              [&](uint32_t, const LightVertex &lv) {
            if (lv.inMedium() || int(lv.depth) + u - 1 > in.set_.maxDepth) return;  // merging on surfaces only
            const Vec3 wi = lv.wo;  // towards y_{m-1}
            const Spectrum f = bu.f(Vec3(zu.wo), wi, TransportMode::Radiance);
            if (f.isBlack()) return;
            ++merges;
            Float weight = 1;
            if (in.connecting_) {
                // w_VM = eta_u o(z_u) / (c + S_L(m-1) + S_C(u)), o(z_u) = pdfFwd of y_m (vcm.h);
                // eta at y_{m-1} (the junction of S_L) = eta_u sigma(z_u).
                const Float oz = Remap(lv.pdfFwd);
                const Float om1 = bu.pdf(Vec3(zu.wo), wi, TransportMode::Radiance) * lv.prevGeom;
                const Float SL = VCMLightPrevSum(lv, om1, terms.H, weights);  // S_L(m-1)
                const Float cRef = VCMPrevConnectible(lv) ? 1 : 0;  // the connection of y_{m-1} and z_u
                const Float oPrev = ConvertDensity(bu.pdf(wi, Vec3(zu.wo), TransportMode::Importance), zu, zp);
                weight = Mis(etaU * oz, power) / (cRef + SL + SC(terms, oz, oPrev, true));
            }
            Lm += lv.throughput() * f * weight;
        });
        // beta_L f beta_C / (pi r_u^2 N) (Eq. 5 with the uniform disk kernel).
        L += zu.throughput() * Lm / etaU;
    }

    const VCMIntegrator &in;
    const BidirContext &ctx;
    Sampler &sampler;
    Arena &arena;
    const int maxCam;
    PathVertex *z;
    BSDF *zb;
    RNG mediaRng;
    RNG *mrng;
    int nC;
    bool power;
    int64_t own;  // index of the pixel's own light subpath
    VCMWeights weights;
    Float *Bc, *eta;
    uint64_t merges = 0, connections = 0;
    Spectrum L = Spectrum(0);
};

void VCMIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    Ray ray;
    const Float w = scene_->camera->generateRay(cs, &ray);
    if (w == 0) return;
    CameraPath path(*this, cs, ray, sampler, arena, rec.pixel());
    const PathVertex *z = path.z;
    bool specularChain = true;  // z_1 .. z_{u-1} all specular (vm mode)
    for (int u = 1; u < path.nC; ++u) {
        const PathVertex &zu = z[u];
        const BSDF &bu = path.zb[u];
        const VCMCameraTerms terms = VCMCameraAt(ctx_, z, path.zb, u, path.Bc[u], path.eta, path.weights);
        path.emission(u, terms, specularChain);
        if (!zu.scatters() || (zu.type == VertexType::Surface && !bu)) break;
        const bool connectible = IsConnectible(zu, &bu);
        const bool gu = merging_ && zu.type == VertexType::Surface;  // merging at z_u is a strategy
        if (connectible && connecting_) {
            path.nextEvent(u, terms, gu);
            path.connectOwnLightSubpath(u, terms, gu);
        }
        if (merging_ && IsMergeable(zu, &bu) && path.eta[u] > 0) {
            path.merge(u, terms);
            if (!connecting_) break;  // vm: merge at the first non-specular vertex only
        }
        specularChain = specularChain && zu.delta();
    }
    nMerges_ += path.merges;
    nConnections_ += path.connections;
    rec.addRadiance(path.L * w);
}

std::string VCMIntegrator::statistics() const {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "vcm: mode %s, kernel %s, initial radius %.4g (last %.4g), %d iterations, %.3g light vertices per iteration "
                  "(%zu bytes each, grid %.1f MB), %llu merges, %llu connections%s%s",
                  set_.mode == VCMMode::VCM ? "vcm" : set_.mode == VCMMode::VC ? "vc" : "vm", KernelName(set_).c_str(), radius1_, radius_,
                  passes_, passes_ ? double(nLightVertices_) / passes_ : 0.0, sizeof(LightVertex),
                  grid_.bytes() / 1e6, (unsigned long long)nMerges_.load(), (unsigned long long)nConnections_.load(),
                  skipped_.empty() ? "" : "; ", skipped_.c_str());
    return std::string(buf) + "\n";
}

}  // namespace gradus
