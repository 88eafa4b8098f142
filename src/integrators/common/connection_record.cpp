#include "integrators/common/connection_record.h"

#include <cmath>
#include <typeinfo>

#include "core/error.h"
#include "materials/bxdfs.h"

namespace gradus {

namespace {

Float Remap(Float f) { return f != 0 ? f : Float(1); }  // Dirac densities count as 1 (bidir.h)

struct Mis {
    bool power;
    Float operator()(Float r) const { return power ? r * r : r; }
};

int8_t Side(Float z) { return z > 0 ? 1 : (z < 0 ? -1 : 0); }

// Shading-normal correction of the adjoint BSDF (Veach 1997, Eq. 5.17), as
// EvalBSDF applies it in importance transport.
Float AdjointCorrection(const Vec3 &ng, const Vec3 &ns, const Vec3 &wo, const Vec3 &wi) {
    Float den = AbsDot(wo, ng) * AbsDot(wi, ns);
    if (den == 0) return 0;
    return AbsDot(wo, ns) * AbsDot(wi, ng) / den;
}

// The fields a record shares with its vertex, copied either way.
template <class From, class To>
void CopySharedFields(const From &f, To &t) {
    CopyVertexCore(f, t);
    t.type = f.type;
    t.flags = f.flags;
}

// The record's vertex as a PathVertex (what the camera-side functions read:
// position, normals, wo, throughput, type, flags, medium).
PathVertex AsVertex(const LightRecord &r) {
    PathVertex v;
    CopySharedFields(r, v);
    return v;
}

// The camera side of Veach 1997 Eq. 10.9 for a connection of camera vertex
// t - 1 with light endpoint q (header): mis(b1) (end_{t-1} + mis(b2) (in_{t-2} +
// T_{t-3})), b1 from ptRev = p(x_{t-1} from q); *qsRev = p(q from x_{t-1}).
Float CameraTerms(const BidirContext &ctx, const Mis &mis, const CameraSums &cam, SubpathView camera, int t,
                  Float ptRev, const PathVertex &q, Float *qsRev) {
    const PathVertex &pt = camera.v[t - 1], &ptPrev = camera.v[t - 2];
    const BSDF *pb = &camera.bsdf[t - 1];
    // Camera-side reverse densities (exact, from the camera subpath).
    *qsRev = PdfArea(ctx, pt, pb, &ptPrev, q, TransportMode::Radiance);
    const Float ptMinusRev = PdfArea(ctx, pt, pb, &q, ptPrev, TransportMode::Importance);
    const Float b1 = Remap(ptRev) / Remap(pt.pdfFwd), b2 = Remap(ptMinusRev) / Remap(ptPrev.pdfFwd);
    Float terms = cam.end[size_t(t - 1)];
    if (t >= 3) terms += mis(b2) * (cam.in[size_t(t - 2)] + cam.T[size_t(t - 3)]);
    return mis(b1) * terms;
}

// The camera vertex of a matrix connection: not an infinite-light vertex
// (it ends the camera path), connectible and scattering.
bool CameraEndConnectible(SubpathView camera, int t) {
    const PathVertex &pt = camera.v[t - 1];
    const BSDF *pb = camera.bsdf ? &camera.bsdf[t - 1] : nullptr;
    return pt.type != VertexType::Light && IsConnectible(pt, pb) && pt.scatters();
}

}  // namespace

void BuildLightRecords(const BidirContext &ctx, SubpathView light, uint32_t firstIndex, LightRecord *rec) {
    const Mis mis{ctx.heuristic == MISHeuristic::Power};
    const PathVertex *L = light.v;
    Float S = 0, SPrev = 0;  // S_{i-1}, S_{i-2}
    bool intPrev = false;    // A'_{i-1}
    for (int i = 0; i < light.n; ++i) {
        const PathVertex &v = L[i];
        const bool deltaPrev = i > 0 ? L[i - 1].delta() : v.isDeltaLight();
        const bool end = !deltaPrev && (i == 0 || EdgeConnectible(ctx, L[i - 1], v));
        const bool in = end && !v.delta();
        LightRecord &r = rec[i];
        r = LightRecord();
        CopySharedFields(v, r);
        r.fwd = Remap(v.pdfFwd);
        r.endAllowed = end;
        r.kind = RecordKind::None;
        if (i > 0) {
            r.fwdPrev = Remap(L[i - 1].pdfFwd);
            r.tail = (intPrev ? 1 : 0) + SPrev;
            const BSDF *b = light.bsdf ? &light.bsdf[i] : nullptr;
            if (v.type == VertexType::Medium || (v.type == VertexType::Surface && !b)) {
                r.kind = RecordKind::Stored;  // no BSDF here: the connection rebuilds it
            } else if (v.type == VertexType::Surface && b && IsConnectible(v, b)) {
                const BxDF *bx = b->bxdf();
                r.kind = typeid(*bx) == typeid(LambertianReflection) ? RecordKind::Lambertian : RecordKind::Stored;
            }
            if (r.kind == RecordKind::Lambertian) {
                const Vec3 n(0, 0, 1);
                const Spectrum f = b->bxdf()->f(n, n, TransportMode::Importance);  // R / pi
                r.fR[0] = float(f.r), r.fR[1] = float(f.g), r.fR[2] = float(f.b);
                // The direction to the previous vertex as PdfArea forms it.
                Vec3 wp = L[i - 1].p - v.p;
                const Float zp = wp.lengthSquared() > 0 ? b->toLocal(Normalize(wp)).z : 0;
                r.prevSide = Side(zp);
                // PdfArea(q, ., pt, L[i-1]) when wo = (towards pt) passes the hemisphere
                // test: the cosine density of wp, converted to area at L[i-1] (Eq. 8.10).
                if (r.prevSide != 0) {
                    wp = Normalize(wp);
                    r.revPrev = ConvertDensity(b->pdf(wp, wp, TransportMode::Radiance), v, L[i - 1]);
                }
                r.woSide = Side(b->toLocal(Vec3(v.wo)).z);
            } else if (r.kind == RecordKind::Stored) {
                r.vertex = firstIndex + uint32_t(i);
            }
        }
        // S_i = mis(rho_i) (A'_i + S_{i-1}).
        const Float rho = Remap(v.pdfRev) / Remap(v.pdfFwd);
        SPrev = S;
        S = mis(rho) * ((in ? 1 : 0) + S);
        intPrev = in;
    }
}

void CameraSums::build(const BidirContext &ctx, SubpathView camera) {
    const Mis mis{ctx.heuristic == MISHeuristic::Power};
    const StrategySet &set = ctx.strategies;
    const int n = camera.n;
    end.assign(size_t(std::max(n, 1)), 0);
    in.assign(size_t(std::max(n, 1)), 0);
    T.assign(size_t(std::max(n, 1)), 0);
    const PathVertex *C = camera.v;
    for (int i = 1; i < n; ++i) {
        bool ok = !C[i - 1].delta() && EdgeConnectible(ctx, C[i], C[i - 1]);
        if (i == 1 && !set.lightTracing) ok = false;                                       // (s + t - 1, 1) not in play
        if (i == 1 && C[1].pdfFwd == 0 && C[0].type == VertexType::Camera) ok = false;  // filter margin
        const Float nk = mis(i == 1 ? set.lightTracingSamples : Float(1));
        end[i] = ok ? nk : 0;
        in[i] = ok && !C[i].delta() ? nk : 0;
        T[i] = mis(Remap(C[i].pdfRev) / Remap(C[i].pdfFwd)) * (in[i] + T[i - 1]);
    }
}

bool ConnectRecord(const BidirContext &ctx, const LightRecord &rec, const PathVertex *stored,
                   const BSDF *storedBsdf, const CameraSums &cam, SubpathView camera, int s, int t,
                   const ConnectSamples &u, ConnectResult *res) {
    *res = ConnectResult();
    GRADUS_CHECK(s >= 2 && t >= 2 && !ctx.strategies.merging && ctx.strategies.lightTracingSamples == 1);
    if (rec.kind == RecordKind::None) return false;
    if (!CameraEndConnectible(camera, t)) return false;
    const PathVertex &pt = camera.v[t - 1];
    const BSDF *pb = &camera.bsdf[t - 1];
    const bool compact = rec.kind == RecordKind::Lambertian;
    const PathVertex qv = compact ? AsVertex(rec) : PathVertex();
    const PathVertex &qs = compact ? qv : stored[0];
    if (!EdgeConnectible(ctx, qs, pt)) return false;

    // The light endpoint's BSDF value towards pt and the two light-side
    // reverse densities (bidir.cpp OtherStrategies: ptRev, qsMinusRev).
    Spectrum fq;
    Float ptRev, qsMinusRev;
    if (compact) {
        Vec3 wi = pt.p - qs.p;
        if (wi.lengthSquared() == 0) return false;
        wi = Normalize(wi);
        const Float z = Dot(wi, Vec3(rec.ns));  // local z in the shading frame
        fq = rec.woSide * z > 0 ? Spectrum(rec.fR[0], rec.fR[1], rec.fR[2]) : Spectrum(0);
        fq *= AdjointCorrection(Vec3(rec.ng), Vec3(rec.ns), Vec3(rec.wo), wi);
        ptRev = ConvertDensity(rec.prevSide * z > 0 ? std::abs(z) * InvPi : 0, qs, pt);
        qsMinusRev = rec.prevSide * z > 0 ? rec.revPrev : 0;
    } else {
        static const BSDF kNone;
        const BSDF &qb = storedBsdf ? *storedBsdf : kNone;
        if (!IsConnectible(qs, &qb)) return false;
        fq = EvalBSDF(qs, qb, pt, TransportMode::Importance);
        ptRev = PdfArea(ctx, qs, &qb, &stored[-1], pt, TransportMode::Importance);
        qsMinusRev = PdfArea(ctx, qs, &qb, &pt, stored[-1], TransportMode::Radiance);
    }
    Spectrum L = qs.throughput() * fq * EvalBSDF(pt, *pb, qs, TransportMode::Radiance) * pt.throughput();
    if (L.isBlack()) return false;
    // Geometry term with shading-normal cosines (as ConnectBDPT).
    Vec3 d = qs.p - pt.p;
    const Float d2 = d.lengthSquared();
    d = d / std::sqrt(d2);
    L *= ScatterCos(qs, d) * ScatterCos(pt, d) / d2;
    if (L.isBlack()) return false;
    res->shadowRayTraced = !u.knownVisible;
    if (!u.knownVisible) {
        L *= Transmittance(ctx, qs, AsInteraction(qs), AsInteraction(pt), u.rng);
        if (L.isBlack()) return false;
    }
    Float qsRev;
    const Mis mis{ctx.heuristic == MISHeuristic::Power};
    const Float camTerms = CameraTerms(ctx, mis, cam, camera, t, ptRev, qs, &qsRev);
    // Veach 1997 Eq. 10.9 with the recursive sums (header).
    const Float a1 = Remap(qsRev) / rec.fwd, a2 = Remap(qsMinusRev) / rec.fwdPrev;
    const Float lightTerms = mis(a1) * ((rec.endAllowed ? 1 : 0) + mis(a2) * rec.tail);
    const Float w = 1 / (1 + camTerms + lightTerms);
    res->weight = w;
    res->unweighted = L;
    res->L = L * w;
    return w > 0;
}

bool ConnectLightOrigin(const BidirContext &ctx, const PathVertex &y0, const CameraSums &cam, SubpathView camera,
                        int t, const ConnectSamples &u, ConnectResult *res) {
    *res = ConnectResult();
    GRADUS_CHECK(t >= 2 && !ctx.strategies.merging && ctx.strategies.lightTracingSamples == 1);
    if (!IsMatrixLightOrigin(y0) || !CameraEndConnectible(camera, t)) return false;
    const PathVertex &pt = camera.v[t - 1];
    const BSDF &pb = camera.bsdf[t - 1];
    if (!EdgeConnectible(ctx, y0, pt)) return false;
    Vec3 d = pt.p - y0.p;  // from the light towards x_t
    const Float d2 = d.lengthSquared();
    d = d / std::sqrt(d2);
    // Emitted radiance times the light side of the geometry term, over p(y0) (header).
    Spectrum Le;
    if (y0.isDeltaLight()) {
        // A point-like emitter: its sampleLi from x_t is y0 itself, L = I / d^2 (pdf 1).
        LightLiSample ls;
        const Float pmf = ctx.lightSampler->pmf(y0.light);
        if (pmf == 0 || !y0.light->sampleLi(AsInteraction(pt), Point2(0.5, 0.5), &ls) || ls.pdf == 0) return false;
        Le = ls.L / (ls.pdf * pmf);
    } else {
        if (y0.pdfFwd == 0) return false;
        Le = EmittedRadiance(ctx, y0, pt) * (AbsDot(Vec3(y0.ng), d) / (d2 * y0.pdfFwd));
    }
    Spectrum L = pt.throughput() * EvalBSDF(pt, pb, y0, TransportMode::Radiance) * Le * ScatterCos(pt, d);
    if (L.isBlack()) return false;
    res->shadowRayTraced = !u.knownVisible;
    if (!u.knownVisible) {
        L *= Transmittance(ctx, pt, AsInteraction(pt), AsInteraction(y0), u.rng);
        if (L.isBlack()) return false;
    }
    // Veach 1997 Eq. 10.9: camera terms with b1 from p(x_t from y0) (the
    // emission density), light terms = strategy (0, t + 1) only.
    const Mis mis{ctx.heuristic == MISHeuristic::Power};
    const Float ptRev = PdfArea(ctx, y0, nullptr, nullptr, pt, TransportMode::Importance);
    Float qsRev;
    const Float camTerms = CameraTerms(ctx, mis, cam, camera, t, ptRev, y0, &qsRev);
    const Float lightTerms = y0.isDeltaLight() ? 0 : mis(Remap(qsRev) / Remap(y0.pdfFwd));
    const Float w = 1 / (1 + camTerms + lightTerms);
    res->weight = w;
    res->unweighted = L;
    res->L = L * w;
    return w > 0;
}

}  // namespace gradus
