#include "integrators/gradient/camera_shift.h"

#include "integrators/gradient/medium_shift.h"

namespace gradus {

namespace {

// Where the offset follows the base: the half-vector chain is re-traced up to
// vertex traceEnd, then the offset reconnects to the base at rec (-1: never).
struct CameraShiftPlan {
    int traceEnd = 0, rec = -1;
};

CameraShiftPlan PlanCameraShift(const SubpathShiftContext &ctx, const ShiftSubpath &x) {
    const int n = x.n;
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
    CameraShiftPlan plan;
    if (ctx.manifold) {
        plan.rec = c;
    } else {
        for (int k = 2; k < n; ++k)
            if (diffuse(k - 1) && diffuse(k)) {
                plan.rec = k;
                break;
            }
    }
    plan.traceEnd = ctx.manifold ? (b >= 0 ? b : n - 1) : (plan.rec >= 0 ? plan.rec - 1 : n - 1);
    if (!ctx.manifold && b >= 0) {
        // Half-vector shift: a specular vertex between b and the reconnection
        // makes the shift of the whole path a fallback, as for its light-tracing
        // strategy (not shifted across specular chains): a path's strategies must
        // all use Eq. 8 or all fall back, or the weights do not sum to one.
        for (int k = b + 1; k < (plan.rec >= 0 ? plan.rec : n); ++k)
            if (!diffuse(k)) {
                plan.traceEnd = b;
                plan.rec = -1;
                break;
            }
    }
    return plan;
}

// The offset while it is built: throughput f(y)|T'|/p(x) (Eq. 5), the
// gradient-MIS ratio rho (Eq. 8) and the direction towards its previous vertex.
struct OffsetState {
    Spectrum beta;
    Float R = 1;
    Vec3 woY;
};

// Direction of the offset at a half-vector-chain vertex (Sec. 3.1: the first
// chain is re-traced with the base's half vectors). Returns the throughput
// factor f_y |cos| J / p_x and the MIS ratio factor J p_y / p_x.
bool PropagateHalfVector(const BSDF &bx, const Vec3 &woX, const Vec3 &wiX, bool deltaX, const BSDF &by,
                         const Vec3 &woY, Vec3 *wiY, Spectrum *factor, Float *ratio, LocalShiftStats *st) {
    st->attempt(ShiftType::HalfVector);
    if (deltaX) {
        bool tr = Transmits(woX, wiX, Vec3(bx.ns()));
        BSDFSample sx, sy;
        if (!DeltaLobe(bx, woX, tr, TransportMode::Radiance, &sx) || Dot(sx.wi, wiX) < 1 - kShiftDirTol ||
            !DeltaLobe(by, woY, tr, TransportMode::Radiance, &sy)) {
            st->fail(ShiftFailure::Geometry);
            return false;
        }
        *wiY = sy.wi;
        *factor = sy.f * (AbsDot(sy.wi, Vec3(by.ns())) / sx.pdf);
        *ratio = sy.pdf / sx.pdf;
    } else {
        // Glossy refraction keeps the generalised half vector (Walter et al. 2007;
        // shift.h); an interface whose index the BSDF does not report cannot be copied.
        HalfVectorShift hv;
        if (!ShiftHalfVectorWorld(bx, woX, wiX, by, woY, &hv)) {
            st->fail(ShiftFailure::Geometry);
            return false;
        }
        *wiY = hv.wi;
        Spectrum fy = by.f(woY, *wiY);
        Float py = by.pdf(woY, *wiY), px = bx.pdf(woX, wiX);
        if (fy.isBlack() || !(py > 0) || !(px > 0)) {
            st->fail(ShiftFailure::Geometry);
            return false;
        }
        *factor = fy * (AbsDot(*wiY, Vec3(by.ns())) * hv.jacobian / px);
        *ratio = hv.jacobian * py / px;
    }
    st->success(ShiftType::HalfVector);
    return true;
}

// Offset surface vertex from a hit, with the base vertex's flags.
void SetSurfaceVertex(const SurfaceInteraction &si, const BSDF &bsdf, const PathVertex &xv, const Spectrum &beta,
                      PathVertex *v) {
    *v = PathVertex();
    v->type = VertexType::Surface;
    v->material = si.material;
    v->p = si.p;
    v->ng = si.n;
    v->ns = bsdf.ns();
    v->wo = si.wo;
    v->geomId = si.geomId;
    v->primId = si.primId;
    v->flags = xv.flags;
    v->rrScale = xv.rrScale;
    v->setThroughput(beta);
}

// Offset vertices 0..traceEnd: the camera ray through the shifted image-plane
// point, then the first chain re-traced with the base's half vectors.
// The offset's camera vertex and ray through the shifted image-plane point.
// The image-plane shift has |T'| = 1 and equal pdfs: the offset starts with
// the camera weight ratio. false: a camera without a ray there (shift failed).
bool StartOffsetAtCamera(const BidirContext &bc, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                         CameraShift *out, OffsetState *o, LocalShiftStats *st, Ray *ray) {
    ShiftSubpath &y = out->y;
    ++st->offsetPaths;
    Ray rx;
    CameraSample c2 = cs;
    c2.pFilm = Point2(cs.pFilm.x + off.x, cs.pFilm.y + off.y);
    Float wx = bc.camera->generateRay(cs, &rx), wy = bc.camera->generateRay(c2, ray);
    if (!(wx > 0) || !(wy > 0)) {
        st->fail(ShiftFailure::Geometry);
        return false;
    }
    y.v[0] = x.v[0];
    y.v[0].p = ray->o;
    y.deltaSample[0] = 0;
    out->rho[0] = 1;
    out->validUpTo = 0;
    o->beta = Spectrum(wy / wx);
    o->R = 1;
    return true;
}

void TraceFirstChain(const SubpathShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                     int traceEnd, Arena &arena, CameraShift *out, OffsetState *o, LocalShiftStats *st) {
    const BidirContext &bc = *ctx.bidir;
    const int n = x.n;
    ShiftSubpath &y = out->y;
    Ray ray;
    if (!StartOffsetAtCamera(bc, x, cs, off, out, o, st, &ray)) return;
    SurfaceInteraction isect;
    for (int i = 1; i <= traceEnd; ++i) {
        const PathVertex &xv = x.v[i];
        bool hit = TraceSurface(*bc.scene, ray, &isect);
        if (!hit) {
            if (xv.isInfiniteLight() && i == n - 1) {
                PathVertex &v = y.v[i];
                v = xv;
                Vec3 d = Normalize(ray.d);
                v.p = ray.o + d;
                v.ng = -d;
                v.wo = -d;
                v.setThroughput(o->beta);
                out->rho[i] = o->R;
                out->validUpTo = i;
            } else {
                st->fail(ShiftFailure::Escaped);
            }
            break;
        }
        if (xv.type != VertexType::Surface) {
            st->fail(ShiftFailure::Escaped);
            break;
        }
        BSDF by = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        bool dy = by && ClassifyBSDF(&by, ctx.threshold) == ShiftVertexClass::Rough;
        if (!by || dy != IsDiffuseVertex(ctx, xv, &x.b[i])) {
            st->fail(ShiftFailure::ClassMismatch);
            break;
        }
        SetSurfaceVertex(isect, by, xv, o->beta, &y.v[i]);
        y.b[i] = by;
        y.deltaSample[i] = x.deltaSample[i];
        out->rho[i] = o->R;
        out->validUpTo = i;
        o->woY = isect.wo;
        if (i == traceEnd || i == n - 1) break;
        Vec3 wiX = Normalize(x.v[i + 1].p - xv.p), wiY;
        Spectrum factor;
        Float ratio;
        if (!PropagateHalfVector(x.b[i], xv.wo, wiX, x.deltaSample[i], by, o->woY, &wiY, &factor, &ratio, st)) break;
        // The base's roulette factor after x_i (rrScale): the offset reuses the
        // decision, so its throughput carries the same 1/q as the base's and
        // the factors cancel in f(y)/f(x); rho (Eq. 8) compares densities
        // without roulette on both sides, as BDPT's weights do.
        o->beta *= factor * xv.rrScale;
        o->R *= ratio;
        ray = isect.spawnRay(wiY);
    }
}

// The offset's direction from its vertex i towards the base's x_rec: a direct
// reconnection (empty second chain) or a manifold walk through the chain's
// specular and near-specular vertices i+1..rec-1. J = Phi(y)/Phi(x) of the
// chain's sampled directions (ChainDirectionsPerArea; for an empty or ideal
// specular chain |d omega_y,i / d omega_x,i|).
bool ShiftToReconnection(const SubpathShiftContext &ctx, const ShiftSubpath &x, const PathVertex &yi, int i, int rec,
                         Arena &arena, SubpathShiftStats *st, Vec3 *wiY, Float *J, WalkedInterior *walked) {
    const Scene &scene = *ctx.bidir->scene;
    const PathVertex &xi = x.v[i], &xr = x.v[rec];
    const int k = rec - i - 1;  // interior vertices of the second chain
    if (xr.isInfiniteLight() && k > 0) return false;  // no manifold walk towards infinity
    if (xr.isInfiniteLight()) {
        // Environment shift: the offset keeps the base's direction towards the
        // point at infinity, |d omega_y / d omega_x| = 1 (shift.h), if it escapes.
        st->shift.attempt(ShiftType::Environment);
        *wiY = -Vec3(xr.wo);
        *J = 1;
        SurfaceInteraction hit;
        if (TraceSurface(scene, VertexIt(yi).spawnRay(*wiY), &hit)) {
            st->shift.fail(ShiftFailure::Occluded);
            return false;
        }
        return true;
    }
    if (k == 0) {
        ReconnectionShift rc;
        if (!ReconnectToVertex(scene, xi.p, VertexIt(yi), xr, &st->shift, &rc)) return false;
        *J = rc.jacobian;
        *wiY = rc.wi;
        return true;
    }
    // Manifold walk from offset b to base c with the base's half vectors.
    ChainInterior in;
    if (k + 2 > kMaxManifoldVertices) ++st->longChains;
    bool ok = ctx.trySpecular && k + 2 <= kMaxManifoldVertices, glossy = false;
    for (int j = 0; ok && j < k; ++j) {
        const PathVertex &xv = x.v[i + 1 + j];
        ok = VertexInteraction(scene, xv, x.v[i + j].p, &in.si[j]);
        in.bsdf[j] = &x.b[i + 1 + j];
        in.wo[j] = xv.wo;
        in.wi[j] = Normalize(x.v[i + 2 + j].p - xv.p);
        in.transmit[j] = Transmits(in.wo[j], in.wi[j], Vec3(x.b[i + 1 + j].ns()));
        in.specular[j] = x.deltaSample[i + 1 + j] != 0;
        in.geomId[j] = xv.geomId;
        glossy |= !in.specular[j];
    }
    st->glossyChains += glossy;
    ManifoldChain base, offChain;
    if (ok)
        ok = BuildChain(ctx, EndpointSP(xi.p, xi.ng, xi.geomId), in, k, EndpointSP(xr.p, xr.ng, xr.geomId), &base);
    if (!ok) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    if (!WalkSecondChain(ctx, base, EndpointSP(yi.p, yi.ng, yi.geomId), in, arena, st, &offChain, walked, J))
        return false;
    *wiY = Normalize(offChain.v[1].sp.p - yi.p);
    return true;
}

// ---- Scenes with media (SubpathShiftContext::media) ----------------------
// The base's segment x_{i-1} -> x_i as pieces through interfaces.
int BaseSegmentPieces(const BidirContext &bc, const ShiftSubpath &x, int i, MediumPiece *xp) {
    const PathVertex &a = x.v[i - 1], &b = x.v[i];
    const bool inf = b.isInfiniteLight();
    const Vec3 d = inf ? -Vec3(b.wo) : Normalize(b.p - a.p);
    const Medium *m = i == 1 ? bc.scene->cameraMedium : MediumTowards(bc, a, d);
    return TraceSegmentPieces(*bc.scene, AsInteraction(a), m, AsInteraction(b), inf, d, xp);
}

// The first chain with media: each segment walks in lockstep with the base's
// (medium_shift.h LockstepSegment: the same interfaces, the free-flight
// distance copied, |T'| = 1) and multiplies the base's distance-sampling
// factor by T_y / T_x (TransmittanceRatio) and, at a medium vertex, by
// sigma_s(y) / sigma_s(x) (f(y) / p(x) with p(x) the base's). A medium vertex
// before traceEnd (half-vector shift) keeps the base's world direction (|T'| = 1).
void TraceFirstChainMedia(const SubpathShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                          int traceEnd, Arena &arena, CameraShift *out, OffsetState *o, LocalShiftStats *st,
                          UniformSource rng) {
    const BidirContext &bc = *ctx.bidir;
    const Scene &scene = *bc.scene;
    const int n = x.n;
    ShiftSubpath &y = out->y;
    Ray ray;
    if (!StartOffsetAtCamera(bc, x, cs, off, out, o, st, &ray)) return;
    const Medium *m = scene.cameraMedium;
    ray = Interaction(ray.o, Normal3(0, 0, 0), Vec3(0, 0, 0)).spawnRay(Normalize(ray.d));
    MediumPiece xp[kMaxMediumPieces], yp[kMaxMediumPieces];
    for (int i = 1; i <= traceEnd; ++i) {
        const PathVertex &xv = x.v[i];
        const int nx = BaseSegmentPieces(bc, x, i, xp);
        if (nx == 0) {
            st->fail(ShiftFailure::Geometry);
            break;
        }
        const SegmentEnd end = xv.isInfiniteLight() ? SegmentEnd::Escape
                               : xv.type == VertexType::Medium ? SegmentEnd::Medium
                                                               : SegmentEnd::Surface;
        if (xv.type != VertexType::Surface && xv.type != VertexType::Medium && !(xv.isInfiniteLight() && i == n - 1)) {
            st->fail(ShiftFailure::Escaped);
            break;
        }
        SurfaceInteraction isect;
        Point3 pm;
        if (!LockstepSegment(scene, ray, m, xp, nx, end, yp, &isect, &pm, &m)) {
            st->fail(ShiftFailure::Escaped);
            break;
        }
        Spectrum seg = x.segFactor[i] * TransmittanceRatio(yp, nx, xp, nx, rng);
        PathVertex &v = y.v[i];
        if (end == SegmentEnd::Escape) {
            o->beta *= seg;
            v = xv;
            const Vec3 d = Normalize(ray.d);
            v.p = yp[nx - 1].o + d;
            v.ng = -d;
            v.wo = -d;
            v.setThroughput(o->beta);
            out->rho[i] = o->R;
            out->validUpTo = i;
            break;
        }
        if (end == SegmentEnd::Medium) {
            // sigma_s(y) / sigma_s(x): a grid scales every channel by its density.
            const Float sy = m->sigmaTAt(pm).maxComponent(), sx = m->sigmaTAt(xv.p).maxComponent();
            if (!(sx > 0)) {
                st->fail(ShiftFailure::Geometry);
                break;
            }
            o->beta *= seg * (sy / sx);
            v = PathVertex();
            v.type = VertexType::Medium;
            v.medium = m;
            v.mediumIndex = xv.mediumIndex;
            v.p = pm;
            v.wo = -yp[nx - 1].d;
            v.flags = xv.flags;
            v.rrScale = xv.rrScale;
            v.setThroughput(o->beta);
            y.b[i] = BSDF();
            y.deltaSample[i] = 0;
            o->woY = -yp[nx - 1].d;
        } else {
            o->beta *= seg;
            BSDF by = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
            bool dy = by && ClassifyBSDF(&by, ctx.threshold) == ShiftVertexClass::Rough;
            if (!by || dy != IsDiffuseVertex(ctx, xv, &x.b[i])) {
                st->fail(ShiftFailure::ClassMismatch);
                break;
            }
            SetSurfaceVertex(isect, by, xv, o->beta, &v);
            v.mediumIndex = MediumIndexOf(scene, m);
            y.b[i] = by;
            y.deltaSample[i] = x.deltaSample[i];
            o->woY = isect.wo;
        }
        out->rho[i] = o->R;
        out->validUpTo = i;
        if (i == traceEnd || i == n - 1) break;
        Vec3 wiX = Normalize(x.v[i + 1].p - xv.p), wiY;
        Spectrum factor;
        Float ratio;
        if (end == SegmentEnd::Medium) {
            st->attempt(ShiftType::HalfVector);
            const Float py = m->phase.p(o->woY, wiX), px = xv.medium->phase.p(Vec3(xv.wo), wiX);
            if (!(py > 0) || !(px > 0)) {
                st->fail(ShiftFailure::Geometry);
                break;
            }
            st->success(ShiftType::HalfVector);
            wiY = wiX;
            factor = Spectrum(py / px);
            ratio = py / px;
            ray = Ray(pm, wiY, Infinity);
        } else {
            if (!PropagateHalfVector(x.b[i], xv.wo, wiX, x.deltaSample[i], y.b[i], o->woY, &wiY, &factor, &ratio, st))
                break;
            m = isect.mediumAfter(wiY, m);
            ray = isect.spawnRay(wiY);
        }
        o->beta *= factor * xv.rrScale;  // roulette: see TraceFirstChain
        o->R *= ratio;
    }
}

// The second chain with media: an empty chain only (a reconnection, or the
// environment shift); the changed segment y_i -> x_rec carries T_y / T_x on
// the base's distance-sampling factor of x_i -> x_rec. A chain of specular
// vertices fails (a property of the path that the shift keeps, so base and
// offset fall back alike: the estimator stays unbiased).
bool ReconnectMedia(const SubpathShiftContext &ctx, const ShiftSubpath &x, const PathVertex &yi, int i, int rec,
                    SubpathShiftStats *st, Vec3 *wiY, Float *J, Spectrum *segRatio, UniformSource rng) {
    const BidirContext &bc = *ctx.bidir;
    const Scene &scene = *bc.scene;
    const PathVertex &xi = x.v[i], &xr = x.v[rec];
    if (rec - i - 1 > 0) {
        ++st->mediaChains;
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    MediumPiece xp[kMaxMediumPieces], yp[kMaxMediumPieces];
    const bool inf = xr.isInfiniteLight();
    const Vec3 dx = inf ? -Vec3(xr.wo) : Normalize(xr.p - xi.p);
    const int nx = TraceSegmentPieces(scene, AsInteraction(xi), MediumTowards(bc, xi, dx), AsInteraction(xr), inf, dx, xp);
    if (nx == 0) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    const ShiftType type = inf ? ShiftType::Environment : ShiftType::Reconnection;
    st->shift.attempt(type);
    if (inf) {
        *wiY = dx;
        *J = 1;
    } else {
        ShiftVertex tgt;
        tgt.p = xr.p;
        tgt.n = xr.onSurface() ? Vec3(xr.ng) : Vec3(0, 0, 0);  // no cosine at a medium vertex
        ReconnectionShift rc;
        if (!ShiftReconnect(xi.p, yi.p, tgt, &rc)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        *wiY = rc.wi;
        *J = rc.jacobian;
    }
    const Interaction yIt = AsInteraction(yi);
    if ((yi.onSurface() && InTangentPlane(yIt.n, *wiY)) || (xr.onSurface() && InTangentPlane(AsInteraction(xr).n, *wiY))) {
        st->shift.fail(ShiftFailure::Occluded);
        return false;
    }
    const int ny = TraceSegmentPieces(scene, yIt, MediumTowards(bc, yi, *wiY), AsInteraction(xr), inf, *wiY, yp);
    // The offset must arrive in the medium the base arrives in (x_rec keeps it).
    if (ny == 0 || yp[ny - 1].medium != xp[nx - 1].medium) {
        st->shift.fail(ShiftFailure::Occluded);
        return false;
    }
    *segRatio = x.segFactor[rec] * TransmittanceRatio(yp, ny, xp, nx, rng);
    return true;
}

// Offset vertices i+1..rec-1 of a walked second chain. Ideal specular: the
// Dirac coefficient of the offset over the base's lobe probability; glossy
// (near-specular, its half-vector kept): f_y |cos_y| / p_x in the throughput
// (Eq. 5, its direction is a variable of J_b) and p_y / p_x in rho (Eq. 8).
bool AppendWalkedInterior(const ShiftSubpath &x, int i, int rec, const WalkedInterior &walked, CameraShift *out,
                          OffsetState *o) {
    ShiftSubpath &y = out->y;
    for (int j = 0; j < rec - i - 1; ++j) {
        const int m = i + 1 + j;
        const PathVertex &xv = x.v[m];
        const Vec3 wiX = Normalize(x.v[m + 1].p - xv.p);
        Float px;
        if (x.deltaSample[m]) {
            BSDFSample sx;
            if (!DeltaLobe(x.b[m], xv.wo, Transmits(xv.wo, wiX, Vec3(x.b[m].ns())), TransportMode::Radiance, &sx))
                return false;
            px = sx.pdf;
        } else {
            // From the vertex positions, as the MIS densities (PdfArea) and the
            // offset's (EvaluateWalked): a stored single-precision direction
            // differs by ~1e-7, which a roughness-5e-4 lobe at grazing
            // reflection turns into ~1% of its density.
            px = x.b[m].pdf(Normalize(x.v[m - 1].p - xv.p), wiX);
            if (!(px > 0)) return false;
        }
        SetSurfaceVertex(walked.si[j], walked.bsdf[j], xv, o->beta, &y.v[m]);
        y.b[m] = walked.bsdf[j];
        y.deltaSample[m] = x.deltaSample[m];
        out->rho[m] = o->R;
        o->beta *= walked.fcos[j] * (xv.rrScale / px);
        o->R *= walked.pdf[j] / px;
    }
    return true;
}

// y_rec = x_rec with the offset's incoming direction; later vertices are the
// base's, their throughputs rescaled by the offset's ratio at rec.
void CopyBaseTail(const ShiftSubpath &x, int rec, const OffsetState &o, bool media, CameraShift *out) {
    ShiftSubpath &y = out->y;
    const int n = x.n;
    const PathVertex &xr = x.v[rec];
    PathVertex &v = y.v[rec];
    v = xr;
    Point3 prevP = y.v[rec - 1].p;
    if (xr.isInfiniteLight())
        v.p = prevP - Vec3(xr.wo);  // same direction (wo, ng = -d), a point along it as escaped vertices store
    else
        v.wo = Normalize(prevP - xr.p);
    v.setThroughput(o.beta);
    y.b[rec] = x.b[rec];
    y.deltaSample[rec] = x.deltaSample[rec];
    out->rho[rec] = o.R;
    Float Rn = o.R;
    Spectrum scale(0);
    if (media && rec + 1 < n && xr.type == VertexType::Medium) {
        // A medium vertex (its phase function), and the next segment's distance factor.
        Vec3 wi = Normalize(x.v[rec + 1].p - xr.p);
        Float pyr, pxr;
        Spectrum fyr = ScatterValue(xr, x.b[rec], v.wo, wi, &pyr);
        ScatterValue(xr, x.b[rec], xr.wo, wi, &pxr);
        if (pxr > 0) {
            Spectrum betaN = o.beta * fyr * (xr.rrScale / pxr) * x.segFactor[rec + 1];
            scale = SafeDiv(betaN, x.v[rec + 1].throughput());
            Rn = o.R * pyr / pxr;
        }
    } else if (rec + 1 < n && x.b[rec]) {
        Vec3 wi = Normalize(x.v[rec + 1].p - xr.p);
        Spectrum fyr = x.b[rec].f(v.wo, wi);
        Float pyr = x.b[rec].pdf(v.wo, wi), pxr = x.b[rec].pdf(xr.wo, wi);
        if (pxr > 0) {
            Spectrum betaN = o.beta * fyr * (AbsDot(wi, Vec3(xr.ns)) / pxr) * xr.rrScale;
            if (media) betaN *= x.segFactor[rec + 1];
            scale = SafeDiv(betaN, x.v[rec + 1].throughput());
            Rn = o.R * pyr / pxr;
        }
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

// Reconnection of the traced offset (ending at vertex i = traceEnd) to the
// base at rec through the second chain.
void ReconnectSecondChain(const SubpathShiftContext &ctx, const ShiftSubpath &x, int i, int rec, Arena &arena,
                          CameraShift *out, OffsetState *o, SubpathShiftStats *st, UniformSource rng) {
    const ShiftSubpath &y = out->y;
    const PathVertex &xi = x.v[i];
    Vec3 wiX = Normalize(x.v[i + 1].p - xi.p), wiY;
    Float J = 0;
    if (ctx.media) {
        Spectrum seg;
        if (!ReconnectMedia(ctx, x, y.v[i], i, rec, st, &wiY, &J, &seg, rng)) return;
        Float py, px;
        const Spectrum fy = ScatterValue(y.v[i], y.b[i], o->woY, wiY, &py);
        ScatterValue(xi, x.b[i], xi.wo, wiX, &px);
        if (fy.isBlack() || !(py > 0) || !(px > 0) || !(J > 0) || !std::isfinite(J)) {
            st->shift.fail(ShiftFailure::Geometry);
            return;
        }
        st->shift.success(x.v[rec].isInfiniteLight() ? ShiftType::Environment : ShiftType::Reconnection);
        // Eq. 5 factor of vertex i (|T'| = d_x^2 / d_y^2, cosines only at surface ends), T_y / T_x.
        o->beta *= fy * (J / px) * xi.rrScale * seg;
        o->R *= J * py / px;
        CopyBaseTail(x, rec, *o, true, out);
        return;
    }
    WalkedInterior walked;
    if (!ShiftToReconnection(ctx, x, y.v[i], i, rec, arena, st, &wiY, &J, &walked)) return;
    Spectrum fy = y.b[i].f(o->woY, wiY);
    Float py = y.b[i].pdf(o->woY, wiY), px = x.b[i].pdf(xi.wo, wiX);
    if (fy.isBlack() || !(py > 0) || !(px > 0) || !(J > 0) || !std::isfinite(J)) {
        st->shift.fail(ShiftFailure::Geometry);
        return;
    }
    if (rec - i - 1 == 0) st->shift.success(x.v[rec].isInfiniteLight() ? ShiftType::Environment : ShiftType::Reconnection);
    // Eq. 5 factor of vertex i and its gradient-MIS ratio J p_y / p_x.
    o->beta *= fy * (AbsDot(wiY, Vec3(y.b[i].ns())) * J / px) * xi.rrScale;  // roulette: see TraceFirstChain
    o->R *= J * py / px;
    if (!AppendWalkedInterior(x, i, rec, walked, out, o)) return;
    CopyBaseTail(x, rec, *o, false, out);
}

// Area densities of the offset in both directions (for its own BDPT weights).
void SetOffsetDensities(const BidirContext &bc, CameraShift *out) {
    ShiftSubpath &y = out->y;
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
        if (k + 2 <= last && !y.deltaSample[k + 1] && y.v[k + 1].scatters())
            y.v[k].pdfRev = PdfArea(bc, y.v[k + 1], &y.b[k + 1], &y.v[k + 2], y.v[k], TransportMode::Importance);
    }
}

}  // namespace

void ShiftCameraSubpath(const SubpathShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                        Arena &arena, CameraShift *out, SubpathShiftStats *st, UniformSource rng) {
    const int n = x.n;
    out->validUpTo = -1;
    out->r = -1;
    out->y.n = n;
    out->y.v = ArenaArray<PathVertex>(arena, n);
    out->y.b = ArenaArray<BSDF>(arena, n);
    out->y.deltaSample = ArenaArray<uint8_t>(arena, n);
    out->rho = ArenaArray<Float>(arena, n + 1);
    if (n < 2) return;
    const CameraShiftPlan plan = PlanCameraShift(ctx, x);
    OffsetState o;
    if (ctx.media)
        TraceFirstChainMedia(ctx, x, cs, off, plan.traceEnd, arena, out, &o, &st->shift, rng);
    else
        TraceFirstChain(ctx, x, cs, off, plan.traceEnd, arena, out, &o, &st->shift);
    const int i = plan.traceEnd;
    if (plan.rec >= 0 && out->validUpTo == i && i >= 1 && plan.rec > i &&
        (out->y.v[i].type == VertexType::Surface || (ctx.media && out->y.v[i].type == VertexType::Medium)))
        ReconnectSecondChain(ctx, x, i, plan.rec, arena, out, &o, st, rng);
    SetOffsetDensities(*ctx.bidir, out);
}

}  // namespace gradus
