#include "integrators/manifold/chain_shift.h"

#include "materials/material.h"
#include "scene/scene.h"

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

// sample() with the lobe-selection number at its extremes picks the reflection
// or the refraction lobe.
bool DeltaLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *s) {
    Float uc = transmit ? Float(1) - Float(1e-9) : Float(0);
    if (!bsdf.sample(wo, uc, Point2(0.5, 0.5), mode, s)) return false;
    return s->isSpecular() && s->pdf > 0 && bool(s->isTransmission()) == transmit && !s->f.isBlack();
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

bool BuildChain(const ManifoldSettings &ctx, const ManifoldSurfacePoint &start, const ChainInterior &interior, int k,
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

// A walk back from the offset must return the base within this (relative to the
// scene scale; walks converge to 1e-7).
constexpr Float kReverseTolerance = 1e-4;

ChainShiftFailure ShiftChain(const ManifoldSettings &s, const Scene &scene, const ManifoldChain &base,
                             const ManifoldSurfacePoint &start, const ManifoldSurfacePoint &target,
                             const ChainInterior &interior, TransportMode mode, Arena &arena,
                             ManifoldWalkResult *walk, WalkedInterior *walked) {
    // A glossy vertex's BSDF sees the walk's residual: near grazing reflection
    // the half-vector moves by ~1/|w_i + w_o| times the direction error, and a
    // lobe of roughness 5e-4 is as narrow as that at the default tolerance
    // (1e-5; measured: densities off by 2x, rho_ij rho_ji off by 11%). Such
    // chains are walked to 1e-11 (hits are refined in double; Newton converges
    // quadratically, so this costs an iteration or two).
    bool glossy = false;
    for (int i = 1; i + 1 < base.size; ++i) glossy |= !base.v[i].specular;
    ManifoldWalkOptions opts = s.walk;
    if (glossy) opts.relativeTolerance = std::min<Float>(opts.relativeTolerance, 1e-11);
    // An end on another surface cannot be walked to (G-VCM: a photon of the
    // kernel on another surface than the base's): no walk.
    if (target.primitiveId != base.back().sp.primitiveId) {
        *walk = ManifoldWalkResult();
        walk->status = ManifoldStatus::InvalidInput;
        return ChainShiftFailure::Walk;
    }
    *walk = ManifoldWalk(*s.mscene, base, start, target, opts);
    if (walk->ok()) walk->status = CheckReversible(*s.mscene, base, walk->chain, opts, kReverseTolerance);
    if (!walk->ok()) return ChainShiftFailure::Walk;
    if (!EvaluateWalked(scene, walk->chain, target.p, interior.transmit, interior.geomId, arena, mode, walked))
        return ChainShiftFailure::Evaluation;
    for (int j = 0; j < base.size - 2; ++j)
        if (walked->bsdf[j].roughnessClass(s.threshold) == RoughnessClass::Rough) return ChainShiftFailure::ClassMismatch;
    return ChainShiftFailure::None;
}

}  // namespace gradus
