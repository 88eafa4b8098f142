#include "integrators/pmlt/path.h"

#include <cmath>

#include "lights/light.h"

namespace gradus::pmlt {

namespace {

Float CosAt(const BidirContext &ctx, const PathVertex &v, const Vec3 &w) {
    if (v.type == VertexType::Camera) return AbsDot(Vec3(ctx.camera->lensNormal()), w);
    return v.onSurface() ? AbsDot(Vec3(v.ng), w) : Float(1);
}

// Emitted radiance (area and infinite lights) or intensity (point and spot
// lights) of emitter vertex e towards vertex to: the factor of F at the emitter.
Spectrum EmitterValue(const BidirContext &ctx, const PathVertex &e, const PathVertex &to) {
    const Light *light = EmitterOf(ctx, e);
    const bool deltaDir = light && (light->flags & LIGHT_DELTA_DIRECTION);
    if (!deltaDir && (e.isInfiniteLight() || (light && (light->flags & LIGHT_AREA))))
        return EmittedRadiance(ctx, e, to);
    if (!light || !IsDeltaLight(light->flags)) return Spectrum(0);
    // Delta lights: sampleLi gives the radiance of a distant light and
    // intensity / distance^2 of a point or spot light at `to`.
    LightLiSample ls;
    if (!light->sampleLi(Interaction(to.p, Vec3(0, 0, 0), Vec3(0, 0, 0)), Point2(0.5, 0.5), &ls)) return Spectrum(0);
    return deltaDir ? ls.L : ls.L * (e.p - to.p).lengthSquared();
}

}  // namespace

Vec3 Dir(const PathVertex &from, const PathVertex &to) {
    const Vec3 d = to.p - from.p;
    const Float l2 = d.lengthSquared();
    return l2 > 0 ? d / std::sqrt(l2) : Vec3(0, 0, 0);
}

Float EtaSquared(const BSDF &bsdf, const Vec3 &w) {
    const Float eta = bsdf.eta();
    return Dot(w, Vec3(bsdf.ns())) < 0 ? eta * eta : Float(1);
}

Float GeometryTerm(const BidirContext &ctx, const PathVertex &a, const PathVertex &b) {
    if (a.isInfiniteLight()) return CosAt(ctx, b, Dir(b, a));
    if (b.isInfiniteLight()) return CosAt(ctx, a, Dir(a, b));
    const Vec3 d = b.p - a.p;
    const Float d2 = d.lengthSquared();
    if (d2 == 0) return 0;
    const Vec3 w = d / std::sqrt(d2);
    return CosAt(ctx, a, w) * CosAt(ctx, b, w) / d2;
}

bool SpecularLobe(const BSDF &bsdf, const Vec3 &wo, const Vec3 &wi, TransportMode mode, Spectrum *f, Float *prob) {
    // The lobes are found by sampling with lobe-selection numbers across [0, 1);
    // a specular sample's direction is a function of wo, so it matches wi up to
    // the precision of the vertex positions.
    for (Float uc : {Float(0), Float(0.25), Float(0.5), Float(0.75), Float(OneMinusEpsilon)}) {
        BSDFSample s;
        if (!bsdf.sample(wo, uc, Point2(0.5, 0.5), mode, &s) || !s.isSpecular() || !(s.pdf > 0)) continue;
        // 1e-5: an angle of 4.5e-3 rad, far below the separation of a BSDF's
        // specular lobes, above the error of float hit points on short edges.
        if (Dot(s.wi, wi) > 1 - 1e-5) {
            *f = s.f;
            *prob = s.pdf;
            return true;
        }
    }
    return false;
}

bool SampleSpecularLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *out) {
    for (Float uc : {Float(0), Float(0.25), Float(0.5), Float(0.75), Float(OneMinusEpsilon)}) {
        BSDFSample s;
        if (!bsdf.sample(wo, uc, Point2(0.5, 0.5), mode, &s) || !s.isSpecular() || !(s.pdf > 0)) continue;
        if (s.isTransmission() == transmit) {
            *out = s;
            return true;
        }
    }
    return false;
}

namespace {

// The camera's factor of F, We G(x_0, x_1), the film position and the lens and
// x_1 densities (Evaluate). The film positions are sampled over the pixel
// bounds, film.scale times denser than the camera's density over the full film.
bool CameraFactor(const BidirContext &ctx, const FilmDomain &film, const Path &x, PathEval *e, Spectrum *factor) {
    const PathVertex &c = x.v[0];
    const Vec3 w01 = Dir(c, x.v[1]);
    const Ray ray(c.p, w01);
    const Spectrum We = ctx.camera->We(ray, &e->pRaster);
    if (We.isBlack() || !film.contains(e->pRaster)) return false;
    Float pdfPos = 0, pdfDir = 0;
    ctx.camera->pdfWe(ray, &pdfPos, &pdfDir);
    e->pE[0] = e->pL[0] = pdfPos > 0 ? pdfPos : Float(1);
    e->pE[1] = ConvertDensity(pdfDir * film.scale, c, x.v[1]);
    *factor = We * GeometryTerm(ctx, c, x.v[1]);
    return true;
}

// Scattering vertex x_i's factor of F and the densities of its neighbours from
// it: pE[i + 1] (camera side) and, with lightSide, pL[i - 1] (light side).
bool ScatterFactor(const BidirContext &ctx, const Path &x, const BSDF *bsdfs, int i, bool lightSide, PathEval *e,
                   Spectrum *factor) {
    const PathVertex &v = x.v[size_t(i)], &prev = x.v[size_t(i - 1)], &next = x.v[size_t(i + 1)];
    const BSDF &b = bsdfs[i];
    if (v.type != VertexType::Surface || !b) return false;
    const Vec3 wo = Dir(v, prev), wi = Dir(v, next);
    const Vec3 ns = Vec3(b.ns()), ng = Vec3(v.ng);
    const Float cosNg = AbsDot(wi, ng);
    if (cosNg == 0) return false;
    Spectrum f;
    Float pdfCam, pdfLight = 0;  // solid-angle densities towards next (camera side) and prev (light side)
    if (v.delta()) {
        // Delta-free specular factors (path.h): both lobes against mu = eta^2 |cos_ns| dw.
        Float probE, probL = 1;
        Spectrum fl, fImp;
        if (!SpecularLobe(b, wo, wi, TransportMode::Radiance, &fl, &probE)) return false;
        if (lightSide && !SpecularLobe(b, wi, wo, TransportMode::Importance, &fImp, &probL)) return false;
        const Float muNext = AbsDot(wi, ns) * EtaSquared(b, wi);
        f = fl * muNext;
        pdfCam = probE * muNext;
        if (lightSide) pdfLight = probL * AbsDot(wo, ns) * EtaSquared(b, wo);
        e->lobeE[size_t(i)] = probE;
        e->lobeL[size_t(i)] = probL;
    } else {
        f = b.f(wo, wi, TransportMode::Radiance);
        pdfCam = b.pdf(wo, wi, TransportMode::Radiance);
        if (lightSide) pdfLight = b.pdf(wi, wo, TransportMode::Importance);
    }
    // pbrt-v3's shading-normal convention for radiance transport (path.h).
    *factor = f * (AbsDot(wi, ns) / cosNg) * GeometryTerm(ctx, v, next);
    e->pE[size_t(i + 1)] = ConvertDensity(pdfCam, v, next);
    if (lightSide) e->pL[size_t(i - 1)] = ConvertDensity(pdfLight, v, prev);
    return true;
}

void ResetEval(int n, PathEval *e) {
    e->F = Spectrum(0);
    e->I = 0;
    e->pE.assign(size_t(n), 0);
    e->pL.assign(size_t(n), 0);
    e->lobeE.assign(size_t(n), 1);
    e->lobeL.assign(size_t(n), 1);
    e->factor.assign(size_t(n), Spectrum(0));
    e->complete = false;
}

bool SetContribution(const Spectrum &F, PathEval *e) {
    if (F.isBlack() || !F.isFinite()) return false;
    e->F = F;
    const double y = F.y();
    e->I = y > 0 ? Float(y) : 0;
    return e->I > 0;
}

}  // namespace

bool Evaluate(const BidirContext &ctx, const FilmDomain &film, const Path &x, const BSDF *bsdfs, PathEval *e) {
    const int n = x.size();
    ResetEval(n, e);
    if (n < 2 || x.v[0].type != VertexType::Camera) return false;
    const PathVertex &last = x.v[size_t(n - 1)];
    if (!CameraFactor(ctx, film, x, e, &e->factor[0])) return false;
    Spectrum F = e->factor[0];
    // Scattering vertices: F's factor and the densities of both neighbours.
    for (int i = 1; i + 1 < n; ++i) {
        if (!ScatterFactor(ctx, x, bsdfs, i, true, e, &e->factor[size_t(i)])) return false;
        F *= e->factor[size_t(i)];
        if (F.isBlack()) return false;
    }
    e->pL[0] = e->pE[0];

    // Emitter.
    const PathVertex &toward = x.v[size_t(n - 2)];
    e->factor[size_t(n - 1)] = EmitterValue(ctx, last, toward);
    F *= e->factor[size_t(n - 1)];
    if (F.isBlack() || !F.isFinite()) return false;
    const Light *light = EmitterOf(ctx, last);
    const bool deltaLight = light && IsDeltaLight(light->flags);
    Float origin = PdfLightOrigin(ctx, last, toward);
    if (deltaLight && light) origin = ctx.lightSampler->pmf(light);  // the position's delta is in every technique
    e->pL[size_t(n - 1)] = origin;
    e->pL[size_t(n - 2)] = n - 2 == 0 ? e->pE[0] : PdfLightDirection(ctx, last, toward);
    if (deltaLight) e->pE[size_t(n - 1)] = 0;  // a delta light is never hit
    e->complete = SetContribution(F, e);
    return e->complete;
}

bool EvaluateChangedPrefix(const BidirContext &ctx, const FilmDomain &film, const Path &y, const BSDF *bsdfs,
                           const PathEval &ex, int last, PathEval *e) {
    const int n = y.size();
    if (!ex.complete || int(ex.factor.size()) != n) return Evaluate(ctx, film, y, bsdfs, e);
    ResetEval(n, e);
    if (n < 2 || y.v[0].type != VertexType::Camera) return false;
    Spectrum F, factor;
    if (!CameraFactor(ctx, film, y, e, &F)) return false;
    // Vertices 1 .. last moved; x_{last+1}'s factor changes with its wo, the
    // emitter's with the vertex before it; the factors after that are x's.
    const int lastScatter = std::min(last + 1, n - 2);
    for (int i = 1; i <= lastScatter; ++i) {
        if (!ScatterFactor(ctx, y, bsdfs, i, false, e, &factor)) return false;
        F *= factor;
        if (F.isBlack()) return false;
    }
    for (int i = lastScatter + 1; i + 1 < n; ++i) F *= ex.factor[size_t(i)];
    F *= last + 1 >= n - 1 ? EmitterValue(ctx, y.v[size_t(n - 1)], y.v[size_t(n - 2)]) : ex.factor[size_t(n - 1)];
    return SetContribution(F, e);
}

PathVertex LensVertex(const BidirContext &ctx, const Ray &ray) {
    PathVertex c;
    c.type = VertexType::Camera;
    c.p = ray.o;
    c.ng = c.ns = ctx.camera->lensNormal();
    return c;
}

bool StrategyPath(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t,
                  const ConnectSamples &cu, Path *x) {
    x->v.clear();
    if (t < 1 || s < 0 || (t == 1 && s < 1)) return false;
    if (t >= 2) {
        x->v.assign(camera.v, camera.v + t);
    } else {
        PathVertex lens;
        CameraWiSample cws;
        if (!SampleLensVertex(ctx, light.v[s - 1], cu.uLens, &lens, &cws)) return false;
        x->v.push_back(lens);
    }
    if (s == 1) {
        PathVertex lv;
        LightLiSample ls;
        Spectrum w;
        if (!SampleLightVertex(ctx, camera.v[t - 1], cu.uLightSelect, cu.uLight, &lv, &ls, &w)) return false;
        x->v.push_back(lv);
    } else {
        for (int j = s - 1; j >= 0; --j) x->v.push_back(light.v[j]);
    }
    const int n = x->size();
    for (int j : {0, t - 1, std::min(t, n - 1), n - 1}) x->v[size_t(j)].flags &= uint8_t(~VERTEX_DELTA);
    for (int j = 1; j < n; ++j) x->v[size_t(j)].wo = PackedVec3(Dir(x->v[size_t(j)], x->v[size_t(j - 1)]));
    return true;
}

bool ValidSplit(const BidirContext &ctx, const Path &x, const PathEval &e, int t) {
    const int n = x.size();
    if (t < 1 || t > n) return false;
    if (t == n) return e.pE[size_t(n - 1)] > 0;
    // The emitter joined straight to the lens, bdpt's (1, 1): not a technique.
    // A point or spot light would otherwise be seen by the camera, which no
    // other technique (nor pbrt-v3) renders.
    if (t == 1 && n == 2) return false;
    const PathVertex &a = x.v[size_t(t - 1)], &b = x.v[size_t(t)];
    if (a.delta() || b.delta()) return false;
    if (a.type == VertexType::Surface && a.material == nullptr) return false;
    if (b.type == VertexType::Light && b.light && (b.light->flags & LIGHT_DELTA_DIRECTION)) return false;
    // No connection ends at infinity: a vertex at infinity stands for a
    // direction, which a connection from a moved vertex would not keep (the
    // bidirectional mutation never samples one alone, mutations.cpp).
    if (a.isInfiniteLight() || b.isInfiniteLight()) return false;
    return EdgeConnectible(ctx, a, b);
}

Float PathEval::splitDensity(const Path &x, const BidirContext &ctx, int t, int lo, int hi) const {
    if (!ValidSplit(ctx, x, *this, t)) return 0;
    double p = 1;
    for (int i = lo; i < hi; ++i) p *= i < t ? pE[size_t(i)] : pL[size_t(i)];
    return Float(p);
}

}  // namespace gradus::pmlt
