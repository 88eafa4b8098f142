#include "integrators/gbdpt/gbdpt_shift.h"

#include <new>

#include "lights/light.h"

namespace gradus {

namespace {

constexpr Float kDirTol = 1e-4;  // 1 - cos between a recomputed and an expected direction

template <typename T>
T *ArenaArray(Arena &arena, int n) {
    T *p = static_cast<T *>(arena.alloc(sizeof(T) * size_t(std::max(n, 1)), alignof(T)));
    for (int i = 0; i < std::max(n, 1); ++i) new (&p[i]) T();
    return p;
}

Interaction AsIt(const PathVertex &v) { return Interaction(v.p, v.onSurface() ? Vec3(v.ng) : Vec3(0, 0, 0), v.wo); }

Spectrum SafeDiv(const Spectrum &a, const Spectrum &b) {
    return Spectrum(b.r != 0 ? a.r / b.r : 0, b.g != 0 ? a.g / b.g : 0, b.b != 0 ? a.b / b.b : 0);
}

// Closest hit that skips material-less interfaces (as the subpath random walk does).
bool TraceSurface(const Scene &scene, Ray ray, SurfaceInteraction *si) {
    bool hit = scene.intersect(ray, si);
    for (int k = 0; hit && !si->material && k < 64; ++k) {
        ray = si->spawnRay(ray.d);
        hit = scene.intersect(ray, si);
    }
    return hit && si->material;
}

bool Transmits(const Vec3 &wo, const Vec3 &wi, const Vec3 &n) { return Dot(wo, n) * Dot(wi, n) < 0; }

// The Dirac lobe of an ideal specular BSDF for a known event (reflection or
// refraction): value f |cos| and discrete probability come from sample() with
// the lobe-selection number at its extremes.
bool DeltaLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *s) {
    Float uc = transmit ? Float(1) - Float(1e-9) : Float(0);
    if (!bsdf.sample(wo, uc, Point2(0.5, 0.5), mode, s)) return false;
    return s->isSpecular() && s->pdf > 0 && bool(s->isTransmission()) == transmit && !s->f.isBlack();
}

// Direction of the offset at a half-vector-chain vertex (Sec. 3.1: the first
// chain is re-traced with the base's half vectors). Returns the throughput
// factor f_y |cos| J / p_x and the MIS ratio factor J p_y / p_x.
bool PropagateHalfVector(const BSDF &bx, const Vec3 &woX, const Vec3 &wiX, bool deltaX, const BSDF &by,
                         const Vec3 &woY, Vec3 *wiY, Spectrum *factor, Float *ratio, GBDPTLocalStats *st) {
    st->shift.attempt(ShiftType::HalfVector);
    if (deltaX) {
        bool tr = Transmits(woX, wiX, Vec3(bx.ns()));
        BSDFSample sx, sy;
        if (!DeltaLobe(bx, woX, tr, TransportMode::Radiance, &sx) || Dot(sx.wi, wiX) < 1 - kDirTol ||
            !DeltaLobe(by, woY, tr, TransportMode::Radiance, &sy)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        *wiY = sy.wi;
        *factor = sy.f * (AbsDot(sy.wi, Vec3(by.ns())) / sx.pdf);
        *ratio = sy.pdf / sx.pdf;
    } else {
        if (Transmits(woX, wiX, Vec3(bx.ns()))) {  // glossy refraction: not supported by the copy
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        HalfVectorShift hv;
        if (!ShiftHalfVector(bx.toLocal(woX), bx.toLocal(wiX), by.toLocal(woY), 1, &hv)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        *wiY = Normalize(by.toWorld(hv.wi));
        Spectrum fy = by.f(woY, *wiY);
        Float py = by.pdf(woY, *wiY), px = bx.pdf(woX, wiX);
        if (fy.isBlack() || !(py > 0) || !(px > 0)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        *factor = fy * (AbsDot(*wiY, Vec3(by.ns())) * hv.jacobian / px);
        *ratio = hv.jacobian * py / px;
    }
    st->shift.success(ShiftType::HalfVector);
    return true;
}

// Surface interaction of a stored vertex (mesh: from barycentrics; else by a ray from `from`).
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

// Endpoint of a chain: geometric normal (area measure), no curvature.
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

Float ChainCos0(const ManifoldChain &c) {
    Vec3 d = c.v[1].sp.p - c.v[0].sp.p;
    return AbsDot(Normalize(d), Vec3(c.v[0].sp.n));
}

// Solid angle at the chain's start per unit area at its end: G / |cos_0| (JM12).
Float SolidAnglePerArea(const ManifoldChain &c) {
    Float c0 = ChainCos0(c);
    Float g = GeneralizedGeometryTerm(c);
    return c0 > 0 && std::isfinite(g) ? g / c0 : 0;
}

// Builds the base chain x[0..k+1] (interior: ideal specular vertices) from
// interactions; records the index of refraction of refracting interiors.
bool BuildChain(const GBDPTShiftContext &ctx, const ManifoldSurfacePoint &start, const SurfaceInteraction *interior,
                const BSDF *const *bsdfs, const Vec3 *wos, const Vec3 *wis, int k, const ManifoldSurfacePoint &end,
                ManifoldChain *chain) {
    ManifoldSurfacePoint pts[kMaxManifoldVertices];
    bool refl[kMaxManifoldVertices], spec[kMaxManifoldVertices];
    if (k + 2 > kMaxManifoldVertices) return false;
    pts[0] = start;
    for (int j = 0; j < k; ++j) {
        ManifoldSurfacePoint sp = ctx.mscene->fromInteraction(interior[j]);
        bool tr = Transmits(wos[j], wis[j], Vec3(sp.n));
        if (tr) {
            BSDFSample s;
            if (!DeltaLobe(*bsdfs[j], wos[j], true, TransportMode::Radiance, &s)) return false;
            Float etaIn = Dot(wos[j], Vec3(bsdfs[j]->ns())) > 0 ? s.eta : 1 / s.eta;
            ctx.mscene->recordEta(sp.primitiveId, etaIn);
            sp.etaInterior = etaIn;
            sp.etaExterior = 1;
            if (Dot(Vec3(sp.n), Vec3(bsdfs[j]->ns())) < 0) std::swap(sp.etaInterior, sp.etaExterior);
        }
        pts[j + 1] = sp;
        refl[j] = !tr;
        spec[j] = true;
    }
    pts[k + 1] = end;
    return MakeChain(pts, k + 2, refl, spec, chain);
}

// Interactions, BSDFs and the specular factors of the walked offset interior.
struct WalkedInterior {
    SurfaceInteraction si[kMaxManifoldVertices];
    BSDF bsdf[kMaxManifoldVertices];
    Spectrum factor{1};  // prod f_y |cos| (Dirac coefficients)
    Float prob = 1;      // prod of discrete lobe probabilities
};

// Re-traces the offset interior from `from` through the walked positions and
// evaluates each ideal specular vertex with the base's event.
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

void RecordWalk(const ManifoldWalkResult &r, GBDPTLocalStats *st) {
    ++st->walks;
    if (!r.ok()) ++st->walkFailures;
    ++st->walkStatus[size_t(r.status)];
}

}  // namespace

Float ChainSolidAnglePerArea(const ManifoldChain &c) { return SolidAnglePerArea(c); }

Float EyeAreaFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb, const Vec3 &ngb) {
    Vec3 d = pb - lens;
    Float D2 = d.lengthSquared();
    d = d / std::sqrt(D2);
    Float cb = AbsDot(ngb, d), ct = AbsDot(n0, d);
    return cb > 0 ? ct * ct * ct * D2 / cb : Float(0);
}

bool IsDiffuseVertex(const GBDPTShiftContext &ctx, const PathVertex &v, const BSDF *b) {
    if (v.type != VertexType::Surface) return true;
    return b && *b && ClassifyBSDF(b, ctx.threshold) == ShiftVertexClass::Rough;
}

void PrepareSubpath(const GBDPTShiftContext &ctx, ShiftSubpath *p) {
    for (int i = 0; i < p->n; ++i) {
        PathVertex &v = p->v[i];
        p->deltaSample[i] = v.delta() ? 1 : 0;
        if (v.type == VertexType::Surface && !IsDiffuseVertex(ctx, v, &p->b[i])) v.flags |= VERTEX_DELTA;
    }
}

void ShiftCameraSubpath(const GBDPTShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                        Arena &arena, CameraShift *out, GBDPTLocalStats *st) {
    const BidirContext &bc = *ctx.bidir;
    const Scene &scene = *bc.scene;
    const int n = x.n;
    out->validUpTo = -1;
    out->r = -1;
    out->y.n = n;
    out->y.v = ArenaArray<PathVertex>(arena, n);
    out->y.b = ArenaArray<BSDF>(arena, n);
    out->y.deltaSample = ArenaArray<uint8_t>(arena, n);
    out->rho = ArenaArray<Float>(arena, n + 1);
    if (n < 2) return;
    ShiftSubpath &y = out->y;
    auto diffuse = [&](int i) { return IsDiffuseVertex(ctx, x.v[i], &x.b[i]); };

    int b = -1, c = -1;
    for (int i = 1; i < n; ++i)
        if (diffuse(i)) {
            if (b < 0) {
                b = i;
            } else {
                c = i;
                break;
            }
        }
    int rec = -1;  // reconnection vertex
    if (ctx.manifold) {
        rec = c;
    } else {
        for (int k = 2; k < n; ++k)
            if (diffuse(k - 1) && diffuse(k)) {
                rec = k;
                break;
            }
    }
    int traceEnd = ctx.manifold ? (b >= 0 ? b : n - 1) : (rec >= 0 ? rec - 1 : n - 1);
    if (!ctx.manifold && b >= 0) {
        // Half-vector shift: a specular vertex between b and the reconnection
        // makes the shift of the whole path a fallback, as for its light-tracing
        // strategy (not shifted across specular chains): a path's strategies must
        // all use Eq. 8 or all fall back, or the weights do not sum to one.
        for (int k = b + 1; k < (rec >= 0 ? rec : n); ++k)
            if (!diffuse(k)) {
                traceEnd = b;
                rec = -1;
                break;
            }
    }

    ++st->shift.offsetPaths;
    Ray rx, ray;
    CameraSample c2 = cs;
    c2.pFilm = Point2(cs.pFilm.x + off.x, cs.pFilm.y + off.y);
    Float wx = bc.camera->generateRay(cs, &rx), wy = bc.camera->generateRay(c2, &ray);
    if (!(wx > 0) || !(wy > 0)) {
        st->shift.fail(ShiftFailure::Geometry);
        return;
    }
    y.v[0] = x.v[0];
    y.v[0].p = ray.o;
    y.deltaSample[0] = 0;
    out->rho[0] = 1;
    out->validUpTo = 0;
    // The image-plane shift has |T'| = 1 and equal pdfs: the offset starts with
    // the camera weight ratio.
    Spectrum beta(wy / wx);
    Float R = 1;
    SurfaceInteraction isect;
    Vec3 woY;
    for (int i = 1; i <= traceEnd; ++i) {
        const PathVertex &xv = x.v[i];
        bool hit = TraceSurface(scene, ray, &isect);
        if (!hit) {
            if (xv.isInfiniteLight() && i == n - 1) {
                PathVertex &v = y.v[i];
                v = xv;
                Vec3 d = Normalize(ray.d);
                v.p = ray.o + d;
                v.ng = -d;
                v.wo = -d;
                v.setThroughput(beta);
                out->rho[i] = R;
                out->validUpTo = i;
            } else {
                st->shift.fail(ShiftFailure::Escaped);
            }
            break;
        }
        if (xv.type != VertexType::Surface) {
            st->shift.fail(ShiftFailure::Escaped);
            break;
        }
        BSDF by = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        bool dy = by && ClassifyBSDF(&by, ctx.threshold) == ShiftVertexClass::Rough;
        if (!by || dy != diffuse(i)) {
            st->shift.fail(ShiftFailure::ClassMismatch);
            break;
        }
        PathVertex &v = y.v[i];
        v = PathVertex();
        v.type = VertexType::Surface;
        v.material = isect.material;
        v.p = isect.p;
        v.ng = isect.n;
        v.ns = by.ns();
        v.wo = isect.wo;
        v.geomId = isect.geomId;
        v.primId = isect.primId;
        v.flags = xv.flags;
        v.setThroughput(beta);
        y.b[i] = by;
        y.deltaSample[i] = x.deltaSample[i];
        out->rho[i] = R;
        out->validUpTo = i;
        woY = isect.wo;
        if (i == traceEnd || i == n - 1) break;
        Vec3 wiX = Normalize(x.v[i + 1].p - xv.p), wiY;
        Spectrum factor;
        Float ratio;
        if (!PropagateHalfVector(x.b[i], xv.wo, wiX, x.deltaSample[i], by, woY, &wiY, &factor, &ratio, st)) break;
        beta *= factor;
        R *= ratio;
        ray = isect.spawnRay(wiY);
    }

    // Reconnection to the base at `rec` through the second chain (or directly).
    const int i = traceEnd;
    if (rec >= 0 && out->validUpTo == i && i >= 1 && rec > i && y.v[i].type == VertexType::Surface) {
        const PathVertex &xi = x.v[i], &xr = x.v[rec];
        const int k = rec - i - 1;  // interior vertices of the second chain
        bool ok = true;
        for (int j = i + 1; j < rec; ++j)
            if (!x.deltaSample[j]) ok = false;
        if (!ok) ++st->unsupportedChains;
        if (xr.isInfiniteLight()) ok = false;
        Spectrum factor(0);
        Float ratio = 0;
        Vec3 wiX = Normalize(x.v[i + 1].p - xi.p), wiY;
        Float J = 0;
        WalkedInterior walked;
        ManifoldChain offChain;
        if (ok && k == 0) {
            st->shift.attempt(ShiftType::Reconnection);
            ShiftVertex tgt;
            tgt.p = xr.p;
            tgt.n = xr.onSurface() ? Vec3(xr.ng) : Vec3(0, 0, 0);
            ReconnectionShift rc;
            if (!ShiftReconnect(xi.p, y.v[i].p, tgt, &rc)) {
                st->shift.fail(ShiftFailure::Geometry);
                ok = false;
            } else if (!scene.unoccluded(AsIt(y.v[i]), AsIt(xr))) {
                st->shift.fail(ShiftFailure::Occluded);
                ok = false;
            } else {
                J = rc.jacobian;
                wiY = rc.wi;
            }
        } else if (ok) {
            // Manifold walk from offset b to base c with the base's half vectors.
            SurfaceInteraction xsi[kMaxManifoldVertices];
            const BSDF *xb[kMaxManifoldVertices];
            Vec3 wos[kMaxManifoldVertices], wis[kMaxManifoldVertices];
            bool tr[kMaxManifoldVertices];
            int gids[kMaxManifoldVertices];
            ok = ctx.trySpecular && k + 2 <= kMaxManifoldVertices;
            for (int j = 0; ok && j < k; ++j) {
                const PathVertex &xv = x.v[i + 1 + j];
                ok = VertexInteraction(scene, xv, x.v[i + j].p, &xsi[j]);
                xb[j] = &x.b[i + 1 + j];
                wos[j] = xv.wo;
                wis[j] = Normalize(x.v[i + 2 + j].p - xv.p);
                tr[j] = Transmits(wos[j], wis[j], Vec3(x.b[i + 1 + j].ns()));
                gids[j] = xv.geomId;
            }
            ManifoldChain base;
            if (ok)
                ok = BuildChain(ctx, EndpointSP(xi.p, xi.ng, xi.geomId), xsi, xb, wos, wis, k,
                                EndpointSP(xr.p, xr.ng, xr.geomId), &base);
            if (!ok) st->shift.fail(ShiftFailure::Geometry);
            if (ok) {
                ManifoldWalkResult res =
                    ManifoldWalk(*ctx.mscene, base, EndpointSP(y.v[i].p, y.v[i].ng, y.v[i].geomId), base.back().sp,
                                 ctx.walk);
                // The walk may converge to another solution of the chain: only
                // reversible walks keep the shift a bijection (JM12 Sec. 5).
                if (res.ok()) res.status = CheckReversible(*ctx.mscene, base, res.chain, ctx.walk, 1e-4);
                RecordWalk(res, st);
                ok = res.ok();
                if (!ok) st->shift.fail(ShiftFailure::Geometry);
                Float ax = ok ? SolidAnglePerArea(base) : 0, ay = ok ? SolidAnglePerArea(res.chain) : 0;
                ok = ok && ax > 0 && ay > 0 &&
                     EvaluateWalked(scene, res.chain, tr, gids, arena, TransportMode::Radiance, &walked);
                if (ok) {
                    J = ay / ax;  // |d omega_y,b / d omega_x,b| with x_c fixed
                    wiY = Normalize(res.chain.v[1].sp.p - y.v[i].p);
                    offChain = res.chain;
                } else if (res.ok()) {
                    st->shift.fail(ShiftFailure::Geometry);
                }
            }
        }
        if (ok) {
            Spectrum fy = y.b[i].f(woY, wiY);
            Float py = y.b[i].pdf(woY, wiY), px = x.b[i].pdf(xi.wo, wiX);
            ok = !fy.isBlack() && py > 0 && px > 0 && J > 0 && std::isfinite(J);
            if (!ok) st->shift.fail(ShiftFailure::Geometry);
            factor = fy * (AbsDot(wiY, Vec3(y.b[i].ns())) * J / px);
            ratio = J * py / px;
        }
        if (ok) {
            if (k == 0) st->shift.success(ShiftType::Reconnection);
            beta *= factor;
            R *= ratio;
            // Walked interior vertices.
            Spectrum betaX0 = x.v[i + 1].throughput();
            for (int j = 0; j < k; ++j) {
                const PathVertex &xv = x.v[i + 1 + j];
                BSDFSample sx;
                bool trj = Transmits(xv.wo, Normalize(x.v[i + 2 + j].p - xv.p), Vec3(x.b[i + 1 + j].ns()));
                if (!DeltaLobe(x.b[i + 1 + j], xv.wo, trj, TransportMode::Radiance, &sx)) {
                    ok = false;
                    break;
                }
                PathVertex &v = y.v[i + 1 + j];
                const SurfaceInteraction &si = walked.si[j];
                v = PathVertex();
                v.type = VertexType::Surface;
                v.material = si.material;
                v.p = si.p;
                v.ng = si.n;
                v.ns = walked.bsdf[j].ns();
                v.wo = si.wo;
                v.geomId = si.geomId;
                v.primId = si.primId;
                v.flags = xv.flags;
                v.setThroughput(beta);
                y.b[i + 1 + j] = walked.bsdf[j];
                y.deltaSample[i + 1 + j] = 1;
                out->rho[i + 1 + j] = R;
                // Dirac coefficient of the offset over the base's lobe probability.
                BSDFSample sy;
                DeltaLobe(walked.bsdf[j], si.wo, trj, TransportMode::Radiance, &sy);
                beta *= sy.f * (AbsDot(sy.wi, Vec3(walked.bsdf[j].ns())) / sx.pdf);
                R *= sy.pdf / sx.pdf;
            }
            (void)betaX0;
        }
        if (ok) {
            // y_rec = x_rec with the offset's incoming direction; later vertices are the base's.
            PathVertex &v = y.v[rec];
            v = xr;
            Point3 prevP = y.v[rec - 1].p;
            v.wo = Normalize(prevP - xr.p);
            v.setThroughput(beta);
            y.b[rec] = x.b[rec];
            y.deltaSample[rec] = x.deltaSample[rec];
            out->rho[rec] = R;
            Float Rn = R;
            Spectrum scale(0);
            if (rec + 1 < n && x.b[rec]) {
                Vec3 wi = Normalize(x.v[rec + 1].p - xr.p);
                Spectrum fyr = x.b[rec].f(v.wo, wi), fxr = x.b[rec].f(xr.wo, wi);
                Float pyr = x.b[rec].pdf(v.wo, wi), pxr = x.b[rec].pdf(xr.wo, wi);
                if (pxr > 0) {
                    Spectrum betaN = beta * fyr * (AbsDot(wi, Vec3(xr.ns)) / pxr);
                    scale = SafeDiv(betaN, x.v[rec + 1].throughput());
                    Rn = R * pyr / pxr;
                }
                (void)fxr;
            }
            for (int j = rec + 1; j < n; ++j) {
                y.v[j] = x.v[j];
                y.v[j].setThroughput(x.v[j].throughput() * scale);
                y.b[j] = x.b[j];
                y.deltaSample[j] = x.deltaSample[j];
                out->rho[j] = Rn;
            }
            out->r = rec;
            out->validUpTo = n - 1;
        }
    }

    // Area densities of the offset in both directions (for its own BDPT weights).
    const int last = out->validUpTo;
    const int fwdEnd = out->r >= 0 ? std::min(out->r + 1, last) : last;
    for (int k = 1; k <= fwdEnd; ++k) {
        const PathVertex &p = y.v[k - 1];
        y.v[k].pdfFwd = y.deltaSample[k - 1]
                            ? 0
                            : PdfArea(bc, p, k - 1 > 0 ? &y.b[k - 1] : nullptr, k - 1 > 0 ? &y.v[k - 2] : nullptr,
                                      y.v[k], TransportMode::Radiance);
    }
    const int revEnd = out->r >= 0 ? out->r - 1 : last;
    for (int k = 1; k <= revEnd; ++k) {
        y.v[k].pdfRev = 0;
        if (k + 2 <= last && !y.deltaSample[k + 1] && y.v[k + 1].type == VertexType::Surface)
            y.v[k].pdfRev = PdfArea(bc, y.v[k + 1], &y.b[k + 1], &y.v[k + 2], y.v[k], TransportMode::Importance);
    }
}

Float LightTracingRatio(const GBDPTShiftContext &ctx, SubpathView light, SubpathView cam, int s, int t,
                        const PathVertex *sampled) {
    const BidirContext &bc = *ctx.bidir;
    if (t < 2 || s + t - 1 < 2) return 0;
    auto Lv = [&](int i) -> const PathVertex & { return (s == 1 && i == 0 && sampled) ? *sampled : light.v[i]; };
    auto Lb = [&](int i) -> const BSDF * { return light.bsdf && !(s == 1 && sampled) ? &light.bsdf[i] : nullptr; };
    const PathVertex &x1 = cam.v[1];
    if (x1.type != VertexType::Surface || !IsDiffuseVertex(ctx, x1, &cam.bsdf[1]) ||
        !EdgeConnectible(bc, x1, cam.v[0]))
        return 0;
    auto remap = [](Float f) { return f != 0 ? f : Float(1); };
    // Reverse densities of the camera vertices t-1 and t-2 given the light side.
    const PathVertex &pt = cam.v[t - 1];
    Float revT1 = 0, revT2 = 0;
    if (s > 0) {
        revT1 = PdfArea(bc, Lv(s - 1), Lb(s - 1), s > 1 ? &Lv(s - 2) : nullptr, pt, TransportMode::Importance);
        revT2 = PdfArea(bc, pt, &cam.bsdf[t - 1], &Lv(s - 1), cam.v[t - 2], TransportMode::Importance);
    } else {
        revT1 = PdfLightOrigin(bc, pt, cam.v[t - 2]);
        revT2 = PdfLightDirection(bc, pt, cam.v[t - 2]);
    }
    Float r = 1;
    for (int i = t - 1; i >= 1; --i) {
        Float rev = i == t - 1 ? revT1 : (i == t - 2 ? revT2 : cam.v[i].pdfRev);
        r *= remap(rev) / remap(cam.v[i].pdfFwd);
    }
    return std::isfinite(r) ? r : 0;
}

bool SampleLightPoint(const GBDPTShiftContext &ctx, const PathVertex &pt, Float uSel, Point2 u, LightPoint *lp) {
    const BidirContext &bc = *ctx.bidir;
    Float pmf;
    const Light *lt = bc.lightSampler->sample(uSel, &pmf);
    if (!lt || pmf == 0) return false;
    LightLiSample ls;
    if (!lt->sampleLi(AsIt(pt), u, &ls) || ls.pdf == 0 || ls.L.isBlack()) return false;
    PathVertex &s = lp->v;
    s = PathVertex();
    s.type = VertexType::Light;
    s.light = lt;
    lp->delta = IsDeltaLight(lt->flags);
    lp->infinite = lt->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION);
    if (lp->delta) s.flags |= VERTEX_DELTA_LIGHT;
    if (lp->infinite) s.flags |= VERTEX_INFINITE;
    s.p = ls.pLight.p;
    s.ng = ls.pLight.n;
    s.ns = ls.pLight.n;
    s.setThroughput(ls.L / (ls.pdf * pmf));
    s.pdfFwd = PdfLightOrigin(bc, s, pt);
    lp->light = lt;
    lp->pmf = pmf;
    lp->pdf = ls.pdf;
    lp->Li = ls.L;
    lp->basePoint = pt.p;
    lp->u = u;
    return true;
}

bool ConnectLightPoint(const GBDPTShiftContext &ctx, const LightPoint &lp, SubpathView cam, int t,
                       ConnectResult *res) {
    *res = ConnectResult();
    const BidirContext &bc = *ctx.bidir;
    const PathVertex &pt = cam.v[t - 1];
    const BSDF *pb = cam.bsdf ? &cam.bsdf[t - 1] : nullptr;
    if (pt.type != VertexType::Surface || !IsConnectible(pt, pb) || lp.infinite) return false;
    PathVertex s = lp.v;
    if (!EdgeConnectible(bc, s, pt)) return false;
    Vec3 d = s.p - pt.p;
    Float d2 = d.lengthSquared();
    if (!(d2 > 0)) return false;
    Vec3 wi = d / std::sqrt(d2);
    Spectrum Li;  // radiance over the base's light-sampling density (area measure, Eq. 8 pairs)
    if (lp.delta) {
        LightLiSample ls;
        if (!lp.light->sampleLi(AsIt(pt), lp.u, &ls) || ls.pdf == 0) return false;
        Li = ls.L / (ls.pdf * lp.pmf);
    } else {
        if (!(lp.light->flags & LIGHT_AREA)) return false;
        Spectrum Le = static_cast<const AreaLight *>(lp.light)->L(Interaction(s.p, s.ng, -wi), -wi);
        Float cosY = AbsDot(Vec3(s.ng), wi);
        Vec3 dx = s.p - lp.basePoint;
        Float d2x = dx.lengthSquared();
        Float cosX = AbsDot(Vec3(s.ng), dx / std::sqrt(d2x));
        if (!(cosX > 0)) return false;
        // p_A(base) = pdf_omega |cos_x| / d_x^2; the offset's geometry |cos_y| / d_y^2.
        Li = Le * ((cosY / d2) / (lp.pmf * lp.pdf * cosX / d2x));
    }
    Spectrum L = pt.throughput() * EvalBSDF(pt, *pb, s, TransportMode::Radiance) * Li * AbsDot(wi, Vec3(pt.ns));
    if (L.isBlack()) return false;
    res->shadowRayTraced = true;
    if (!bc.scene->unoccluded(AsIt(pt), Interaction(s.p, s.ng, -wi))) return false;
    s.pdfFwd = PdfLightOrigin(bc, s, pt);
    Float w = MISWeight(bc, SubpathView{&s, nullptr, 1}, cam, 1, t, &s);
    res->weight = w;
    res->unweighted = L;
    res->L = L * w;
    return w > 0;
}

bool ShiftLightTracingPath(const GBDPTShiftContext &ctx, const ShiftSubpath &light, int s, const PathVertex &lens,
                           Point2 pRaster, const Spectrum &fx, Point2i off, Arena &arena, Spectrum *fy, Float *wy,
                           Float *rho, GBDPTLocalStats *st) {
    const BidirContext &bc = *ctx.bidir;
    const Scene &scene = *bc.scene;
    if (s < 2) return false;
    const PathVertex &x1 = light.v[s - 1];
    // c: first diffuse vertex after b = x1 going towards the light.
    int c = -1;
    for (int j = s - 2; j >= 0; --j) {
        const PathVertex &v = light.v[j];
        if (v.type == VertexType::Light || IsDiffuseVertex(ctx, v, &light.b[j])) {
            c = j;
            break;
        }
        if (!light.deltaSample[j]) {
            ++st->unsupportedChains;
            return false;
        }
    }
    if (c < 0) return false;
    const int k = s - 2 - c;  // interior (ideal specular) vertices
    if (k > 0 && (!ctx.manifold || !ctx.trySpecular)) return false;
    const PathVertex &xc = light.v[c];
    if (xc.isInfiniteLight()) return false;
    if (xc.type == VertexType::Light && !(xc.light && (xc.light->flags & LIGHT_AREA))) return false;

    ++st->shift.offsetPaths;
    Ray r1, ray;
    CameraSample c1{pRaster, Point2(0.5, 0.5)}, c2{Point2(pRaster.x + off.x, pRaster.y + off.y), Point2(0.5, 0.5)};
    Float w1 = bc.camera->generateRay(c1, &r1), w2 = bc.camera->generateRay(c2, &ray);
    if (!(w1 > 0) || !(w2 > 0)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    SurfaceInteraction isect;
    if (!TraceSurface(scene, ray, &isect)) {
        st->shift.fail(ShiftFailure::Escaped);
        return false;
    }
    BSDF by = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
    if (!by || ClassifyBSDF(&by, ctx.threshold) != ShiftVertexClass::Rough) {
        st->shift.fail(ShiftFailure::ClassMismatch);
        return false;
    }
    const BSDF &bx = light.b[s - 1];
    const Vec3 woX1 = Normalize(lens.p - x1.p), woY1 = isect.wo;
    const Vec3 wiX1 = Normalize(light.v[s - 2].p - x1.p);
    Vec3 wiY1, towardCamX, towardCamY;  // towardCam*: at c, towards the camera side
    Float J = 0, discX = 1, discY = 1;
    Spectrum chainX(1), chainY(1);
    ManifoldChain offChain;
    WalkedInterior walked;
    if (k == 0) {
        st->shift.attempt(ShiftType::Reconnection);
        ShiftVertex tgt;
        tgt.p = xc.p;
        tgt.n = xc.onSurface() ? Vec3(xc.ng) : Vec3(0, 0, 0);
        ReconnectionShift rc;
        if (!ShiftReconnect(x1.p, isect.p, tgt, &rc)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        if (!scene.unoccluded(Interaction(isect.p, isect.n, woY1), AsIt(xc))) {
            st->shift.fail(ShiftFailure::Occluded);
            return false;
        }
        st->shift.success(ShiftType::Reconnection);
        J = rc.jacobian;
        wiY1 = rc.wi;
        towardCamX = -wiX1;
        towardCamY = -wiY1;
    } else {
        SurfaceInteraction xsi[kMaxManifoldVertices];
        const BSDF *xb[kMaxManifoldVertices];
        Vec3 wos[kMaxManifoldVertices], wis[kMaxManifoldVertices];
        bool tr[kMaxManifoldVertices];
        int gids[kMaxManifoldVertices];
        if (k + 2 > kMaxManifoldVertices) return false;
        // Chain from b = x1 (camera side) to c; interior j is light vertex s-2-j.
        for (int j = 0; j < k; ++j) {
            const PathVertex &v = light.v[s - 2 - j];
            if (!VertexInteraction(scene, v, light.v[s - 1 - j].p, &xsi[j])) {
                st->shift.fail(ShiftFailure::Geometry);
                return false;
            }
            xb[j] = &light.b[s - 2 - j];
            wos[j] = Normalize(light.v[s - 1 - j].p - v.p);  // towards the camera side
            wis[j] = Normalize(light.v[s - 3 - j].p - v.p);
            tr[j] = Transmits(wos[j], wis[j], Vec3(xb[j]->ns()));
            gids[j] = v.geomId;
            BSDFSample sx;
            if (!DeltaLobe(*xb[j], wos[j], tr[j], TransportMode::Radiance, &sx) || Dot(sx.wi, wis[j]) < 1 - kDirTol) {
                st->shift.fail(ShiftFailure::Geometry);
                return false;
            }
            chainX *= sx.f * AbsDot(sx.wi, Vec3(xb[j]->ns()));
            discX *= sx.pdf;
        }
        ManifoldChain base;
        // The walk ends on c's shape (an area light's emitting shape for a light vertex).
        int gidc = xc.type == VertexType::Surface ? xc.geomId : ctx.mscene->geomOfLight(xc.light);
        if (gidc < 0 || !BuildChain(ctx, EndpointSP(x1.p, x1.ng, x1.geomId), xsi, xb, wos, wis, k,
                                    EndpointSP(xc.p, xc.ng, gidc), &base)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        ManifoldWalkResult res =
            ManifoldWalk(*ctx.mscene, base, EndpointSP(isect.p, isect.n, isect.geomId), base.back().sp, ctx.walk);
        if (res.ok()) res.status = CheckReversible(*ctx.mscene, base, res.chain, ctx.walk, 1e-4);
        RecordWalk(res, st);
        if (!res.ok()) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        Float ax = SolidAnglePerArea(base), ay = SolidAnglePerArea(res.chain);
        if (!(ax > 0) || !(ay > 0) ||
            !EvaluateWalked(scene, res.chain, tr, gids, arena, TransportMode::Radiance, &walked)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        J = ay / ax;
        chainY = walked.factor;
        discY = walked.prob;
        wiY1 = Normalize(res.chain.v[1].sp.p - isect.p);
        towardCamX = Normalize(light.v[c + 1].p - xc.p);
        towardCamY = Normalize(res.chain.v[k].sp.p - xc.p);
        offChain = res.chain;
    }
    // Eq. 5 in the camera-side parameterisation: f(y)|T'| / f(x).
    Spectrum fX1 = bx.f(woX1, wiX1, TransportMode::Radiance) * AbsDot(wiX1, Vec3(bx.ns()));
    Spectrum fY1 = by.f(woY1, wiY1, TransportMode::Radiance) * AbsDot(wiY1, Vec3(by.ns())) * J;
    Spectrum fXc, fYc;
    Float pcX, pcY;  // solid-angle density of the light path's direction at c
    if (xc.type == VertexType::Light) {
        const AreaLight *al = static_cast<const AreaLight *>(xc.light);
        fXc = al->L(Interaction(xc.p, xc.ng, towardCamX), towardCamX);
        fYc = al->L(Interaction(xc.p, xc.ng, towardCamY), towardCamY);
        Float pp;
        xc.light->pdfLe(Ray(xc.p, towardCamX), xc.ng, &pp, &pcX);
        xc.light->pdfLe(Ray(xc.p, towardCamY), xc.ng, &pp, &pcY);
    } else {
        const BSDF &bcv = light.b[c];
        Vec3 wl = xc.wo;  // towards the light side
        fXc = bcv.f(towardCamX, wl, TransportMode::Radiance);
        fYc = bcv.f(towardCamY, wl, TransportMode::Radiance);
        pcX = bcv.pdf(wl, towardCamX, TransportMode::Importance);
        pcY = bcv.pdf(wl, towardCamY, TransportMode::Importance);
    }
    Spectrum num = fY1 * chainY * fYc * (w2 / w1), den = fX1 * chainX * fXc;
    *fy = fx * SafeDiv(num, den);
    if (fy->isBlack() || !fy->isFinite()) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    // rho = |T'| p(y)/p(x): image-plane area factor dA_b/ds = cos^3 D^2 / |cos_b|
    // (ShiftJacobianFactor's cos^4/G for an empty eye chain) times the light
    // path's density of b through the chain.
    Vec3 n0 = bc.camera->lensNormal();
    // The MIS densities of common/ (area measure, Dirac factors remapped to 1)
    // and the camera-side rho of the same path's other strategies imply the
    // effective |T'| = (F_y/F_x) J_b (disc_y/disc_x) (G1_x/G1_y), G1 = |cos|/d^2
    // of the first edge after b; the light-tracing strategy's density ratio is
    // that of the vertex after c, p_omega,c G1c. (For an empty chain this is
    // F p_omega,c Q, the exact |T'| p(y)/p(x).)
    Float Fx = EyeAreaFactor(lens.p, n0, x1.p, x1.ng), Fy = EyeAreaFactor(lens.p, n0, isect.p, isect.n);
    const PathVertex &xn = light.v[s - 2];  // the vertex after b towards c (base)
    Point3 ynP = k > 0 ? offChain.v[1].sp.p : xc.p;
    Vec3 ynN = k > 0 ? Vec3(walked.si[0].n) : Vec3(xc.ng);
    auto g1 = [](const Point3 &a, const Point3 &b2, const Vec3 &nb, bool surf) {
        Vec3 d = b2 - a;
        Float d2 = d.lengthSquared();
        return (surf ? AbsDot(nb, d / std::sqrt(d2)) : Float(1)) / d2;
    };
    Float G1x = g1(x1.p, xn.p, Vec3(xn.ng), xn.onSurface()), G1y = g1(isect.p, ynP, ynN, xn.onSurface());
    // Vertex after c towards b: base light.v[c + 1], offset the last walked vertex or y1.
    const PathVertex &xa = light.v[c + 1];
    Point3 yaP = k > 0 ? offChain.v[k].sp.p : isect.p;
    Vec3 yaN = k > 0 ? Vec3(walked.si[k - 1].n) : Vec3(isect.n);
    Float Gcx = g1(xc.p, xa.p, Vec3(xa.ng), true), Gcy = g1(xc.p, yaP, yaN, true);
    Float denR = Fx * discX * G1y * pcX * Gcx;
    *rho = denR > 0 ? Fy * J * discY * G1x * pcY * Gcy / denR : 0;


    // Offset light subpath (its own area densities) for its BDPT weight: only
    // vertices c-1 .. s-1 differ, so they are swapped in place and restored
    // (copying whole subpaths per light-tracing strategy made long paths O(n^2)).
    const int lo = std::max(c - 1, 0), m = s - lo;
    PathVertex saveV[kMaxManifoldVertices + 3];
    BSDF saveB[kMaxManifoldVertices + 3];
    if (m > kMaxManifoldVertices + 3) return false;
    for (int j = 0; j < m; ++j) {
        saveV[j] = light.v[lo + j];
        saveB[j] = light.b[lo + j];
    }
    PathVertex *yv = light.v;
    BSDF *yb = light.b;
    for (int j = 0; j < k; ++j) {
        PathVertex &v = yv[s - 2 - j];
        const SurfaceInteraction &si = walked.si[j];
        v.p = si.p;
        v.ng = si.n;
        v.ns = walked.bsdf[j].ns();
        v.wo = Normalize(offChain.v[j + 2].sp.p - si.p);
        v.pdfFwd = v.pdfRev = 0;
        yb[s - 2 - j] = walked.bsdf[j];
    }
    {
        PathVertex &v = yv[s - 1];
        v.p = isect.p;
        v.ng = isect.n;
        v.wo = wiY1;
        v.material = isect.material;
        v.geomId = isect.geomId;
        v.primId = isect.primId;
        SurfaceInteraction si2 = isect;
        si2.wo = wiY1;
        yb[s - 1] = isect.material->getBSDF(si2, arena, TransportMode::Importance);
        v.ns = yb[s - 1].ns();
        v.pdfRev = 0;
        v.pdfFwd = 0;
    }
    yv[c + 1].pdfFwd = PdfArea(bc, xc, c > 0 ? &yb[c] : nullptr, c > 0 ? &yv[c - 1] : nullptr, yv[c + 1],
                               TransportMode::Importance);
    if (k > 0) yv[c].pdfRev = 0;
    if (c >= 1 && xc.type == VertexType::Surface)
        yv[c - 1].pdfRev = PdfArea(bc, xc, &yb[c], &yv[c + 1], yv[c - 1], TransportMode::Radiance);
    PathVertex lensY = lens;
    *wy = MISWeight(bc, SubpathView{yv, yb, s}, SubpathView{&lensY, nullptr, 1}, s, 1, &lensY);
    for (int j = 0; j < m; ++j) {
        light.v[lo + j] = saveV[j];
        light.b[lo + j] = saveB[j];
    }
    return *wy > 0;
}

}  // namespace gradus
