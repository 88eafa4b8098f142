#include "integrators/gradient/lighttracing_shift.h"

#include "integrators/gradient/medium_shift.h"
#include "lights/light.h"

namespace gradus {

namespace {

// c: the first diffuse vertex after b = x_1 going towards the light (-1: none).
int FindChainEnd(const SubpathShiftContext &ctx, const ShiftSubpath &light, int s) {
    for (int j = s - 2; j >= 0; --j) {
        const PathVertex &v = light.v[j];
        if (v.type == VertexType::Light || IsDiffuseVertex(ctx, v, &light.b[j])) return j;
    }
    return -1;
}

// |cos at b2| / d^2 of the edge a -> b2 (no cosine off surfaces).
Float EdgeGeometry(const Point3 &a, const Point3 &b2, const Vec3 &nb, bool surf) {
    Vec3 d = b2 - a;
    Float d2 = d.lengthSquared();
    return (surf ? AbsDot(nb, d / std::sqrt(d2)) : Float(1)) / d2;
}

// The second chain b .. c of base and offset.
struct LightChain {
    Float J = 0;                  // Phi(y)/Phi(x) (ChainDirectionsPerArea; |d omega_y,b / d omega_x,b| without glossy vertices)
    Float discX = 1, discY = 1;   // discrete lobe probabilities of the ideal specular interiors
    Spectrum chainX{1}, chainY{1};  // f |cos| of the interiors (Dirac coefficients at ideal specular ones)
    Float glossyRho = 1;          // the glossy interiors' factors of rho (ShiftLightTracingPath)
    Vec3 wiY1;                    // offset direction at b towards c
    Vec3 towardCamX, towardCamY;  // at c, towards the camera side
    ManifoldChain offChain;
    WalkedInterior walked;
};

// Empty chain towards a light at infinity: the environment shift (as the
// camera subpath's): the offset b keeps the direction towards the light at
// infinity, J = 1, if it escapes.
bool EnvironmentChain(const Scene &scene, const SurfaceInteraction &yHit, const Vec3 &woY1, const Vec3 &wiX1,
                      LightChain *ch, SubpathShiftStats *st) {
    st->shift.attempt(ShiftType::Environment);
    SurfaceInteraction hit;
    if (TraceSurface(scene, Interaction(yHit.p, yHit.n, woY1).spawnRay(wiX1), &hit)) {
        st->shift.fail(ShiftFailure::Occluded);
        return false;
    }
    st->shift.success(ShiftType::Environment);
    ch->J = 1;
    ch->wiY1 = wiX1;
    ch->towardCamX = ch->towardCamY = -wiX1;
    return true;
}

// Empty chain: the offset b reconnects to c.
bool ReconnectionChain(const Scene &scene, const PathVertex &x1, const PathVertex &xc, const SurfaceInteraction &yHit,
                       const Vec3 &woY1, const Vec3 &wiX1, LightChain *ch, SubpathShiftStats *st) {
    ReconnectionShift rc;
    if (!ReconnectToVertex(scene, x1.p, Interaction(yHit.p, yHit.n, woY1), xc, &st->shift, &rc)) return false;
    st->shift.success(ShiftType::Reconnection);
    ch->J = rc.jacobian;
    ch->wiY1 = rc.wi;
    ch->towardCamX = -wiX1;
    ch->towardCamY = -ch->wiY1;
    return true;
}

// The base's k chain interiors from b = x1 (camera side) towards c; interior
// j is light vertex s-2-j. Sets in, chainX and discX; *glossy: some interior
// is a near-specular glossy vertex.
bool BaseChainInterior(const Scene &scene, const ShiftSubpath &light, int s, int k, ChainInterior *in, LightChain *ch,
                       bool *glossy, SubpathShiftStats *st) {
    for (int j = 0; j < k; ++j) {
        const PathVertex &v = light.v[s - 2 - j];
        if (!VertexInteraction(scene, v, light.v[s - 1 - j].p, &in->si[j])) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        const BSDF &b = light.b[s - 2 - j];
        in->bsdf[j] = &b;
        in->wo[j] = Normalize(light.v[s - 1 - j].p - v.p);  // towards the camera side
        in->wi[j] = Normalize(light.v[s - 3 - j].p - v.p);
        in->transmit[j] = Transmits(in->wo[j], in->wi[j], Vec3(b.ns()));
        in->specular[j] = light.deltaSample[s - 2 - j] != 0;
        in->geomId[j] = v.geomId;
        if (!in->specular[j]) {
            // Near-specular glossy vertex: its direction towards c is a variable (J_b).
            *glossy = true;
            Spectrum fc = b.f(in->wo[j], in->wi[j], TransportMode::Radiance) * AbsDot(in->wi[j], Vec3(b.ns()));
            if (fc.isBlack()) {
                st->shift.fail(ShiftFailure::Geometry);
                return false;
            }
            ch->chainX *= fc;
            continue;
        }
        BSDFSample sx;
        if (!DeltaLobe(b, in->wo[j], in->transmit[j], TransportMode::Radiance, &sx) ||
            Dot(sx.wi, in->wi[j]) < 1 - kShiftDirTol) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        ch->chainX *= sx.f * AbsDot(sx.wi, Vec3(b.ns()));
        ch->discX *= sx.pdf;
    }
    return true;
}

// Each glossy interior g of the light path (vertex s-2-j) enters rho
// (ShiftLightTracingPath) with its MIS densities of common/ in both
// directions: p_omega,g towards b times the edge geometry there (the
// light-tracing strategy's density of the next vertex), and the edge
// geometry of g's edge towards c, which the camera side's density
// p_omega,g |cos|/d^2 carries beyond the ratio p_y,g / p_x,g of its rho:
//   glossyRho = prod_g (p_y,g Gb_y Gc_x) / (p_x,g Gb_x Gc_y).
bool GlossyChainRho(const ShiftSubpath &light, int s, int c, const SurfaceInteraction &yHit, const ChainInterior &in,
                    LightChain *ch, SubpathShiftStats *st) {
    const PathVertex &x1 = light.v[s - 1], &xc = light.v[c];
    const int k = s - 2 - c;
    auto chainPos = [&](bool off, int i) -> Point3 {  // chain vertex i: b, interiors, c
        if (!off) return i == 0 ? x1.p : i == k + 1 ? xc.p : light.v[s - 1 - i].p;
        return i == 0 ? yHit.p : i == k + 1 ? xc.p : ch->offChain.v[i].sp.p;
    };
    auto chainNormal = [&](bool off, int i) -> Vec3 {
        if (!off) return i == 0 ? Vec3(x1.ng) : i == k + 1 ? Vec3(xc.ng) : Vec3(light.v[s - 1 - i].ng);
        return i == 0 ? Vec3(yHit.n) : i == k + 1 ? Vec3(xc.ng) : Vec3(ch->walked.si[i - 1].n);
    };
    const bool cSurf = xc.onSurface();
    for (int j = 0; j < k; ++j) {
        if (in.specular[j]) continue;
        Float f[2];
        for (int off = 0; off < 2; ++off) {
            const BSDF &bg = off ? ch->walked.bsdf[j] : light.b[s - 2 - j];
            Point3 pg = chainPos(off, j + 1), pb = chainPos(off, j), pc = chainPos(off, j + 2);
            Float pdf = bg.pdf(Normalize(pc - pg), Normalize(pb - pg), TransportMode::Importance);
            Float gb = EdgeGeometry(pg, pb, chainNormal(off, j), true);
            Float gc = EdgeGeometry(pg, pc, chainNormal(off, j + 2), j + 2 < k + 1 || cSurf);
            f[off] = pdf * gb / gc;
        }
        if (!(f[0] > 0) || !(f[1] > 0)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        ch->glossyRho *= f[1] / f[0];
    }
    return true;
}

// Offset b (`yHit`, with direction woY1 towards the camera) connected to c:
// reconnection for an empty chain (k = 0), else a manifold walk.
bool ShiftChain(const SubpathShiftContext &ctx, const ShiftSubpath &light, int s, int c,
                const SurfaceInteraction &yHit, const Vec3 &woY1, const Vec3 &wiX1, Arena &arena, LightChain *ch,
                SubpathShiftStats *st) {
    const Scene &scene = *ctx.bidir->scene;
    const PathVertex &x1 = light.v[s - 1], &xc = light.v[c];
    const int k = s - 2 - c;
    if (k == 0 && xc.isInfiniteLight()) return EnvironmentChain(scene, yHit, woY1, wiX1, ch, st);
    if (k == 0) return ReconnectionChain(scene, x1, xc, yHit, woY1, wiX1, ch, st);
    ChainInterior in;
    if (k + 2 > kMaxManifoldVertices) {
        ++st->longChains;
        return false;
    }
    bool glossy = false;
    if (!BaseChainInterior(scene, light, s, k, &in, ch, &glossy, st)) return false;
    st->glossyChains += glossy;
    ManifoldChain base;
    // The walk ends on c's shape (an area light's emitting shape for a light vertex).
    int gidc = xc.type == VertexType::Surface ? xc.geomId : ctx.mscene->geomOfLight(xc.light);
    if (gidc < 0 ||
        !BuildChain(ctx, EndpointSP(x1.p, x1.ng, x1.geomId), in, k, EndpointSP(xc.p, xc.ng, gidc), &base)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    if (!WalkSecondChain(ctx, base, EndpointSP(yHit.p, yHit.n, yHit.geomId), in, arena, st, &ch->offChain,
                         &ch->walked, &ch->J))
        return false;
    ch->discY = ch->walked.prob;
    for (int j = 0; j < k; ++j) ch->chainY *= ch->walked.fcos[j];
    ch->wiY1 = Normalize(ch->offChain.v[1].sp.p - yHit.p);
    if (glossy && !GlossyChainRho(light, s, c, yHit, in, ch, st)) return false;
    ch->towardCamX = Normalize(light.v[c + 1].p - xc.p);
    ch->towardCamY = Normalize(ch->offChain.v[k].sp.p - xc.p);
    return true;
}

// Emission (c a light vertex) or BSDF value at c towards the camera side, and
// the solid-angle density of the light path's direction there.
void EvalAtChainEnd(const ShiftSubpath &light, int c, const Vec3 &towardCam, Spectrum *f, Float *pdf) {
    const PathVertex &xc = light.v[c];
    if (xc.isInfiniteLight()) {  // the same direction for base and offset: equal factors
        *f = Spectrum(1);
        *pdf = 1;
    } else if (xc.type == VertexType::Light && xc.isDeltaLight()) {
        // Point or spot light: intensity towards the camera side (radiance
        // arriving at unit distance) and the emission's directional density.
        LightLiSample ls;
        Float pp;
        *f = xc.light->sampleLi(Interaction(xc.p + towardCam, Vec3(0, 0, 0), Vec3(0, 0, 0)), Point2(0.5, 0.5), &ls)
                 ? ls.L
                 : Spectrum(0);
        xc.light->pdfLe(Ray(xc.p, towardCam), xc.ng, &pp, pdf);
    } else if (xc.type == VertexType::Light) {
        const AreaLight *al = static_cast<const AreaLight *>(xc.light);
        *f = al->L(Interaction(xc.p, xc.ng, towardCam), towardCam);
        Float pp;
        xc.light->pdfLe(Ray(xc.p, towardCam), xc.ng, &pp, pdf);
    } else if (xc.type == VertexType::Medium) {
        *f = Spectrum(xc.medium->phase.p(towardCam, Vec3(xc.wo)));
        *pdf = xc.medium->phase.p(Vec3(xc.wo), towardCam);
    } else {
        const BSDF &bcv = light.b[c];
        Vec3 wl = xc.wo;  // towards the light side
        *f = bcv.f(towardCam, wl, TransportMode::Radiance);
        *pdf = bcv.pdf(wl, towardCam, TransportMode::Importance);
    }
}


// The offset light-tracing path differs from the base only in light vertices
// c-1 .. s-1: they are swapped in place for the offset's and restored when this
// goes out of scope (copying whole subpaths per light-tracing strategy made
// long paths O(n^2)). kCapacity: the most vertices swapped (stack storage).
template <int kCapacity>
class SwappedLightVertices {
  public:
    SwappedLightVertices(const ShiftSubpath &light, int c, int s)
        : light_(light), lo_(std::max(c - 1, 0)), m_(s - lo_), ok_(m_ <= kCapacity) {
        for (int j = 0; ok_ && j < m_; ++j) {
            v_[j] = light.v[lo_ + j];
            b_[j] = light.b[lo_ + j];
        }
    }
    ~SwappedLightVertices() {
        for (int j = 0; ok_ && j < m_; ++j) {
            light_.v[lo_ + j] = v_[j];
            light_.b[lo_ + j] = b_[j];
        }
    }
    SwappedLightVertices(const SwappedLightVertices &) = delete;
    SwappedLightVertices &operator=(const SwappedLightVertices &) = delete;
    bool ok() const { return ok_; }

  private:
    const ShiftSubpath &light_;
    const int lo_, m_;
    const bool ok_;
    PathVertex v_[kCapacity];
    BSDF b_[kCapacity];
};

// The offset's area densities at c's neighbours, which change with the
// direction from c to the offset's b: c+1's forward (importance) and, where c
// scatters, c-1's reverse (radiance) density (the terms of BDPT's weight).
void UpdateChainEndDensities(const BidirContext &bc, PathVertex *yv, const BSDF *yb, int c) {
    const PathVertex &xc = yv[c];
    yv[c + 1].pdfFwd = PdfArea(bc, xc, c > 0 ? &yb[c] : nullptr, c > 0 ? &yv[c - 1] : nullptr, yv[c + 1],
                               TransportMode::Importance);
    if (c >= 1 && xc.scatters())
        yv[c - 1].pdfRev = PdfArea(bc, xc, &yb[c], &yv[c + 1], yv[c - 1], TransportMode::Radiance);
}

// BDPT weight of the offset light-tracing path (vertices swapped as above).
Float OffsetWeight(const BidirContext &bc, const ShiftSubpath &light, int s, int c, const SurfaceInteraction &yHit,
                   const LightChain &ch, const PathVertex &lens, Arena &arena, bool *ok) {
    const int k = s - 2 - c;
    const PathVertex &xc = light.v[c];
    const SwappedLightVertices<kMaxManifoldVertices + 3> swapped(light, c, s);
    *ok = swapped.ok();
    if (!*ok) return 0;
    PathVertex *yv = light.v;
    BSDF *yb = light.b;
    // An infinite light's origin moves with b, so that it lies in the same direction.
    if (xc.isInfiniteLight()) yv[c].p = yHit.p + (light.v[c].p - light.v[c + 1].p);
    for (int j = 0; j < k; ++j) {
        PathVertex &v = yv[s - 2 - j];
        const SurfaceInteraction &si = ch.walked.si[j];
        v.p = si.p;
        v.ng = si.n;
        v.ns = ch.walked.bsdf[j].ns();
        v.wo = Normalize(ch.offChain.v[j + 2].sp.p - si.p);
        v.pdfFwd = v.pdfRev = 0;
        yb[s - 2 - j] = ch.walked.bsdf[j];
    }
    {
        PathVertex &v = yv[s - 1];
        v.p = yHit.p;
        v.ng = yHit.n;
        v.wo = ch.wiY1;
        v.material = yHit.material;
        v.geomId = yHit.geomId;
        v.primId = yHit.primId;
        SurfaceInteraction si2 = yHit;
        si2.wo = ch.wiY1;
        yb[s - 1] = yHit.material->getBSDF(si2, arena, TransportMode::Importance);
        v.ns = yb[s - 1].ns();
        v.pdfRev = 0;
        v.pdfFwd = 0;
    }
    if (k > 0) yv[c].pdfRev = 0;
    UpdateChainEndDensities(bc, yv, yb, c);
    // A glossy interior is sampled from, unlike an ideal specular one: its
    // neighbours' densities are real (as in the base's light subpath).
    for (int m = c + 1; m <= s - 2; ++m)
        if (!light.deltaSample[m]) {
            yv[m + 1].pdfFwd = PdfArea(bc, yv[m], &yb[m], &yv[m - 1], yv[m + 1], TransportMode::Importance);
            yv[m - 1].pdfRev = PdfArea(bc, yv[m], &yb[m], &yv[m + 1], yv[m - 1], TransportMode::Radiance);
        }
    PathVertex lensY = lens;
    return MISWeight(bc, SubpathView{yv, yb, s}, SubpathView{&lensY, nullptr, 1}, s, 1, &lensY);
}

// ---- Scenes with media ------------------------------------------------------
// Empty second chain only (a chain of specular vertices fails, as the
// camera-subpath shift's: camera_shift.h): the offset b walks the base's
// camera segment lens -> x_1 in lockstep (the same interfaces; a medium
// vertex at the base's free-flight distance from its last interface, |T'| = 1)
// and reconnects to c. Both changed segments carry T_y / T_x, a medium b
// sigma_s(y) / sigma_s(x); f(y)/p(x) = f(x)/p(x) times these and the
// scattering factors' ratio (the base's value holds its distance densities
// and its transmittance estimates).
bool ShiftLightTracingPathMedia(const SubpathShiftContext &ctx, const ShiftSubpath &light, int s,
                                const PathVertex &lens, Point2 pRaster, const Spectrum &fx, Point2i off, Arena &arena,
                                Spectrum *fy, Float *wy, Float *rho, SubpathShiftStats *st, UniformSource rng) {
    const BidirContext &bc = *ctx.bidir;
    const Scene &scene = *bc.scene;
    if (s < 2) return false;
    const PathVertex &x1 = light.v[s - 1];
    const int c = FindChainEnd(ctx, light, s);
    if (c < 0) return false;
    if (s - 2 - c > 0) {
        ++st->mediaChains;
        return false;
    }
    const PathVertex &xc = light.v[c];
    const bool envC = xc.isInfiniteLight(), pointC = xc.type == VertexType::Light && !envC && xc.isDeltaLight();
    if (xc.type == VertexType::Light && !envC && !pointC && !(xc.light && (xc.light->flags & LIGHT_AREA))) return false;
    if (pointC && !xc.light) return false;
    const bool medB = x1.type == VertexType::Medium;

    ++st->shift.offsetPaths;
    Ray r1, ray;
    CameraSample c1{pRaster, Point2(0.5, 0.5)}, c2{Point2(pRaster.x + off.x, pRaster.y + off.y), Point2(0.5, 0.5)};
    Float w1 = bc.camera->generateRay(c1, &r1), w2 = bc.camera->generateRay(c2, &ray);
    if (!(w1 > 0) || !(w2 > 0)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    // The base's camera segment lens -> x_1, then the offset's in lockstep.
    const Interaction lensIt(lens.p, Normal3(0, 0, 0), Vec3(0, 0, 0));
    MediumPiece xl[kMaxMediumPieces], yl[kMaxMediumPieces];
    const Vec3 dLens = Normalize(x1.p - lens.p);
    const int nl = TraceSegmentPieces(scene, lensIt, scene.cameraMedium, AsInteraction(x1), false, dLens, xl);
    if (nl == 0) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    SurfaceInteraction isect;
    Point3 pm;
    const Medium *my;
    if (!LockstepSegment(scene, lensIt.spawnRay(Normalize(ray.d)), scene.cameraMedium, xl, nl,
                         medB ? SegmentEnd::Medium : SegmentEnd::Surface, yl, &isect, &pm, &my)) {
        st->shift.fail(ShiftFailure::Escaped);
        return false;
    }
    // The offset b as a vertex (Importance mode: the light subpath's).
    PathVertex yb;
    BSDF byR;
    Float sigmaRatio = 1;
    const Vec3 woY1 = -yl[nl - 1].d;
    if (medB) {
        yb.type = VertexType::Medium;
        yb.medium = my;
        yb.mediumIndex = x1.mediumIndex;
        yb.p = pm;
        const Float sx = my->sigmaTAt(x1.p).maxComponent();
        if (!(sx > 0)) return false;
        sigmaRatio = my->sigmaTAt(pm).maxComponent() / sx;
    } else {
        byR = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        if (!byR || ClassifyBSDF(&byR, ctx.threshold) != ShiftVertexClass::Rough) {
            st->shift.fail(ShiftFailure::ClassMismatch);
            return false;
        }
        yb.type = VertexType::Surface;
        yb.material = isect.material;
        yb.p = isect.p;
        yb.ng = isect.n;
        yb.geomId = isect.geomId;
        yb.primId = isect.primId;
        yb.mediumIndex = MediumIndexOf(scene, my);
    }
    // b -> c: the environment shift or a reconnection; the offset arrives in the base's medium.
    const Vec3 wiX1 = Normalize(light.v[s - 2].p - x1.p);
    Vec3 wiY1;
    Float J;
    if (envC) {
        st->shift.attempt(ShiftType::Environment);
        wiY1 = wiX1;
        J = 1;
    } else {
        st->shift.attempt(ShiftType::Reconnection);
        ShiftVertex tgt;
        tgt.p = xc.p;
        tgt.n = xc.onSurface() ? Vec3(xc.ng) : Vec3(0, 0, 0);
        ReconnectionShift rc;
        if (!ShiftReconnect(x1.p, yb.p, tgt, &rc)) {
            st->shift.fail(ShiftFailure::Geometry);
            return false;
        }
        wiY1 = rc.wi;
        J = rc.jacobian;
    }
    yb.wo = wiY1;
    const Interaction ybIt = medB ? Interaction(pm, Normal3(0, 0, 0), woY1) : Interaction(isect.p, isect.n, woY1);
    const Interaction xcIt = AsInteraction(xc);
    if ((!medB && InTangentPlane(ybIt.n, wiY1)) || (!envC && xc.onSurface() && InTangentPlane(xcIt.n, wiY1))) {
        st->shift.fail(ShiftFailure::Occluded);
        return false;
    }
    MediumPiece xcP[kMaxMediumPieces], ycP[kMaxMediumPieces];
    const Medium *mxb = MediumTowards(bc, x1, wiX1);
    const Medium *myb = medB ? my : isect.mediumAfter(wiY1, my);
    const int nxc = TraceSegmentPieces(scene, AsInteraction(x1), mxb, xcIt, envC, wiX1, xcP);
    const int nyc = TraceSegmentPieces(scene, ybIt, myb, xcIt, envC, wiY1, ycP);
    if (nxc == 0 || nyc == 0 || ycP[nyc - 1].medium != xcP[nxc - 1].medium) {
        st->shift.fail(ShiftFailure::Occluded);
        return false;
    }
    st->shift.success(envC ? ShiftType::Environment : ShiftType::Reconnection);
    const Spectrum T = TransmittanceRatio(yl, nl, xl, nl, rng) * TransmittanceRatio(ycP, nyc, xcP, nxc, rng);
    // Eq. 5 in the camera-side parameterisation: f(y)|T'| / f(x).
    const Vec3 woX1 = Normalize(lens.p - x1.p);
    Spectrum fX1, fY1;
    if (medB) {
        fX1 = Spectrum(x1.medium->phase.p(woX1, wiX1));
        fY1 = Spectrum(my->phase.p(woY1, wiY1) * J);
    } else {
        const BSDF &bx = light.b[s - 1];
        fX1 = bx.f(woX1, wiX1, TransportMode::Radiance) * AbsDot(wiX1, Vec3(bx.ns()));
        fY1 = byR.f(woY1, wiY1, TransportMode::Radiance) * AbsDot(wiY1, Vec3(byR.ns())) * J;
    }
    Spectrum fXc, fYc;
    Float pcX, pcY;
    EvalAtChainEnd(light, c, -wiX1, &fXc, &pcX);
    EvalAtChainEnd(light, c, -wiY1, &fYc, &pcY);
    *fy = fx * SafeDiv(fY1 * fYc * (w2 / w1), fX1 * fXc) * T * sigmaRatio;
    if (fy->isBlack() || !fy->isFinite()) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    // rho = |T'| p(y)/p(x) (Eq. 8), as ShiftLightTracingPath's for an empty
    // chain, without cosines at a medium b (ConvertDensity's measure).
    const Vec3 n0 = bc.camera->lensNormal();
    const Float Fx = medB ? EyeVolumeFactor(lens.p, n0, x1.p) : EyeAreaFactor(lens.p, n0, x1.p, x1.ng);
    const Float Fy = medB ? EyeVolumeFactor(lens.p, n0, pm) : EyeAreaFactor(lens.p, n0, isect.p, isect.n);
    Float G1x = EdgeGeometry(x1.p, xc.p, Vec3(xc.ng), xc.onSurface());
    Float G1y = EdgeGeometry(yb.p, xc.p, Vec3(xc.ng), xc.onSurface());
    Float Gcx = EdgeGeometry(xc.p, x1.p, Vec3(x1.ng), !medB), Gcy = EdgeGeometry(xc.p, yb.p, Vec3(yb.ng), !medB);
    if (envC) {
        G1x = G1y = 1;
        Gcx = medB ? 1 : AbsDot(wiX1, Vec3(x1.ng));
        Gcy = medB ? 1 : AbsDot(wiX1, Vec3(yb.ng));
    }
    const Float denR = Fx * G1y * pcX * Gcx;
    *rho = denR > 0 ? Fy * J * G1x * pcY * Gcy / denR : 0;

    // BDPT weight of the offset: light vertex s-1 swapped for y_b (restored after).
    const SwappedLightVertices<3> swapped(light, c, s);  // empty chain: c-1 .. c+1
    PathVertex *yv = light.v;
    BSDF *ybs = light.b;
    if (envC) yv[c].p = yb.p + (light.v[c].p - light.v[c + 1].p);
    {
        PathVertex &v = yv[s - 1];
        const PathVertex keep = v;
        v = yb;
        v.flags = keep.flags;
        v.rrScale = keep.rrScale;
        v.setThroughput(keep.throughput());
        if (medB) {
            ybs[s - 1] = BSDF();
        } else {
            SurfaceInteraction si2 = isect;
            si2.wo = wiY1;
            ybs[s - 1] = isect.material->getBSDF(si2, arena, TransportMode::Importance);
            v.ns = ybs[s - 1].ns();
        }
        v.pdfRev = 0;
        v.pdfFwd = 0;
    }
    UpdateChainEndDensities(bc, yv, ybs, c);
    PathVertex lensY = lens;
    *wy = MISWeight(bc, SubpathView{yv, ybs, s}, SubpathView{&lensY, nullptr, 1}, s, 1, &lensY);
    return *wy > 0;
}

}  // namespace

bool ShiftLightTracingPath(const SubpathShiftContext &ctx, const ShiftSubpath &light, int s, const PathVertex &lens,
                           Point2 pRaster, const Spectrum &fx, Point2i off, Arena &arena, Spectrum *fy, Float *wy,
                           Float *rho, SubpathShiftStats *st, UniformSource rng) {
    if (ctx.media) return ShiftLightTracingPathMedia(ctx, light, s, lens, pRaster, fx, off, arena, fy, wy, rho, st, rng);
    const BidirContext &bc = *ctx.bidir;
    if (s < 2) return false;
    const PathVertex &x1 = light.v[s - 1];
    const int c = FindChainEnd(ctx, light, s);
    if (c < 0) return false;
    const int k = s - 2 - c;  // interior (ideal specular) vertices
    if (k > 0 && (!ctx.manifold || !ctx.trySpecular)) return false;
    const PathVertex &xc = light.v[c];
    // Light vertices as c: area lights (reconnection or walk), infinite and
    // distant lights (environment shift) and point/spot lights (reconnection to
    // the point) when the chain is empty.
    const bool envC = xc.isInfiniteLight(), pointC = xc.type == VertexType::Light && !envC && xc.isDeltaLight();
    if ((envC || pointC) && k > 0) return false;
    if (xc.type == VertexType::Light && !envC && !pointC && !(xc.light && (xc.light->flags & LIGHT_AREA))) return false;
    if (pointC && !xc.light) return false;

    ++st->shift.offsetPaths;
    Ray r1, ray;
    CameraSample c1{pRaster, Point2(0.5, 0.5)}, c2{Point2(pRaster.x + off.x, pRaster.y + off.y), Point2(0.5, 0.5)};
    Float w1 = bc.camera->generateRay(c1, &r1), w2 = bc.camera->generateRay(c2, &ray);
    if (!(w1 > 0) || !(w2 > 0)) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    SurfaceInteraction isect;
    if (!TraceSurface(*bc.scene, ray, &isect)) {
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
    LightChain ch;
    if (!ShiftChain(ctx, light, s, c, isect, woY1, wiX1, arena, &ch, st)) return false;
    // Eq. 5 in the camera-side parameterisation: f(y)|T'| / f(x).
    const Vec3 &wiY1 = ch.wiY1;
    Spectrum fX1 = bx.f(woX1, wiX1, TransportMode::Radiance) * AbsDot(wiX1, Vec3(bx.ns()));
    Spectrum fY1 = by.f(woY1, wiY1, TransportMode::Radiance) * AbsDot(wiY1, Vec3(by.ns())) * ch.J;
    Spectrum fXc, fYc;
    Float pcX, pcY;  // solid-angle density of the light path's direction at c
    EvalAtChainEnd(light, c, ch.towardCamX, &fXc, &pcX);
    EvalAtChainEnd(light, c, ch.towardCamY, &fYc, &pcY);
    Spectrum num = fY1 * ch.chainY * fYc * (w2 / w1), den = fX1 * ch.chainX * fXc;
    *fy = fx * SafeDiv(num, den);
    if (fy->isBlack() || !fy->isFinite()) {
        st->shift.fail(ShiftFailure::Geometry);
        return false;
    }
    // rho = |T'| p(y)/p(x) (Eq. 8): image-plane area factor dA_b/ds =
    // cos^3 D^2 / |cos_b| (ShiftJacobianFactor's cos^4/G for an empty eye
    // chain) times the light path's density of b through the chain.
    Vec3 n0 = bc.camera->lensNormal();
    // The MIS densities of common/ (area measure, Dirac factors remapped to 1)
    // and the camera-side rho of the same path's other strategies imply the
    // effective |T'| = (F_y/F_x) J_b (disc_y/disc_x) (G1_x/G1_y), G1 = |cos|/d^2
    // of the first edge after b; the light-tracing strategy's density ratio is
    // that of the vertex after c, p_omega,c G1c. (For an empty chain this is
    // F p_omega,c Q, the exact |T'| p(y)/p(x).)
    Float Fx = EyeAreaFactor(lens.p, n0, x1.p, x1.ng), Fy = EyeAreaFactor(lens.p, n0, isect.p, isect.n);
    const PathVertex &xn = light.v[s - 2];  // the vertex after b towards c (base)
    Point3 ynP = k > 0 ? ch.offChain.v[1].sp.p : xc.p;
    Vec3 ynN = k > 0 ? Vec3(ch.walked.si[0].n) : Vec3(xc.ng);
    Float G1x = EdgeGeometry(x1.p, xn.p, Vec3(xn.ng), xn.onSurface());
    Float G1y = EdgeGeometry(isect.p, ynP, ynN, xn.onSurface());
    if (envC) G1x = G1y = 1;  // b's direction towards infinity is the variable (J = 1)
    // Vertex after c towards b: base light.v[c + 1], offset the last walked vertex or y1.
    const PathVertex &xa = light.v[c + 1];
    Point3 yaP = k > 0 ? ch.offChain.v[k].sp.p : isect.p;
    Vec3 yaN = k > 0 ? Vec3(ch.walked.si[k - 1].n) : Vec3(isect.n);
    Float Gcx = EdgeGeometry(xc.p, xa.p, Vec3(xa.ng), true), Gcy = EdgeGeometry(xc.p, yaP, yaN, true);
    if (envC) {
        // From infinity the density of b is the disk's positional one projected
        // on b: |cos_b| without a distance (GenerateLightSubpath).
        Gcx = AbsDot(wiX1, Vec3(xa.ng));
        Gcy = AbsDot(wiX1, yaN);
    }
    Float denR = Fx * ch.discX * G1y * pcX * Gcx;
    *rho = denR > 0 ? Fy * ch.J * ch.discY * G1x * pcY * Gcy * ch.glossyRho / denR : 0;

    bool ok;
    *wy = OffsetWeight(bc, light, s, c, isect, ch, lens, arena, &ok);
    return ok && *wy > 0;
}

}  // namespace gradus
