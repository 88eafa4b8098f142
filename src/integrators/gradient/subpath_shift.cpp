#include "integrators/gradient/subpath_shift.h"

#include <cstdio>

namespace gradus {

namespace {

Float ChainCos0(const ManifoldChain &c) {
    Vec3 d = c.v[1].sp.p - c.v[0].sp.p;
    return AbsDot(Normalize(d), Vec3(c.v[0].sp.n));
}

}  // namespace

// Re-traces the offset interior from `off`'s start through the walked
// positions and evaluates each vertex with the base's event: the Dirac lobe of
// an ideal specular vertex, f and the solid-angle density of a glossy one.
// The offset path ends at `end` (the base's x_c), not at the walk's end (within
// its tolerance): a glossy vertex is evaluated towards the path's own vertex,
// as its MIS densities are (near grazing reflection, a walk tolerance of 1e-5
// moves the half-vector by ~1/|w_i + w_o| times more, a lobe width of a
// roughness-5e-4 BSDF).
bool EvaluateWalked(const Scene &scene, const ManifoldChain &off, const Point3 &end, const bool *transmit,
                    const int *geomIds, Arena &arena, TransportMode mode, WalkedInterior *w) {
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
        BSDF &b = w->bsdf[j - 1];
        b = si.material->getBSDF(si, arena, mode);
        if (!b) return false;
        Vec3 wn = Normalize((j == k ? end : off.v[j + 1].sp.p) - si.p);
        if (off.v[j].specular) {
            BSDFSample s;
            if (!DeltaLobe(b, si.wo, transmit[j - 1], mode, &s) || Dot(s.wi, wn) < 1 - 1e-3) return false;
            w->fcos[j - 1] = s.f * AbsDot(s.wi, Vec3(b.ns()));
            w->pdf[j - 1] = s.pdf;
            w->factor *= w->fcos[j - 1];
            w->prob *= s.pdf;
        } else {
            if (Transmits(si.wo, wn, Vec3(b.ns())) != transmit[j - 1]) return false;
            w->fcos[j - 1] = b.f(si.wo, wn, mode) * AbsDot(wn, Vec3(b.ns()));
            w->pdf[j - 1] = b.pdf(si.wo, wn, mode);
            if (w->fcos[j - 1].isBlack() || !(w->pdf[j - 1] > 0)) return false;
        }
        prev = si.p;
    }
    return true;
}


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

Float ChainDirectionsPerArea(const ManifoldChain &c) {
    // Segments [a, e] end at each glossy interior vertex and at the chain's end.
    Float phi = 1;
    bool glossy = false;
    for (int a = 0, e = 1; e < c.size; ++e) {
        if (e < c.size - 1 && c.v[e].specular) continue;
        glossy |= e < c.size - 1;
        ManifoldChain seg;
        seg.size = e - a + 1;
        for (int i = a; i <= e; ++i) seg.v[i - a] = c.v[i];
        Float s = ChainSolidAnglePerArea(seg);
        if (!(s > 0)) return 0;
        phi *= s;
        a = e;
    }
    // |dx_g/dO_g| with both ends fixed (G-MLT Eq. 14; ideal specular vertices eliminated).
    return glossy ? phi * HalfVectorJacobian(c) : phi;
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
            // eta inside / outside (of the shading normal's side).
            Float etaIn = b.eta();
            if (interior.specular[j]) {
                BSDFSample s;
                if (!DeltaLobe(b, wo, true, TransportMode::Radiance, &s)) return false;
                etaIn = Dot(wo, Vec3(b.ns())) > 0 ? s.eta : 1 / s.eta;
            }
            if (etaIn == 1) return false;  // an interface whose index the BSDF does not report
            ctx.mscene->recordEta(sp.primitiveId, etaIn);
            sp.etaInterior = etaIn;
            sp.etaExterior = 1;
            if (Dot(Vec3(sp.n), Vec3(b.ns())) < 0) std::swap(sp.etaInterior, sp.etaExterior);
        }
        pts[j + 1] = sp;
        refl[j] = !tr;
        spec[j] = interior.specular[j];
    }
    pts[k + 1] = end;
    if (!MakeChain(pts, k + 2, refl, spec, chain)) return false;
    // A glossy vertex's half-vector offset is measured in a frame field that
    // depends on the surface point only (one fixed reference axis for all
    // chains), not on the base's dpdu: the walk copies a chain's reference
    // axes to the offset, and the shift back starts from a chain built on the
    // offset, so only a common field makes T_ji(T_ij(x)) = x (measured without
    // it: 1 of 96 glossy-chain pairs came back 1.6e-3 away). Ideal specular
    // vertices have o = 0 in every frame.
    static const Vec3 kGlossyFrameRef = Normalize(Vec3(0.5377, 0.2513, 0.8046));
    for (int j = 0; j < k; ++j)
        if (!spec[j]) {
            ManifoldVertex &v = chain->v[j + 1];
            SetupManifoldVertex(&v, v.sp, &kGlossyFrameRef);
            bool ok = false;
            v.o = ProjectedHalfVector(*chain, j + 1, &ok);
            if (!ok) return false;
        }
    return true;
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
    // A glossy vertex's BSDF sees the walk's residual: near grazing reflection
    // the half-vector moves by ~1/|w_i + w_o| times the direction error, and a
    // lobe of roughness 5e-4 is as narrow as that at the default tolerance
    // (1e-5; measured: densities off by 2x, rho_ij rho_ji off by 11%). Such
    // chains are walked to 1e-11 (hits are refined in double; Newton converges
    // quadratically, so this costs an iteration or two).
    bool glossy = false;
    for (int i = 1; i + 1 < base.size; ++i) glossy |= !base.v[i].specular;
    ManifoldWalkOptions opts = ctx.walk;
    if (glossy) opts.relativeTolerance = std::min<Float>(opts.relativeTolerance, 1e-11);
    ManifoldWalkResult res = ManifoldWalk(*ctx.mscene, base, start, base.back().sp, opts);
    if (res.ok()) res.status = CheckReversible(*ctx.mscene, base, res.chain, opts, 1e-4);
    st->recordWalk(res);
    if (!res.ok()) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    Float ax = ChainDirectionsPerArea(base), ay = ChainDirectionsPerArea(res.chain);
    if (!(ax > 0) || !(ay > 0) ||
        !EvaluateWalked(*ctx.bidir->scene, res.chain, base.back().sp.p, interior.transmit, interior.geomId, arena,
                        TransportMode::Radiance, walked)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    // The offset's interior must have the base's vertex classes, or the shift
    // back would take another plan (not a bijection).
    for (int j = 0; j < base.size - 2; ++j)
        if (ClassifyBSDF(&walked->bsdf[j], ctx.threshold) == ShiftVertexClass::Rough) {
            st->shift.fail(ShiftFailure::ClassMismatch);
            return false;
        }
    *J = ay / ax;
    *offset = res.chain;
    return true;
}

}  // namespace gradus
