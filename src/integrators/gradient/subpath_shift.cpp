#include "integrators/gradient/subpath_shift.h"

#include <cstdio>

namespace gradus {

namespace {

Float ChainCos0(const ManifoldChain &c) {
    Vec3 d = c.v[1].sp.p - c.v[0].sp.p;
    return AbsDot(Normalize(d), Vec3(c.v[0].sp.n));
}

// Re-traces the offset interior from `off`'s start through the walked
// positions and evaluates each ideal specular vertex with the base's event.
bool EvaluateWalked(const Scene &scene, const ManifoldChain &off, const bool *transmit, const int *geomIds,
                    Arena &arena, TransportMode mode, WalkedInterior *w) {
    int k = off.size - 2;
    Point3 prev = off.v[0].sp.p;
    for (int j = 1; j <= k; ++j) {
        Point3 p = off.v[j].sp.p;
        Vec3 d = p - prev;
        Float len = d.length();
        if (!(len > 0)) return false;
        d = d / len;
        SurfaceInteraction &si = w->si[j - 1];
        if (!scene.intersect(Ray(prev + d * (1e-5 * len), d), &si) || si.geomId != geomIds[j - 1] || !si.material ||
            Distance(si.p, p) > 1e-3 * len)
            return false;
        w->bsdf[j - 1] = si.material->getBSDF(si, arena, mode);
        Vec3 wn = Normalize(off.v[j + 1].sp.p - si.p);
        BSDFSample s;
        if (!w->bsdf[j - 1] || !DeltaLobe(w->bsdf[j - 1], si.wo, transmit[j - 1], mode, &s) ||
            Dot(s.wi, wn) < 1 - 1e-3)
            return false;
        w->factor *= s.f * AbsDot(s.wi, Vec3(w->bsdf[j - 1].ns()));
        w->prob *= s.pdf;
        prev = si.p;
    }
    return true;
}

}  // namespace

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
    unsupportedChains += o.unsupportedChains;
    for (size_t i = 0; i < size_t(ManifoldStatus::Count); ++i) walkStatus[i] += o.walkStatus[i];
}

std::string SubpathShiftStats::formatWalks(bool walksTried) const {
    std::string s;
    if (!walksTried) s += "  manifold walks: skipped (no specular or near-specular surfaces)\n";
    char buf[256];
    std::snprintf(buf, sizeof buf, "  manifold walks %llu, failures %llu; second chains with glossy vertices "
                                   "(fallback) %llu\n",
                  (unsigned long long)walks, (unsigned long long)walkFailures, (unsigned long long)unsupportedChains);
    s += buf;
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

Float ChainSolidAnglePerArea(const ManifoldChain &c) {
    Float c0 = ChainCos0(c);
    Float g = GeneralizedGeometryTerm(c);
    return c0 > 0 && std::isfinite(g) ? g / c0 : 0;
}

Float EyeAreaFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb, const Vec3 &ngb) {
    Vec3 d = pb - lens;
    Float D2 = d.lengthSquared();
    d = d / std::sqrt(D2);
    Float cb = AbsDot(ngb, d), ct = AbsDot(n0, d);
    return cb > 0 ? ct * ct * ct * D2 / cb : Float(0);
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

// sample() with the lobe-selection number at its extremes picks the reflection
// or the refraction lobe.
bool DeltaLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *s) {
    Float uc = transmit ? Float(1) - Float(1e-9) : Float(0);
    if (!bsdf.sample(wo, uc, Point2(0.5, 0.5), mode, s)) return false;
    return s->isSpecular() && s->pdf > 0 && bool(s->isTransmission()) == transmit && !s->f.isBlack();
}

bool VertexInteraction(const Scene &scene, const PathVertex &v, const Point3 &from, SurfaceInteraction *si) {
    if (v.type != VertexType::Surface || v.geomId < 0) return false;
    const GeometryRecord &g = scene.geometry[v.geomId];
    if (g.mesh) {
        g.mesh->interaction(v.primId, v.b1, v.b2, v.wo, si);
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

ManifoldSurfacePoint EndpointSP(const Point3 &p, const Vec3 &ng, int geomId) {
    ManifoldSurfacePoint sp;
    sp.p = p;
    sp.n = ng;
    Vec3 s, t;
    CoordinateSystem(ng, &s, &t);
    sp.dpdu = s;
    sp.dpdv = t;
    sp.primitiveId = geomId;
    return sp;
}

bool BuildChain(const SubpathShiftContext &ctx, const ManifoldSurfacePoint &start, const ChainInterior &interior, int k,
                const ManifoldSurfacePoint &end, ManifoldChain *chain) {
    ManifoldSurfacePoint pts[kMaxManifoldVertices];
    bool refl[kMaxManifoldVertices], spec[kMaxManifoldVertices];
    if (k + 2 > kMaxManifoldVertices) return false;
    pts[0] = start;
    for (int j = 0; j < k; ++j) {
        ManifoldSurfacePoint sp = ctx.mscene->fromInteraction(interior.si[j]);
        const BSDF &b = *interior.bsdf[j];
        const Vec3 &wo = interior.wo[j];
        bool tr = Transmits(wo, interior.wi[j], Vec3(sp.n));
        if (tr) {
            BSDFSample s;
            if (!DeltaLobe(b, wo, true, TransportMode::Radiance, &s)) return false;
            Float etaIn = Dot(wo, Vec3(b.ns())) > 0 ? s.eta : 1 / s.eta;
            ctx.mscene->recordEta(sp.primitiveId, etaIn);
            sp.etaInterior = etaIn;
            sp.etaExterior = 1;
            if (Dot(Vec3(sp.n), Vec3(b.ns())) < 0) std::swap(sp.etaInterior, sp.etaExterior);
        }
        pts[j + 1] = sp;
        refl[j] = !tr;
        spec[j] = true;
    }
    pts[k + 1] = end;
    return MakeChain(pts, k + 2, refl, spec, chain);
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
    ManifoldWalkResult res = ManifoldWalk(*ctx.mscene, base, start, base.back().sp, ctx.walk);
    if (res.ok()) res.status = CheckReversible(*ctx.mscene, base, res.chain, ctx.walk, 1e-4);
    st->recordWalk(res);
    if (!res.ok()) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    Float ax = ChainSolidAnglePerArea(base), ay = ChainSolidAnglePerArea(res.chain);
    if (!(ax > 0) || !(ay > 0) ||
        !EvaluateWalked(*ctx.bidir->scene, res.chain, interior.transmit, interior.geomId, arena,
                        TransportMode::Radiance, walked)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    *J = ay / ax;
    *offset = res.chain;
    return true;
}

}  // namespace gradus
