#include "integrators/gradient/subpath_shift.h"

#include <cstdio>

namespace gradus {




void SubpathShiftStats::recordWalk(const ManifoldWalkResult &r) {
    ++walks;
    if (!r.ok()) ++walkFailures;
    ++walkStatus[size_t(r.status)];
}

void SubpathShiftStats::add(const SubpathShiftStats &o) {
    for (int i = 0; i < int(ShiftType::Count); ++i) {
        shift.attempts[i] += o.shift.attempts[i];
        shift.successes[i] += o.shift.successes[i];
    }
    for (int i = 0; i < int(ShiftFailure::Count); ++i) shift.failures[i] += o.shift.failures[i];
    shift.offsetPaths += o.shift.offsetPaths;
    walks += o.walks;
    walkFailures += o.walkFailures;
    glossyChains += o.glossyChains;
    longChains += o.longChains;
    mediaChains += o.mediaChains;
    for (size_t i = 0; i < size_t(ManifoldStatus::Count); ++i) walkStatus[i] += o.walkStatus[i];
}

std::string SubpathShiftStats::formatWalks(bool walksTried) const {
    std::string s;
    if (!walksTried) s += "  manifold walks: skipped (no specular or near-specular surfaces)\n";
    char buf[256];
    std::snprintf(buf, sizeof buf, "  manifold walks %llu, failures %llu; second chains with glossy vertices %llu, "
                                   "too long for a walk (fallback) %llu\n",
                  (unsigned long long)walks, (unsigned long long)walkFailures, (unsigned long long)glossyChains,
                  (unsigned long long)longChains);
    s += buf;
    if (mediaChains) {
        std::snprintf(buf, sizeof buf, "  second chains with specular vertices in a scene with media (fallback) %llu\n",
                      (unsigned long long)mediaChains);
        s += buf;
    }
    for (size_t i = 1; i < size_t(ManifoldStatus::Count); ++i)
        if (walkStatus[i]) {
            std::snprintf(buf, sizeof buf, "    walk failure %-26s %llu\n", ToString(ManifoldStatus(i)),
                          (unsigned long long)walkStatus[i]);
            s += buf;
        }
    return s;
}

bool IsDiffuseVertex(const SubpathShiftContext &ctx, const PathVertex &v, const BSDF *b) {
    if (v.type != VertexType::Surface) return true;
    return b && *b && ClassifyBSDF(b, ctx.threshold) == ShiftVertexClass::Rough;
}

void PrepareSubpath(const SubpathShiftContext &ctx, ShiftSubpath *p) {
    for (int i = 0; i < p->n; ++i) {
        PathVertex &v = p->v[i];
        p->deltaSample[i] = v.delta() ? 1 : 0;
        if (v.type == VertexType::Surface && !IsDiffuseVertex(ctx, v, &p->b[i])) v.flags |= VERTEX_DELTA;
    }
}


Spectrum DiracCameraWalk(const BidirContext &ctx, Ray ray, int maxDepth, RNG &rng, Arena &arena) {
    const Scene &scene = *ctx.scene;
    PathVertex prev;  // the vertex the walk left last (first the lens)
    prev.type = VertexType::Camera;
    prev.p = ray.o;
    Spectrum beta(1), L(0);
    // Vertex j of the camera subpath: depth j - 1 (GenerateCameraSubpath with
    // maxDepth + 2 vertices makes vertices up to maxDepth + 1 and scatters at
    // those up to maxDepth).
    for (int j = 1; j <= maxDepth + 1; ++j) {
        SurfaceInteraction isect;
        const Scene::SurfaceHit h = scene.intersectSurface(&ray, &isect);
        if (h == Scene::SurfaceHit::Stuck) break;
        if (h == Scene::SurfaceHit::Miss) {
            const Ray towards(ray.o, Normalize(ray.d));
            for (const Light *l : scene.infiniteLights) L += beta * l->Le(towards);
            break;
        }
        if (!isect.material) break;
        const BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        PathVertex v;
        MakeSurfaceVertex(ctx, isect, bsdf, &v);
        L += beta * EmittedRadiance(ctx, v, prev);
        if (j == maxDepth + 1 || !bsdf) break;
        const Float uc = Float(rng.uniform());
        const Point2 u2(Float(rng.uniform()), Float(rng.uniform()));
        BSDFSample bs;
        if (!bsdf.sample(isect.wo, uc, u2, TransportMode::Radiance, &bs) || !bs.valid() || !bs.isSpecular()) break;
        beta *= bs.f * (AbsDot(bs.wi, Vec3(v.ns)) / bs.pdf);
        if (beta.isBlack() || !beta.isFinite()) break;
        ray = isect.spawnRay(bs.wi);
        prev = v;
    }
    return L;
}

Float EyeAreaFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb, const Vec3 &ngb) {
    Vec3 d = pb - lens;
    Float D2 = d.lengthSquared();
    d = d / std::sqrt(D2);
    Float cb = AbsDot(ngb, d), ct = AbsDot(n0, d);
    return cb > 0 ? ct * ct * ct * D2 / cb : Float(0);
}

Float EyeVolumeFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb) {
    Vec3 d = pb - lens;
    Float D2 = d.lengthSquared();
    Float ct = AbsDot(n0, d / std::sqrt(D2));
    return ct * ct * ct * D2;
}

Spectrum ScatterValue(const PathVertex &v, const BSDF &b, const Vec3 &wo, const Vec3 &wi, Float *pdf) {
    if (v.type == VertexType::Medium) {
        const Float p = v.medium->phase.p(wo, wi);
        *pdf = p;
        return Spectrum(p);
    }
    *pdf = b.pdf(wo, wi);
    return b.f(wo, wi) * AbsDot(wi, Vec3(b.ns()));
}

Interaction VertexIt(const PathVertex &v) {
    return Interaction(v.p, v.onSurface() ? Vec3(v.ng) : Vec3(0, 0, 0), v.wo);
}

Spectrum SafeDiv(const Spectrum &a, const Spectrum &b) {
    return Spectrum(b.r != 0 ? a.r / b.r : 0, b.g != 0 ? a.g / b.g : 0, b.b != 0 ? a.b / b.b : 0);
}

bool TraceSurface(const Scene &scene, Ray ray, SurfaceInteraction *si) {
    return scene.intersectSurface(&ray, si) == Scene::SurfaceHit::Hit;
}

bool VertexInteraction(const Scene &scene, const PathVertex &v, const Point3 &from, SurfaceInteraction *si) {
    if (v.type != VertexType::Surface || v.geomId < 0) return false;
    const GeometryRecord &g = scene.geometry[v.geomId];
    if (g.mesh) {
        g.meshInteraction(v.primId, v.b1, v.b2, v.wo, si);
        si->p = v.p;
        si->geomId = v.geomId;
        si->primId = v.primId;
        si->material = g.material;
        return true;
    }
    Vec3 d = v.p - from;
    Float len = d.length();
    if (!(len > 0)) return false;
    d = d / len;
    Float eps = 1e-4 * len;
    if (!scene.intersect(Ray(from + d * eps, d), si) || si->geomId != v.geomId) return false;
    return Distance(si->p, v.p) < 1e-3 * len;
}



bool ReconnectToVertex(const Scene &scene, const Point3 &xFrom, const Interaction &yFrom, const PathVertex &target,
                       LocalShiftStats *st, ReconnectionShift *rc) {
    st->attempt(ShiftType::Reconnection);
    ShiftVertex tgt;
    tgt.p = target.p;
    tgt.n = target.onSurface() ? Vec3(target.ng) : Vec3(0, 0, 0);
    if (!ShiftReconnect(xFrom, yFrom.p, tgt, rc)) {
        st->fail(ShiftFailure::Geometry);
        return false;
    }
    if (!scene.unoccluded(yFrom, VertexIt(target))) {
        st->fail(ShiftFailure::Occluded);
        return false;
    }
    return true;
}

bool WalkSecondChain(const SubpathShiftContext &ctx, const ManifoldChain &base, const ManifoldSurfacePoint &start,
                     const ChainInterior &interior, Arena &arena, SubpathShiftStats *st, ManifoldChain *offset,
                     WalkedInterior *walked, Float *J) {
    ManifoldWalkResult res;
    const ChainShiftFailure f =
        ShiftChain(ctx, *ctx.bidir->scene, base, start, base.back().sp, interior, TransportMode::Radiance, arena, &res,
                   walked);
    st->recordWalk(res);
    if (f != ChainShiftFailure::None) {
        st->shift.fail(f == ChainShiftFailure::ClassMismatch ? ShiftFailure::ClassMismatch : ShiftFailure::Geometry);
        return false;
    }
    Float ax = ChainDirectionsPerArea(base), ay = ChainDirectionsPerArea(res.chain);
    if (!(ax > 0) || !(ay > 0)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    *J = ay / ax;
    *offset = res.chain;
    return true;
}

}  // namespace gradus
