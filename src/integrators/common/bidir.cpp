#include "integrators/common/bidir.h"

#include <type_traits>

#include "core/error.h"
#include "core/stats.h"
#include "render/render_loop.h"
#include "shapes/sphere.h"
#include "shapes/triangle.h"

namespace gradus {

namespace {

TransportMode Flip(TransportMode m) {
    return m == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
}

// Directional density of all infinite lights towards w (direction to the light).
Float InfiniteLightDensity(const BidirContext &ctx, const Vec3 &w) {
    Float pdf = 0;
    for (const Light *l : ctx.scene->infiniteLights) pdf += ctx.lightSampler->pmf(l) * l->pdfLi(Interaction(), w);
    return pdf;
}

// Shading-normal correction of the adjoint BSDF (Veach 1997, Eq. 5.17):
// |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|), applied to importance transport.
Float ShadingCorrection(const PathVertex &v, const Vec3 &wo, const Vec3 &wi) {
    Vec3 ng = v.ng, ns = v.ns;
    Float den = AbsDot(wo, ng) * AbsDot(wi, ns);
    if (den == 0) return 0;
    return AbsDot(wo, ns) * AbsDot(wi, ng) / den;
}

void Barycentrics(const GeometryRecord &g, int tri, const Point3 &p, float *b1, float *b2) {
    Point3 c[3];
    g.triangleCorners(tri, c);
    const Point3 &p0 = c[0], &p1 = c[1], &p2 = c[2];
    Vec3 e1 = p1 - p0, e2 = p2 - p0, d = p - p0;
    Float d11 = Dot(e1, e1), d12 = Dot(e1, e2), d22 = Dot(e2, e2), dd1 = Dot(d, e1), dd2 = Dot(d, e2);
    Float den = d11 * d22 - d12 * d12;
    if (den == 0) {
        *b1 = *b2 = 0;
        return;
    }
    *b1 = float((d22 * dd1 - d12 * dd2) / den);
    *b2 = float((d11 * dd2 - d12 * dd1) / den);
}

// What a ray met in a scene with media.
enum class MediaStep { Miss, Surface, Medium, Absorbed, Stuck };

// Traces *ray through the interfaces (surfaces without a material), sampling a
// scattering distance in the medium of each segment (pbrt-v3's
// Medium::Sample); *beta takes the factors, *medium the medium at the end.
MediaStep TraceThroughMedia(const Scene &scene, Ray *ray, const Medium **medium, UniformSource rng,
                            SurfaceInteraction *isect, MediumInteraction *mi, Spectrum *beta, Spectrum *segF) {
    for (int k = 0;; ++k) {
        const bool hit = scene.intersect(*ray, isect);
        if (*medium) {
            Ray seg = *ray;  // up to the hit (t in units of |d|)
            if (hit) seg.tMax = Dot(isect->p - ray->o, ray->d) / ray->d.lengthSquared();
            const Spectrum f = (*medium)->sample(seg, rng, mi);
            *beta *= f;
            *segF *= f;
            if (beta->isBlack() || !beta->isFinite()) return MediaStep::Absorbed;
            if (mi->valid()) return MediaStep::Medium;
        }
        if (!hit) return MediaStep::Miss;
        if (isect->material) return MediaStep::Surface;
        if (k >= kMaxInterfaceCrossings) return MediaStep::Stuck;
        *medium = isect->mediumAfter(ray->d, *medium);
        *ray = isect->spawnRay(ray->d);
    }
}

// One random walk in progress (RandomWalk): the ray to trace, the throughput,
// the solid-angle density of the next vertex and the medium the ray is in;
// path[n-1] is the last vertex. Compiled with and without media (kMedia: the
// scene has media), so that media-free scenes run no media code.
template <bool kMedia>
struct Walk {
    const BidirContext &ctx;
    const Scene &scene;
    Sampler &sampler;
    Arena &arena;
    const TransportMode mode;
    const int maxVertices;
    PathVertex *path;
    BSDF *bsdfs;
    UniformSource rng;
    Ray ray;
    Spectrum beta;
    const Float beta0;
    Float pdfFwd;
    const Medium *medium;
    int n;
    Spectrum segF{1};  // the distance-sampling factors of the last segment (kMedia)

    // What the next segment met: Miss, Surface or Medium; Absorbed and Stuck end the walk.
    MediaStep trace(SurfaceInteraction *isect, MediumInteraction *mi) {
        if constexpr (!kMedia) {
            const Scene::SurfaceHit h = scene.intersectSurface(&ray, isect);  // through interfaces
            if (h == Scene::SurfaceHit::Stuck) return MediaStep::Stuck;
            return h == Scene::SurfaceHit::Hit ? MediaStep::Surface : MediaStep::Miss;
        }
        else {
            segF = Spectrum(1);
            return TraceThroughMedia(scene, &ray, &medium, rng, isect, mi, &beta, &segF);
        }
    }

    // Russian roulette on the throughput relative to the subpath's start, after
    // vertex v (the n-th); false: the subpath ends.
    bool roulette(PathVertex &v) {
        if (ctx.rrDepth >= 0 && n > ctx.rrDepth + 1 && n < maxVertices) {
            Float uRR = sampler.get1D();
            Float rel = beta0 > 0 ? beta.maxComponent() / beta0 : 1;
            if (rel < 1) {
                Float q = std::max<Float>(0.05, 1 - rel);
                if (uRR < q) return false;
                beta = beta / (1 - q);
                v.rrScale = float(1 / (1 - q));
            }
        }
        return true;
    }

    // A medium vertex: HG phase function (value = pdf, so beta is unchanged),
    // then the next direction; false: the walk ends.
    bool mediumVertex(const MediumInteraction &mi) {
        PathVertex &prev = path[n - 1];
        PathVertex &v = path[n];
        v = PathVertex();
        v.type = VertexType::Medium;
        v.medium = medium;
        v.mediumIndex = MediumIndexOf(scene, medium);
        v.p = mi.p;
        v.wo = -Normalize(ray.d);
        v.setThroughput(beta);
        v.pdfFwd = ConvertDensity(pdfFwd, prev, v);
        bsdfs[n] = BSDF();
        ++n;
        DebugTrace("%s vertex %d: medium %s p (%.6g, %.6g, %.6g) pdfFwd %.4g",
                   mode == TransportMode::Radiance ? "camera" : "light", n - 1, medium->name.c_str(), v.p.x, v.p.y,
                   v.p.z, v.pdfFwd);
        if (n >= maxVertices) return false;
        sampler.get1D();  // the lobe choice of a surface vertex: keeps the dimensions aligned
        const Point2 u2 = sampler.get2D();
        Vec3 wi;
        const Float pdf = medium->phase.sample(Vec3(v.wo), u2, &wi);
        if (!(pdf > 0)) return false;
        pdfFwd = pdf;
        prev.pdfRev = ConvertDensity(pdf, v, prev);  // HG is symmetric: p(wi, wo) = p(wo, wi)
        if (!roulette(v)) return false;
        ray = Ray(v.p, wi, Infinity);
        return true;
    }

    // An escaped camera path ends on the infinite lights.
    void escaped() {
        if (mode != TransportMode::Radiance || scene.infiniteLights.empty()) return;
        PathVertex &v = path[n];
        v = PathVertex();
        v.type = VertexType::Light;
        v.flags = VERTEX_INFINITE;
        v.light = nullptr;
        Vec3 d = Normalize(ray.d);
        v.p = ray.o + d;
        v.ng = -d;
        v.wo = -d;
        v.setThroughput(beta);
        v.pdfFwd = pdfFwd;
        bsdfs[n] = BSDF();
        ++n;
        DebugTrace("camera vertex %d: escaped towards (%.4f, %.4f, %.4f) (infinite lights)", n - 1, d.x, d.y, d.z);
    }

    // A surface vertex at isect, then its BSDF's sampled direction; false: the walk ends.
    bool surfaceVertex(SurfaceInteraction &isect) {
        PathVertex &prev = path[n - 1];
        PathVertex &v = path[n];
        BSDF bsdf = isect.material->getBSDF(isect, arena, mode);
        MakeSurfaceVertex(ctx, isect, bsdf, &v);
        if constexpr (kMedia) v.mediumIndex = MediumIndexOf(scene, medium);
        v.setThroughput(beta);
        v.pdfFwd = ConvertDensity(pdfFwd, prev, v);
        bsdfs[n] = bsdf;
        ++n;
        if (DebugTracing()) {
            const Spectrum tb = v.throughput();
            DebugTrace("%s vertex %d: p (%.6g, %.6g, %.6g) ng (%.3f, %.3f, %.3f) beta (%.4g, %.4g, %.4g) pdfFwd %.4g%s",
                       mode == TransportMode::Radiance ? "camera" : "light", n - 1, v.p.x, v.p.y, v.p.z,
                       double(v.ng.x), double(v.ng.y), double(v.ng.z), tb.r, tb.g, tb.b, v.pdfFwd,
                       bsdf ? "" : " (no BSDF)");
        }
        if (n >= maxVertices || !bsdf) return false;
        return scatter(isect, bsdf, prev, v);
    }

    // Samples the BSDF of surface vertex v (after prev): densities both ways,
    // the throughput's factor and the next ray.
    bool scatter(const SurfaceInteraction &isect, const BSDF &bsdf, PathVertex &prev, PathVertex &v) {
        Vec3 wo = isect.wo;
        Float uc = sampler.get1D();
        Point2 u2 = sampler.get2D();
        BSDFSample bs;
        if (!bsdf.sample(wo, uc, u2, mode, &bs) || !bs.valid()) return false;
        Float pdfRev;
        pdfFwd = bs.pdf;
        if (bs.isSpecular()) {
            v.flags |= VERTEX_DELTA;
            pdfFwd = pdfRev = 0;
        } else {
            pdfRev = bsdf.pdf(bs.wi, wo, Flip(mode));
        }
        beta *= bs.f * (AbsDot(bs.wi, Vec3(v.ns)) / bs.pdf);
        if (mode == TransportMode::Importance) beta *= ShadingCorrection(v, wo, bs.wi);
        prev.pdfRev = ConvertDensity(pdfRev, v, prev);
        if (beta.isBlack() || !beta.isFinite()) return false;
        if (!roulette(v)) return false;
        if constexpr (kMedia) medium = isect.mediumAfter(bs.wi, medium);
        ray = isect.spawnRay(bs.wi);
        return true;
    }
};

// Random walk shared by both subpaths (Veach 1997, Sec. 10.2): path[n-1] is the
// origin; fills vertices n.. up to maxVertices, setting pdfFwd of each new
// vertex and pdfRev of its predecessor.
// With media, each segment samples a scattering distance in its medium
// (`medium`, distances from *rng); a scattering there is a medium vertex.
template <bool kMedia>
int RandomWalkT(const BidirContext &ctx, const Ray &ray, const Spectrum &beta, Float pdfDir, Sampler &sampler,
                Arena &arena, TransportMode mode, int n, int maxVertices, PathVertex *path, BSDF *bsdfs,
                const Medium *medium, UniformSource rng, Spectrum *segFactors) {
    GRADUS_STAT_COUNTER("BDPT/Subpath vertices", nVerts);
    const Scene &scene = *ctx.scene;
    GRADUS_CHECK(!kMedia || rng);
    Walk<kMedia> w{ctx, scene, sampler, arena, mode, maxVertices, path, bsdfs, rng,
                   ray, beta, beta.maxComponent(), pdfDir, medium, n};
    while (w.n < maxVertices) {
        SurfaceInteraction isect;
        MediaStep st;
        if constexpr (kMedia) {
            GRADUS_STAT_COUNTER("BDPT/Medium vertices", nMediumVerts);
            MediumInteraction mi;
            st = w.trace(&isect, &mi);
            if (segFactors) segFactors[w.n] = w.segF;  // the segment towards vertex w.n (if one is made)
            if (st == MediaStep::Medium) {
                ++nVerts;
                ++nMediumVerts;
                if (!w.mediumVertex(mi)) break;
                continue;
            }
        } else {
            st = w.trace(&isect, nullptr);
        }
        if (st == MediaStep::Absorbed || st == MediaStep::Stuck) break;
        if (st == MediaStep::Miss) {
            w.escaped();
            break;
        }
        ++nVerts;
        if (!w.surfaceVertex(isect)) break;
    }
    return w.n;
}

int RandomWalk(const BidirContext &ctx, const Ray &ray, const Spectrum &beta, Float pdfDir, Sampler &sampler,
               Arena &arena, TransportMode mode, int n, int maxVertices, PathVertex *path, BSDF *bsdfs,
               const Medium *medium, UniformSource rng, Spectrum *segFactors = nullptr) {
    if (ctx.scene->features.media)
        return RandomWalkT<true>(ctx, ray, beta, pdfDir, sampler, arena, mode, n, maxVertices, path, bsdfs, medium,
                                 rng, segFactors);
    return RandomWalkT<false>(ctx, ray, beta, pdfDir, sampler, arena, mode, n, maxVertices, path, bsdfs, medium, rng,
                              nullptr);
}

}  // namespace

void MakeSurfaceVertex(const BidirContext &ctx, const SurfaceInteraction &isect, const BSDF &bsdf, PathVertex *pv) {
    PathVertex &v = *pv;
    v = PathVertex();
    v.type = VertexType::Surface;
    v.material = isect.material;
    v.p = isect.p;
    v.ng = isect.n;
    v.wo = isect.wo;
    v.geomId = isect.geomId;
    v.primId = isect.primId;
    const GeometryRecord &g = ctx.scene->geometry[isect.geomId];
    if (g.mesh) Barycentrics(g, isect.primId, isect.p, &v.b1, &v.b2);
    if (isect.spawnOffset > 0) v.b2 = float(isect.spawnOffset), v.flags |= VERTEX_SPAWN_OFFSET;
    v.ns = bsdf ? bsdf.ns() : isect.shading.n;
}

Interaction AsInteraction(const PathVertex &v) {
    // Light and camera vertices off a surface get no ray offset (zero normal).
    Vec3 n = v.onSurface() ? Vec3(v.ng) : Vec3(0, 0, 0);
    Interaction it(v.p, n, v.wo);
    if (v.flags & VERTEX_SPAWN_OFFSET) it.spawnOffset = v.b2;
    return it;
}

const Medium *MediumAt(const Scene &scene, uint8_t index) {
    return index == 0 ? nullptr : scene.media[size_t(index) - 1].get();
}

uint8_t MediumIndexOf(const Scene &scene, const Medium *m) {
    if (!m) return 0;
    for (size_t i = 0; i < scene.media.size() && i < 255; ++i)
        if (scene.media[i].get() == m) return uint8_t(i + 1);
    GRADUS_CHECK(false);  // more than 255 media: refused by BidirFamily::preprocessBidir
    return 0;
}

const Medium *MediumTowards(const BidirContext &ctx, const PathVertex &v, const Vec3 &d) {
    auto side = [&](const MediumInterface &mi) {
        if (!mi.transition()) return mi.inside;
        return Dot(Vec3(v.ng), d) > 0 ? mi.outside : mi.inside;
    };
    switch (v.type) {
    case VertexType::Camera: return ctx.scene->cameraMedium;
    case VertexType::Medium: return v.medium;
    case VertexType::Light:
        if (!v.light || v.isInfiniteLight()) return nullptr;
        return v.ng.isZero() ? v.light->mediumInterface.inside : side(v.light->mediumInterface);
    case VertexType::Surface: {
        const MediumInterface &mi = ctx.scene->geometry[size_t(v.geomId)].mediumInterface;
        return mi.transition() ? side(mi) : MediumAt(*ctx.scene, v.mediumIndex);
    }
    }
    return nullptr;
}

Spectrum Transmittance(const BidirContext &ctx, const PathVertex &a, const Interaction &ia, const Interaction &ib,
                       UniformSource rng) {
    const Scene &scene = *ctx.scene;
    if (!scene.features.media) return scene.unoccluded(ia, ib) ? Spectrum(1) : Spectrum(0);
    GRADUS_CHECK(rng);
    return scene.transmittance(ia, MediumTowards(ctx, a, ib.p - ia.p), ib, rng);
}

Float ScatterPdf(const PathVertex &v, const BSDF &bsdf, const Vec3 &wo, const Vec3 &wi, TransportMode mode) {
    if (v.type == VertexType::Medium) return v.medium->phase.p(wo, wi);
    return bsdf.pdf(wo, wi, mode);
}

// Veach 1997, Eq. 8.10; densities towards infinite-light vertices stay directional.
Float ConvertDensity(Float pdf, const PathVertex &from, const PathVertex &to) {
    if (to.isInfiniteLight()) return pdf;
    Vec3 w = to.p - from.p;
    Float d2 = w.lengthSquared();
    if (d2 == 0) return 0;
    Float invD2 = 1 / d2;
    if (to.onSurface()) pdf *= AbsDot(Vec3(to.ng), w * std::sqrt(invD2));
    return pdf * invD2;
}

bool IsMergeable(const PathVertex &v, const BSDF *bsdf) {
    GRADUS_CHECK(bsdf);  // merging terms need the BSDFs of the subpaths
    return v.type == VertexType::Surface && *bsdf && bsdf->hasNonSpecular();
}

void AllocSubpath(Arena &arena, int n, PathVertex **v, BSDF **b) {
    *v = static_cast<PathVertex *>(arena.alloc(sizeof(PathVertex) * n, alignof(PathVertex)));
    // Not constructed: the walks assign every vertex and BSDF they create (and
    // only those are read); constructing maxdepth + 2 BSDFs per subpath cost
    // 4.6% of G-BDPT's time at maxdepth 65.
    static_assert(std::is_trivially_copyable_v<BSDF> && std::is_trivially_copyable_v<PathVertex>);
    *b = static_cast<BSDF *>(arena.alloc(sizeof(BSDF) * n, alignof(BSDF)));
}

bool SampleLensVertex(const BidirContext &ctx, const PathVertex &qs, Point2 u, PathVertex *v, CameraWiSample *cws) {
    if (!ctx.camera->sampleWi(AsInteraction(qs), u, cws) || cws->pdf == 0) return false;
    *v = PathVertex();
    v->type = VertexType::Camera;
    v->p = cws->pLens.p;
    v->ng = cws->pLens.n;
    v->ns = cws->pLens.n;
    v->setThroughput(cws->We / cws->pdf);
    v->pdfFwd = 1;
    return true;
}

bool SampleLightVertex(const BidirContext &ctx, const PathVertex &pt, Float uSel, Point2 u, PathVertex *v,
                       LightLiSample *ls, Spectrum *weight) {
    Float pmf;
    const Light *lt = ctx.lightSampler->sample(uSel, &pmf);
    if (!lt || pmf == 0) return false;
    if (!lt->sampleLi(AsInteraction(pt), u, ls) || ls->pdf == 0 || ls->L.isBlack()) return false;
    *v = PathVertex();
    v->type = VertexType::Light;
    v->light = lt;
    if (IsDeltaLight(lt->flags)) v->flags |= VERTEX_DELTA_LIGHT;
    if (lt->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION)) v->flags |= VERTEX_INFINITE;
    v->p = ls->pLight.p;
    v->ng = ls->pLight.n;
    v->ns = ls->pLight.n;
    *weight = ls->L / (ls->pdf * pmf);
    v->setThroughput(*weight);
    v->pdfFwd = PdfLightOrigin(ctx, *v, pt);
    return true;
}

void BidirContext::init(const Scene &s, const LightSampler &ls, MISHeuristic h) {
    scene = &s;
    camera = s.camera.get();
    lightSampler = &ls;
    heuristic = h;
    Point3 c;
    Float r = 0;
    s.bounds.boundingSphere(&c, &r);
    minConnectDist = std::isfinite(r) ? 2e-5 * r : 0;
}

int GenerateCameraSubpath(const BidirContext &ctx, const Ray &ray, Sampler &sampler, Arena &arena,
                          int maxVertices, PathVertex *path, BSDF *bsdfs, UniformSource mediaRng,
                          Spectrum *segFactors) {
    if (maxVertices <= 0) return 0;
    PathVertex &v = path[0];
    v = PathVertex();
    v.type = VertexType::Camera;
    v.p = ray.o;
    v.ng = ctx.camera->lensNormal();
    v.ns = v.ng;
    v.setThroughput(Spectrum(1));
    v.pdfFwd = 1;
    bsdfs[0] = BSDF();
    Float pdfPos, pdfDir;
    // A ray through the film's filter margin (sample bounds beyond the raster)
    // has pdfDir 0: the subpath is still traced (its radiance reaches the
    // image's border pixels through the filter), and x_1's pdfFwd 0 tells the
    // MIS that light tracing cannot produce the path (OtherStrategies). It
    // used to stop here, and the margin's samples added zero radiance with
    // full filter weight: a 2-pixel frame up to 30% dark with a radius-2 filter.
    ctx.camera->pdfWe(ray, &pdfPos, &pdfDir);
    return RandomWalk(ctx, ray, Spectrum(1), pdfDir, sampler, arena, TransportMode::Radiance, 1, maxVertices, path,
                      bsdfs, ctx.scene->cameraMedium, mediaRng, segFactors);
}

RNG CameraSampleMediaRNG(const Sampler &sampler, const CameraSample &cs) {
    return MediaRNG(sampler.seed(), cs.pFilm, cs.pLens);
}

BidirDimensions::BidirDimensions(const Sampler &sampler, int maxCameraVertices, int maxLightVertices)
    : d0_(sampler.dimension()),
      light_(d0_ + kWalkDims * maxCameraVertices),
      connect_(light_ + kLightOriginDims + kWalkDims * maxLightVertices),
      maxLight_(maxLightVertices) {}

void BidirDimensions::startLightSubpath(Sampler &sampler) const {
    if (d0_ < 0) return;
    GRADUS_CHECK(sampler.dimension() <= light_);
    sampler.setDimension(light_);
}

void BidirDimensions::startConnection(Sampler &sampler, int s, int t) {
    if (d0_ < 0) return;
    if (!lightChecked_) {  // the light subpath stayed in its block
        GRADUS_CHECK(sampler.dimension() <= connect_);
        lightChecked_ = true;
    }
    sampler.setDimension(connect_ + kConnectDims * ((t - 1) * (maxLight_ + 1) + s));
}

int GenerateLightSubpath(const BidirContext &ctx, Sampler &sampler, Arena &arena, int maxVertices, PathVertex *path,
                         BSDF *bsdfs, UniformSource mediaRng) {
    Float uSel = sampler.get1D();
    Point2 u1 = sampler.get2D(), u2 = sampler.get2D();
    if (maxVertices <= 0) return 0;
    Float pmf;
    const Light *light = ctx.lightSampler->sample(uSel, &pmf);
    if (!light || pmf == 0) return 0;
    LightLeSample les;
    if (!light->sampleLe(u1, u2, &les) || les.pdfPos == 0 || les.pdfDir == 0 || les.L.isBlack()) return 0;
    PathVertex &v = path[0];
    v = PathVertex();
    v.type = VertexType::Light;
    v.light = light;
    if (IsDeltaLight(light->flags)) v.flags |= VERTEX_DELTA_LIGHT;
    bool infinite = light->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION);
    if (infinite) v.flags |= VERTEX_INFINITE;
    v.p = les.p;  // on the emitter's surface (the ray's origin is offset from it)
    v.ng = les.nLight;
    v.ns = les.nLight;
    v.setThroughput(les.L);
    v.pdfFwd = les.pdfPos * pmf;
    bsdfs[0] = BSDF();
    Float cosL = les.nLight == Normal3(0, 0, 0) ? 1 : AbsDot(les.nLight, les.ray.d);
    Spectrum beta = les.L * (cosL / (pmf * les.pdfPos * les.pdfDir));
    const Medium *medium = ctx.scene->features.media ? MediumTowards(ctx, v, les.ray.d) : nullptr;
    int n = RandomWalk(ctx, les.ray, beta, les.pdfDir, sampler, arena, TransportMode::Importance, 1, maxVertices,
                       path, bsdfs, medium, mediaRng);
    if (infinite) {
        // Infinite/distant lights: the origin density is directional and the
        // first hit's density is the disk's positional density projected onto it.
        if (n > 1) {
            path[1].pdfFwd = les.pdfPos;
            if (path[1].onSurface()) path[1].pdfFwd *= AbsDot(les.ray.d, Vec3(path[1].ng));
        }
        path[0].pdfFwd = InfiniteLightDensity(ctx, -les.ray.d);
    }
    return n;
}

const Light *EmitterOf(const BidirContext &ctx, const PathVertex &v) {
    if (v.type == VertexType::Light) return v.light;
    if (v.type == VertexType::Surface && v.geomId >= 0) {
        const GeometryRecord &g = ctx.scene->geometry[v.geomId];
        if (!g.areaLights.empty()) return g.areaLights[v.primId];
    }
    return nullptr;
}

bool IsConnectible(const PathVertex &v, const BSDF *bsdf) {
    switch (v.type) {
    case VertexType::Camera: return true;
    case VertexType::Light: return !(v.light && (v.light->flags & LIGHT_DELTA_DIRECTION));
    case VertexType::Surface: return bsdf && bsdf->hasNonSpecular();
    case VertexType::Medium: return true;
    }
    return false;
}

Float PdfLightOrigin(const BidirContext &ctx, const PathVertex &v, const PathVertex &next) {
    Vec3 w = next.p - v.p;
    if (w.lengthSquared() == 0) return 0;
    w = Normalize(w);
    if (v.isInfiniteLight()) return InfiniteLightDensity(ctx, -w);
    const Light *light = EmitterOf(ctx, v);
    if (!light) return 0;
    return ctx.lightSampler->pmf(light) * light->pdfLePosition(Ray(v.p, w), v.ng);
}

Float PdfLightDirection(const BidirContext &ctx, const PathVertex &v, const PathVertex &next) {
    Vec3 w = next.p - v.p;
    Float d2 = w.lengthSquared();
    if (d2 == 0) return 0;
    w = w / std::sqrt(d2);
    Float pdf;
    if (v.isInfiniteLight()) {
        // Positional density on the disk perpendicular to the direction (all
        // infinite/distant lights share the scene's bounding disk).
        const Light *l = v.light ? v.light : (ctx.scene->infiniteLights.empty() ? nullptr : ctx.scene->infiniteLights[0]);
        if (!l) return 0;
        pdf = l->pdfLePosition(Ray(next.p, -w), Normal3(0, 0, 0));
    } else {
        const Light *light = EmitterOf(ctx, v);
        if (!light) return 0;
        Float pdfPos, pdfDir;
        light->pdfLe(Ray(v.p, w), v.ng, &pdfPos, &pdfDir);
        pdf = pdfDir / d2;
    }
    if (next.onSurface()) pdf *= AbsDot(Vec3(next.ng), w);
    return pdf;
}

namespace {
template <bool kMedia>
Float PdfAreaT(const BidirContext &ctx, const PathVertex &cur, const BSDF *bsdf, const PathVertex *prev,
               const PathVertex &next, TransportMode mode) {
    // A light vertex, or an emissive surface vertex used as the origin of a light subpath.
    if (cur.type == VertexType::Light || (cur.type == VertexType::Surface && !prev && EmitterOf(ctx, cur)))
        return PdfLightDirection(ctx, cur, next);
    Vec3 wn = next.p - cur.p;
    if (wn.lengthSquared() == 0) return 0;
    wn = Normalize(wn);
    Float pdf = 0;
    if (cur.type == VertexType::Camera) {
        Float pdfPos;
        ctx.camera->pdfWe(Ray(cur.p, wn), &pdfPos, &pdf);
    } else if (kMedia && cur.type == VertexType::Medium) {
        if (!prev) return 0;
        Vec3 wp = prev->p - cur.p;
        if (wp.lengthSquared() == 0) return 0;
        pdf = cur.medium->phase.p(Normalize(wp), wn);
    } else {
        if (!prev || !bsdf || !*bsdf) return 0;
        Vec3 wp = prev->p - cur.p;
        if (wp.lengthSquared() == 0) return 0;
        pdf = bsdf->pdf(Normalize(wp), wn, mode);
    }
    return ConvertDensity(pdf, cur, next);
}
}  // namespace

Float PdfArea(const BidirContext &ctx, const PathVertex &cur, const BSDF *bsdf, const PathVertex *prev,
              const PathVertex &next, TransportMode mode) {
    if (ctx.scene->features.media) return PdfAreaT<true>(ctx, cur, bsdf, prev, next, mode);
    return PdfAreaT<false>(ctx, cur, bsdf, prev, next, mode);
}

namespace {
template <bool kMedia>
Spectrum EvalBSDFT(const PathVertex &cur, const BSDF &bsdf, const PathVertex &next, TransportMode mode) {
    Vec3 wi = next.p - cur.p;
    if (wi.lengthSquared() == 0) return Spectrum(0);
    wi = Normalize(wi);
    Vec3 wo = cur.wo;
    if (kMedia && cur.type == VertexType::Medium) return Spectrum(cur.medium->phase.p(wo, wi));
    Spectrum f = bsdf.f(wo, wi, mode);
    if (mode == TransportMode::Importance) f *= ShadingCorrection(cur, wo, wi);
    return f;
}
}  // namespace

Spectrum EvalBSDF(const PathVertex &cur, const BSDF &bsdf, const PathVertex &next, TransportMode mode) {
    return EvalBSDFT<true>(cur, bsdf, next, mode);
}

Spectrum EmittedRadiance(const BidirContext &ctx, const PathVertex &v, const PathVertex &towards) {
    if (v.isInfiniteLight()) {
        Vec3 d = Normalize(v.p - towards.p);  // direction from the scene towards the light
        Spectrum Le(0);
        for (const Light *l : ctx.scene->infiniteLights) Le += l->Le(Ray(towards.p, d));
        return Le;
    }
    const Light *light = EmitterOf(ctx, v);
    if (!light || !(light->flags & LIGHT_AREA)) return Spectrum(0);
    Vec3 w = towards.p - v.p;
    if (w.lengthSquared() == 0) return Spectrum(0);
    return static_cast<const AreaLight *>(light)->L(Interaction(v.p, v.ng, v.wo), Normalize(w));
}

BSDF RebuildBSDF(const BidirContext &ctx, const PathVertex &v, TransportMode mode, Arena &arena) {
    if (v.type != VertexType::Surface || v.geomId < 0) return BSDF();
    const GeometryRecord &g = ctx.scene->geometry[v.geomId];
    SurfaceInteraction si;
    if (g.mesh) {
        g.meshInteraction(v.primId, v.b1, v.b2, v.wo, &si);
    } else if (g.curve) {  // u, v (hair's h) from the point and wo, as at the hit
        g.curve->interaction(v.primId, v.p, v.wo, &si);
    } else {
        Vec3 wo = v.wo;
        g.sphere->interaction(Ray(v.p + wo, -wo), 1, &si);
        si.wo = wo;
    }
    si.p = v.p;
    si.material = g.material;
    si.areaLight = g.areaLights.empty() ? nullptr : g.areaLights[v.primId];
    si.geomId = v.geomId;
    si.primId = v.primId;
    return g.material ? g.material->getBSDF(si, arena, mode) : BSDF();
}

bool EdgeConnectible(const BidirContext &ctx, const PathVertex &a, const PathVertex &b) {
    if (a.isInfiniteLight() || b.isInfiniteLight()) return true;
    const Vec3 d = b.p - a.p;
    const Float d2 = d.lengthSquared();
    if (d2 < ctx.minConnectDist * ctx.minConnectDist) return false;
    // An edge in the tangent plane of a surface end (|cos| < 1e-6) carries a
    // geometry term of ~0, but visibility along a surface's own plane is not
    // decided by the ray tracer: light crossed a closed face through such
    // connections (bench/stress camera_in_box). Left out of the estimate and of
    // every MIS sum alike, as near-coincident vertices are.
    auto grazing = [&](const PathVertex &v) { return v.onSurface() && InTangentPlane(v.ng, d); };
    return !grazing(a) && !grazing(b);
}

namespace {

// Sum over every strategy in `set` except the connection (s, t) of
// (n_k p_k / n_st p_st)^beta for the path light[0..s-1] camera[t-1..0]; *ptRevOut
// gets the light-side density of camera[t-1]. mergeMode: the strategy being
// weighted is a merge at camera[t-1] (VCM), so light[s-1] is not known to be
// connectible and its delta flag counts.
template <bool kMedia>
Float OtherStrategies(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s,
                      int t, const PathVertex *sampled, bool mergeMode, Float *ptRevOut, int split = -1,
                      MISSplit *parts = nullptr, Float *etaOwnOut = nullptr) {
    auto Lv = [&](int i) -> const PathVertex & { return (s == 1 && i == 0 && sampled) ? *sampled : light.v[i]; };
    auto Cv = [&](int i) -> const PathVertex & { return (t == 1 && i == 0 && sampled) ? *sampled : camera.v[i]; };
    auto Lb = [&](int i) -> const BSDF * { return light.bsdf ? &light.bsdf[i] : nullptr; };
    auto Cb = [&](int i) -> const BSDF * { return camera.bsdf ? &camera.bsdf[i] : nullptr; };

    // Reverse densities that depend on the other subpath (Veach 1997, Sec. 10.2).
    Float ptRev = 0, ptMinusRev = 0, qsRev = 0, qsMinusRev = 0;
    if (t > 0) {
        const PathVertex &pt = Cv(t - 1);
        if (s > 0)
            ptRev = PdfAreaT<kMedia>(ctx, Lv(s - 1), Lb(s - 1), s > 1 ? &Lv(s - 2) : nullptr, pt,
                                     TransportMode::Importance);
        else if (t > 1)
            ptRev = PdfLightOrigin(ctx, pt, Cv(t - 2));
        if (t > 1) {
            if (s > 0)
                ptMinusRev = PdfAreaT<kMedia>(ctx, pt, Cb(t - 1), &Lv(s - 1), Cv(t - 2), TransportMode::Importance);
            else
                ptMinusRev = PdfLightDirection(ctx, pt, Cv(t - 2));
        }
    }
    if (s > 0) {
        const PathVertex &qs = Lv(s - 1);
        qsRev = PdfAreaT<kMedia>(ctx, Cv(t - 1), Cb(t - 1), t > 1 ? &Cv(t - 2) : nullptr, qs,
                                 TransportMode::Radiance);
        if (s > 1)
            qsMinusRev = PdfAreaT<kMedia>(ctx, qs, Lb(s - 1), &Cv(t - 1), Lv(s - 2), TransportMode::Radiance);
    }
    *ptRevOut = ptRev;
    auto camRev = [&](int i) { return i == t - 1 ? ptRev : (i == t - 2 ? ptMinusRev : Cv(i).pdfRev); };
    auto lightRev = [&](int i) { return i == s - 1 ? qsRev : (i == s - 2 ? qsMinusRev : Lv(i).pdfRev); };
    // Endpoints of a connection are connectible by construction.
    auto camDelta = [&](int i) { return i != t - 1 && Cv(i).delta(); };
    auto lightDelta = [&](int i) { return (mergeMode || i != s - 1) && Lv(i).delta(); };
    auto remap = [](Float f) { return f != 0 ? f : Float(1); };
    const bool power = ctx.heuristic == MISHeuristic::Power;
    auto mis = [&](Float r) { return power ? r * r : r; };
    // Sample counts relative to this strategy's, n_k / n_s (Veach 1997 Sec. 9.2):
    // ri = p_k / p_s becomes n_k p_k / (n_s p_s). Exactly 1 with one sample each.
    const Float nOwn = t == 1 ? set.lightTracingSamples : Float(1);
    const Float relLT = set.lightTracingSamples / nOwn, relOther = 1 / nOwn;
    // Merging at x_j (G-VCM Eq. 12: N p_VM,j = N pi r^2 p_acc p_VC,j): relative to
    // the connection whose endpoint on x_j's side is x_j, eta_VCM times the
    // density of x_j from the other side (Georgiev et al. 2012, Sec. 4.2); a
    // delta density (x_j after a specular vertex: a caustic) counts as 1, as in
    // every ratio here.
    // A kernel whose eta is the same at every vertex takes the constant path.
    const MergeKernel *varying = set.kernel && set.kernel->varies() ? set.kernel : nullptr;
    const Float etaConst = varying ? Float(1) : set.kernel ? set.kernel->piN * set.kernel->r2 : set.mergeFactor;
    const Float eta = set.merging ? etaConst * relOther : 0;
    // With a varying kernel (merge_kernel.h), eta_j of each vertex of the path
    // in camera order (Cv(0) .. Cv(t-1), Lv(s-1) .. Lv(0)); the light origin is no merge.
    const int nPath = s + t;
    Float etaBuf[128];
    std::vector<Float> etaVec;
    Float *etaPath = etaBuf;
    if (set.merging && varying) {
        if (nPath > 128) {
            etaVec.resize(size_t(nPath));
            etaPath = etaVec.data();
        }
        auto pv = [&](int k) -> const PathVertex & { return k < t ? Cv(k) : Lv(s - 1 - (k - t)); };
        auto pb = [&](int k) -> const BSDF * { return k < t ? Cb(k) : Lb(s - 1 - (k - t)); };
        PathMergeEta(*varying, nPath, pv, pb,
                     [&](int k) { return k + 1 < nPath && pb(k) && MergeableIn(set, pv(k), pb(k)); }, etaPath);
        if (etaOwnOut) *etaOwnOut = etaPath[t - 1];
    } else if (etaOwnOut) {
        *etaOwnOut = etaConst;
    }
    auto etaCam = [&](int i) { return varying ? eta * etaPath[i] : eta; };
    auto etaLight = [&](int i) { return varying ? eta * etaPath[t + (s - 1 - i)] : eta; };

    // w = 1 / sum_k (n_k p_k / n_s p_s)^beta with p_k / p_{k+1} = pdfRev / pdfFwd
    // of the vertex that changes sides (Veach 1997 Eq. 10.9).
    Float sumRi = 0;
    // Strategies with fewer camera vertices: (s + t - i, i), connection edge C[i] -- C[i-1].
    Float ri = 1;
    for (int i = t - 1; i > 0; --i) {
        if (i == split && parts) {  // the camera terms with endpoints above `split`, and their ratio product
            parts->shared = sumRi;
            parts->product = mis(ri);
        }
        // ri is the ratio of the connection with camera endpoint C[i]: merging at C[i]
        // (not at the light origin x_0, which C[t-1] is when s = 0).
        if (eta > 0 && !(s == 0 && i == t - 1) && MergeableIn(set, Cv(i), Cb(i))) sumRi += mis(etaCam(i) * remap(camRev(i)) * ri);
        ri *= remap(camRev(i)) / remap(Cv(i).pdfFwd);
        int sp = s + t - i;
        if (sp == 1 && i == 1) continue;  // (1,1) is not evaluated
        if (i == 1 && !set.lightTracing) continue;  // (s + t - 1, 1) not in play
        // x_1 seen through the filter margin, outside the raster (pdfFwd 0,
        // GenerateCameraSubpath): light tracing cannot reach that direction.
        if (i == 1 && Cv(1).pdfFwd == 0 && Cv(0).type == VertexType::Camera) continue;
        if (camDelta(i) || Cv(i - 1).delta()) continue;
        if (!EdgeConnectible(ctx, Cv(i), Cv(i - 1))) continue;
        sumRi += mis(ri * (i == 1 ? relLT : relOther));
    }
    const Float camSum = sumRi;
    // Strategies with fewer light vertices: (i, s + t - i), connection edge L[i-1] -- L[i].
    ri = 1;
    for (int i = s - 1; i >= 0; --i) {
        // ri is the ratio of the connection with light endpoint L[i]: merging at L[i] (i >= 1).
        if (eta > 0 && i >= 1 && MergeableIn(set, Lv(i), Lb(i))) sumRi += mis(etaLight(i) * remap(lightRev(i)) * ri);
        ri *= remap(lightRev(i)) / remap(Lv(i).pdfFwd);
        int tp = s + t - i;
        if (i == 1 && tp == 1) continue;
        bool deltaPrev = i > 0 ? Lv(i - 1).delta() : Lv(0).isDeltaLight();
        if (lightDelta(i) || deltaPrev) continue;
        if (i > 0 && !EdgeConnectible(ctx, Lv(i - 1), Lv(i))) continue;
        sumRi += mis(ri * relOther);  // t' = s + t - i >= 2
    }
    if (parts) parts->shared += sumRi - camSum;  // + the light-side terms
    return sumRi;
}

}  // namespace

namespace {
template <bool kMedia>
Float MISWeightT(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s, int t,
                 const PathVertex *sampled, int split, MISSplit *parts) {
    GRADUS_CHECK(!set.lightTracing || set.lightTracingSamples > 0);
    if (parts) *parts = MISSplit();
    if (t == 1 && !set.lightTracing) return 0;  // not in play
    if (s + t == 2) return 1;
    GRADUS_CHECK(!parts || (SplitSupported(set) && split >= 1 && split + 2 <= t - 1));
    Float ptRev;
    Float w =
        1 / (1 + OtherStrategies<kMedia>(ctx, set, light, camera, s, t, sampled, false, &ptRev, split, parts));
    if (parts) parts->valid = true;
    return w;
}
}  // namespace

Float MISWeight(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s, int t,
                const PathVertex *sampled, int split, MISSplit *parts) {
    if (ctx.scene->features.media) return MISWeightT<true>(ctx, set, light, camera, s, t, sampled, split, parts);
    return MISWeightT<false>(ctx, set, light, camera, s, t, sampled, split, parts);
}

Float CameraPrefixSum(const BidirContext &ctx, const StrategySet &set, SubpathView camera, int split) {
    GRADUS_CHECK(SplitSupported(set) && split >= 1 && split < camera.n);
    // The camera loop of OtherStrategies over i = split .. 1 with ri starting
    // at 1: Q = sum_i allowed_i prod_{j=i}^{split} rho_j, rho_j = pdfRev_j /
    // pdfFwd_j (Veach 1997 Eq. 10.9; Dirac densities remapped to 1), and with
    // merging the merge at each mergeable C[i], eta pdfRev_i prod_{j=i+1}^{split}
    // rho_j (G-VCM Eq. 12; VCM's recursive camera sum, Georgiev et al. 2012,
    // for a constant eta: the strategies of t >= split + 3 have n_s = 1). Stored
    // pdfRev are exact here: vertices below split + 1 are never a connection's
    // endpoint or its predecessor for the strategies MISSplit serves.
    const bool power = ctx.heuristic == MISHeuristic::Power;
    auto mis = [&](Float r) { return power ? r * r : r; };
    auto remap = [](Float f) { return f != 0 ? f : Float(1); };
    const Float eta = !set.merging ? 0 : set.kernel ? set.kernel->piN * set.kernel->r2 : set.mergeFactor;
    const PathVertex *c = camera.v;
    Float ri = 1, sum = 0;
    for (int i = split; i > 0; --i) {
        if (eta > 0 && MergeableIn(set, c[i], camera.bsdf ? &camera.bsdf[i] : nullptr))
            sum += mis(eta * remap(c[i].pdfRev) * ri);
        ri *= remap(c[i].pdfRev) / remap(c[i].pdfFwd);
        if (i == 1 && !set.lightTracing) continue;  // (s + t - 1, 1) not in play
        if (i == 1 && c[1].pdfFwd == 0 && c[0].type == VertexType::Camera) continue;  // filter margin
        if (c[i].delta() || c[i - 1].delta()) continue;
        if (!EdgeConnectible(ctx, c[i], c[i - 1])) continue;
        sum += mis(ri * (i == 1 ? set.lightTracingSamples : Float(1)));
    }
    return sum;
}

Float MergeWeight(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s,
                  int t) {
    GRADUS_CHECK(set.merging && s >= 1 && t >= 2);
    Float ptRev, etaOwn;
    const Float others =
        ctx.scene->features.media
            ? OtherStrategies<true>(ctx, set, light, camera, s, t, nullptr, true, &ptRev, -1, nullptr, &etaOwn)
            : OtherStrategies<false>(ctx, set, light, camera, s, t, nullptr, true, &ptRev, -1, nullptr, &etaOwn);
    // The connection (s, t) itself is a strategy of this path unless light[s-1]
    // is specular or the edge is degenerate.
    const bool vc = (s == 1 || !light.v[s - 1].delta()) && EdgeConnectible(ctx, light.v[s - 1], camera.v[t - 1]);
    const Float own = etaOwn * (ptRev != 0 ? ptRev : Float(1));  // delta: 1, as in the sums
    const Float misOwn = ctx.heuristic == MISHeuristic::Power ? own * own : own;
    return misOwn / ((vc ? 1 : 0) + others);
}

namespace {

// The connection code compiled with and without media (kMedia: the scene has
// media): without, no vertex is a medium vertex and visibility is a shadow ray.
template <bool kMedia>
bool Scatters(const PathVertex &v) {
    if constexpr (kMedia) return v.scatters();
    else return v.type == VertexType::Surface;
}
template <bool kMedia>
Float ScatterCosT(const PathVertex &v, const Vec3 &w) {
    if constexpr (kMedia) return ScatterCos(v, w);
    else return AbsDot(w, Vec3(v.ns));
}
template <bool kMedia>
Spectrum TransmittanceT(const BidirContext &ctx, const PathVertex &a, const Interaction &ia, const Interaction &ib,
                        UniformSource rng) {
    if constexpr (kMedia) return Transmittance(ctx, a, ia, ib, rng);
    else return ctx.scene->unoccluded(ia, ib) ? Spectrum(1) : Spectrum(0);
}

template <bool kMedia>
bool ConnectT(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t, const ConnectSamples &u,
              ConnectResult *res) {
    *res = ConnectResult();
    if (t < 1 || (s == 1 && t == 1)) return false;
    if (t == 1 && !ctx.strategies.lightTracing) return false;
    // An infinite-light vertex ends the camera path: only s = 0 uses it.
    if (s > 0 && camera.v[t - 1].type == VertexType::Light) return false;
    PathVertex sampled;
    bool haveSampled = false;
    Spectrum L(0);
    if (s == 0) {
        const PathVertex &pt = camera.v[t - 1];
        if (t < 2) return false;
        L = pt.throughput() * EmittedRadiance(ctx, pt, camera.v[t - 2]);
    } else if (t == 1) {
        const PathVertex &qs = light.v[s - 1];
        const BSDF *qb = light.bsdf ? &light.bsdf[s - 1] : nullptr;
        if (!IsConnectible(qs, qb) || !Scatters<kMedia>(qs)) return false;
        CameraWiSample cws;
        if (!SampleLensVertex(ctx, qs, u.uLens, &sampled, &cws)) return false;
        haveSampled = true;
        if (!EdgeConnectible(ctx, qs, sampled)) return false;
        L = qs.throughput() * EvalBSDFT<kMedia>(qs, *qb, sampled, TransportMode::Importance) * (cws.We / cws.pdf) *
            ScatterCosT<kMedia>(qs, cws.wi);
        if (L.isBlack()) return false;
        res->shadowRayTraced = !u.knownVisible;
        if (!u.knownVisible) {
            L *= TransmittanceT<kMedia>(ctx, qs, AsInteraction(qs), cws.pLens, u.rng);
            if (L.isBlack()) return false;
        }
        res->splat = true;
        res->pRaster = cws.pRaster;
    } else if (s == 1) {
        const PathVertex &pt = camera.v[t - 1];
        const BSDF *pb = camera.bsdf ? &camera.bsdf[t - 1] : nullptr;
        if (!IsConnectible(pt, pb) || !Scatters<kMedia>(pt)) return false;
        LightLiSample ls;
        Spectrum Lw;
        if (!SampleLightVertex(ctx, pt, u.uLightSelect, u.uLight, &sampled, &ls, &Lw)) return false;
        if (u.infiniteLightsOnly && !sampled.isInfiniteLight()) return false;
        haveSampled = true;
        if (!EdgeConnectible(ctx, sampled, pt)) return false;
        L = pt.throughput() * EvalBSDFT<kMedia>(pt, *pb, sampled, TransportMode::Radiance) * Lw *
            ScatterCosT<kMedia>(pt, ls.wi);
        if (L.isBlack()) return false;
        res->shadowRayTraced = !u.knownVisible;
        if (!u.knownVisible) {
            L *= TransmittanceT<kMedia>(ctx, pt, AsInteraction(pt), ls.pLight, u.rng);
            if (L.isBlack()) return false;
        }
    } else {
        const PathVertex &qs = light.v[s - 1], &pt = camera.v[t - 1];
        const BSDF *qb = light.bsdf ? &light.bsdf[s - 1] : nullptr;
        const BSDF *pb = camera.bsdf ? &camera.bsdf[t - 1] : nullptr;
        if (!IsConnectible(qs, qb) || !IsConnectible(pt, pb)) return false;
        if (!Scatters<kMedia>(qs) || !Scatters<kMedia>(pt)) return false;
        if (!EdgeConnectible(ctx, qs, pt)) return false;
        L = qs.throughput() * EvalBSDFT<kMedia>(qs, *qb, pt, TransportMode::Importance) *
            EvalBSDFT<kMedia>(pt, *pb, qs, TransportMode::Radiance) * pt.throughput();
        if (L.isBlack()) return false;
        // Geometry term with shading-normal cosines (the adjoint correction
        // in EvalBSDF accounts for the geometric ones on the light side).
        Vec3 d = qs.p - pt.p;
        Float d2 = d.lengthSquared();
        d = d / std::sqrt(d2);
        L *= ScatterCosT<kMedia>(qs, d) * ScatterCosT<kMedia>(pt, d) / d2;
        if (L.isBlack()) return false;
        res->shadowRayTraced = !u.knownVisible;
        if (!u.knownVisible) {
            L *= TransmittanceT<kMedia>(ctx, qs, AsInteraction(qs), AsInteraction(pt), u.rng);
            if (L.isBlack()) return false;
        }
    }
    if (L.isBlack()) return false;
    const bool split = u.misParts && u.misSplit >= 1 && u.misSplit + 2 <= t - 1;
    Float w = MISWeightT<kMedia>(ctx, ctx.strategies, light, camera, s, t, haveSampled ? &sampled : nullptr,
                                 split ? u.misSplit : -1, split ? u.misParts : nullptr);
    res->weight = w;
    res->unweighted = L;
    res->L = L * w;
    return w > 0;
}

}  // namespace

bool ConnectBDPT(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t,
                 const ConnectSamples &u, ConnectResult *res) {
    if (ctx.scene->features.media) return ConnectT<true>(ctx, light, camera, s, t, u, res);
    return ConnectT<false>(ctx, light, camera, s, t, u, res);
}

}  // namespace gradus
