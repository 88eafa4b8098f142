#include "integrators/pmlt/mutations.h"

#include <algorithm>
#include <cmath>

#include "integrators/gradient/subpath_shift.h"
#include "lights/light.h"

namespace gradus::pmlt {

bool Trace(const BidirContext &ctx, const PathVertex &from, const Vec3 &dir, Arena &arena, bool allowInfinite,
           PathVertex *v, BSDF *b, SurfaceInteraction *si) {
    Ray ray = AsInteraction(from).spawnRay(dir);
    SurfaceInteraction local;
    SurfaceInteraction &isect = si ? *si : local;
    const Scene::SurfaceHit h = ctx.scene->intersectSurface(&ray, &isect);
    if (h == Scene::SurfaceHit::Stuck) return false;
    if (h == Scene::SurfaceHit::Miss) {
        if (!allowInfinite || ctx.scene->infiniteLights.empty()) return false;
        *v = PathVertex();
        v->type = VertexType::Light;
        v->flags = VERTEX_INFINITE;
        v->light = nullptr;
        v->p = from.p + dir;
        v->ng = -dir;
        v->wo = -dir;
        *b = BSDF();
        return true;
    }
    const BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
    MakeSurfaceVertex(ctx, isect, bsdf, v);
    *b = bsdf;
    return true;
}

namespace {

// Samples a scattering direction at v (arrived at from wo); marks v specular
// when a specular lobe was chosen.
bool Scatter(PathVertex *v, const BSDF &b, const Vec3 &wo, TransportMode mode, Sampler &u, Vec3 *wi) {
    if (!b) return false;
    const Float uc = u.get1D();
    const Point2 u2 = u.get2D();
    BSDFSample bs;
    if (!b.sample(wo, uc, u2, mode, &bs) || !bs.valid()) return false;
    v->flags = uint8_t(bs.isSpecular() ? (v->flags | VERTEX_DELTA) : (v->flags & ~VERTEX_DELTA));
    *wi = bs.wi;
    return true;
}

}  // namespace

bool FollowSpecular(const Path &x, int j, PathVertex *v, const BSDF &b, const Vec3 &wo, TransportMode mode,
                    Vec3 *wi) {
    const PathVertex &xj = x.v[size_t(j)];
    const Vec3 ng = xj.ng;
    const bool transmit = Dot(Dir(xj, x.v[size_t(j - 1)]), ng) * Dot(Dir(xj, x.v[size_t(j + 1)]), ng) < 0;
    BSDFSample bs;
    if (!b || !SampleSpecularLobe(b, wo, transmit, mode, &bs)) return false;
    v->flags |= VERTEX_DELTA;
    *wi = bs.wi;
    return true;
}

ShiftClass ShiftClassOf(const PathVertex &v, const BSDF &b, Float threshold) {
    if (v.delta()) return ShiftClass::Dirac;
    if (v.type != VertexType::Surface || !b) return ShiftClass::Rough;
    const Float r = b.roughness();  // the lowest of its lobes: 0 with a Dirac lobe among them
    return r > 0 && r < threshold ? ShiftClass::NearSpecular : ShiftClass::Rough;
}

namespace {

// A film offset (density ~ 1/r on [r1, r2], uniform angle; symmetric).
Point2 PerturbFilm(Point2 p, Float r1, Float r2, Sampler &u) {
    const Float r = r2 * std::exp(-std::log(r2 / r1) * u.get1D());
    const Float phi = 2 * Pi * u.get1D();
    return Point2(p.x + r * std::cos(phi), p.y + r * std::sin(phi));
}

// A direction at angle theta (density ~ 1/theta on [t1, t2]) from w, uniform
// azimuth: a density per solid angle that depends on the angle only (symmetric).
Vec3 PerturbDirection(const Vec3 &w, Float t1, Float t2, Sampler &u) {
    const Float theta = t2 * std::exp(-std::log(t2 / t1) * u.get1D());
    const Float phi = 2 * Pi * u.get1D();
    Vec3 s, t;
    CoordinateSystem(w, &s, &t);
    const Float st = std::sin(theta);
    return Normalize(s * (st * std::cos(phi)) + t * (st * std::sin(phi)) + w * std::cos(theta));
}

bool Visible(const BidirContext &ctx, const PathVertex &a, const PathVertex &b) {
    return EdgeConnectible(ctx, a, b) && ctx.scene->unoccluded(AsInteraction(a), AsInteraction(b));
}

// Index into [0, n) from a uniform number.
int Pick(Float u, int n) { return std::min(int(u * Float(n)), n - 1); }

Float DeleteWeight(int nd) { return nd == 0 ? 0.25 : nd == 1 ? 0.5 : std::ldexp(1.0, -(nd + 1)); }

Float AddWeight(int delta) {
    const int d = std::abs(delta);
    return d == 0 ? 0.5 : d == 1 ? 0.15 : d == 2 ? 0.05 : 0.02 * std::ldexp(1.0, -(d - 3));
}

}  // namespace

const char *MutationName(MutationType t) {
    switch (t) {
    case MutationType::Bidirectional: return "bidirectional";
    case MutationType::Lens: return "lens";
    case MutationType::Caustic: return "caustic";
    case MutationType::MultiChain: return "multichain";
    case MutationType::Manifold: return "manifold";
    }
    return "?";
}

void BuildBSDFs(const BidirContext &ctx, const Path &x, Arena &arena, std::vector<BSDF> *bsdf) {
    bsdf->resize(x.v.size());
    for (size_t i = 0; i < x.v.size(); ++i) (*bsdf)[i] = RebuildBSDF(ctx, x.v[i], TransportMode::Radiance, arena);
}

Mutator::Mutator(const BidirContext &ctx, const FilmDomain &film, const MutationSettings &s)
    : ctx_(ctx), film_(film), set_(s) {
    if (set_.lensR2 <= 0) set_.lensR2 = Float(0.1) * Float(std::max(film.pixels.width(), film.pixels.height()));
    set_.lensR2 = std::max(set_.lensR2, set_.lensR1 * Float(1.0001));
    // Tables of the bidirectional mutation's choice probabilities (O(1) each).
    const int maxN = set_.maxDepth + 2;
    deleteNorm_.assign(size_t(maxN) + 1, 0.0);
    for (int n = 2; n <= maxN; ++n)
        for (int k = 0; k <= n; ++k)
            if (positionCount(n, k) > 0) deleteNorm_[size_t(n)] += DeleteWeight(k);
    addOffset_ = maxN + 1;
    addPrefix_.assign(size_t(2 * addOffset_ + 2), 0.0);
    for (size_t i = 1; i < addPrefix_.size(); ++i) addPrefix_[i] = addPrefix_[i - 1] + AddWeight(int(i) - 1 - addOffset_);
}

ProposalResult Mutator::propose(MutationType type, const State &x, Sampler &u, Arena &arena, State *y,
                                double *ratioOut, MutationStats *stats) const {
    *ratioOut = 0;
    if (!applies(type, x.x)) return ProposalResult::NotApplicable;
    switch (type) {
    case MutationType::Bidirectional: return bidirectional(x, u, arena, y, ratioOut);
    case MutationType::Lens: return lens(x, false, u, arena, y, ratioOut);
    case MutationType::MultiChain: return lens(x, true, u, arena, y, ratioOut);
    case MutationType::Caustic: return caustic(x, u, arena, y, ratioOut);
    case MutationType::Manifold: return manifold(x, u, arena, y, ratioOut, stats);
    }
    return ProposalResult::NotApplicable;
}

// ---------------------------------------------------------------- bidirectional mutation
// Deleting [a, a + nd) keeps a prefix of a vertices and a suffix of n - a - nd.
// A kept part is never the lone lens or the lone emitter (a new direction from
// a fixed lens point or emitter point would need densities the camera and light
// interfaces do not offer); inserting (nd = 0) or joining the kept parts
// (na = 0) needs both parts to end on surfaces. The rules depend on (n, nd, a,
// na) only and hold for the reverse move with (n', na, a, nd).
bool Mutator::allowedPosition(int n, int nd, int a) const {
    const int suffix = n - a - nd;
    if (a < 0 || suffix < 0 || a == 1 || suffix == 1) return false;
    if (nd == 0) return a >= 2 && suffix >= 2;
    return true;
}

int Mutator::positionCount(int n, int nd) const {
    // allowedPosition in closed form: a in [0, n - nd] without a = 1 and
    // without a = n - nd - 1 (a lone kept emitter); insertions a in [2, n - 2].
    if (nd < 0 || nd > n) return 0;
    if (nd == 0) return std::max(0, n - 3);
    const int A = n - nd;
    return (A + 1) - (A >= 1 ? 1 : 0) - (A >= 1 && A - 1 != 1 ? 1 : 0);
}

Float Mutator::deletionProbability(int n, int nd) const {
    if (positionCount(n, nd) == 0) return 0;
    // Normaliser over the deletion counts that have a position (cached per n).
    if (n >= int(deleteNorm_.size())) return 0;
    return DeleteWeight(nd) / deleteNorm_[size_t(n)];
}

bool Mutator::allowedAddition(int n, int nd, int a, int na) const {
    const int np = n - nd + na, suffix = n - a - nd;
    if (na < 0 || np < 2 || np > set_.maxDepth + 2) return false;
    if (nd == 0 && na == 0) return false;
    if (na == 0) return a >= 2 && suffix >= 2;
    return true;
}

Float Mutator::additionProbability(int n, int nd, int a, int na) const {
    if (!allowedAddition(n, nd, a, na)) return 0;
    // The allowed counts are a contiguous range [lo, hi] (less na = 0 when
    // that is not allowed): the normaliser from prefix sums of AddWeight.
    const int lo = std::max(0, 2 - (n - nd)), hi = set_.maxDepth + 2 - (n - nd);
    auto prefix = [&](int delta) {  // sum of AddWeight(d) for d < delta
        const int i = std::clamp(delta + addOffset_, 0, int(addPrefix_.size()) - 1);
        return addPrefix_[size_t(i)];
    };
    double sum = prefix(hi - nd + 1) - prefix(lo - nd);
    if (lo == 0 && !allowedAddition(n, nd, a, 0)) sum -= AddWeight(-nd);
    return Float(AddWeight(na - nd) / sum);
}

// T of the move that deleted the vertices the state's path holds at [a, a + na)
// (its `na` new vertices) from a path of n vertices with nd there: Veach 1997,
// Ch. 11 (bidirectional mutation), P_d P_pos P_a times the split-averaged density of those vertices.
Float Mutator::bidirDensity(const State &s, int a, int nd, int na, int n) const {
    const Float pd = deletionProbability(n, nd);
    const int positions = positionCount(n, nd);
    const Float pa = additionProbability(n, nd, a, na);
    if (pd == 0 || positions == 0 || pa == 0 || !allowedPosition(n, nd, a)) return 0;
    const int tmin = a == 0 ? 1 : 0;  // without a kept prefix the camera side samples the lens
    double sum = 0;
    for (int tp = tmin; tp <= na; ++tp) sum += s.e.splitDensity(s.x, ctx_, a + tp, a, a + na);
    return Float(double(pd) / positions * pa * sum / double(na + 1 - tmin));
}

// The choices of one bidirectional mutation of a path of n vertices: nd
// deleted at [a, a + nd), na inserted, tp of them from the camera side and
// sp = na - tp from the light side.
struct Mutator::BidirMove {
    int n = 0, nd = 0, a = -1, na = -1, tp = 0, sp = 0;
    int suffixStart() const { return a + nd; }
    int suffixLen() const { return n - a - nd; }
};

// The light side's new vertices (light order) and the kept suffix (its first
// vertex re-scattered when the light side starts there).
struct Mutator::LightSide {
    std::vector<PathVertex> v, suffix;
    std::vector<BSDF> b;
};

ProposalResult Mutator::bidirectional(const State &xs, Sampler &u, Arena &arena, State *ys, double *ratioOut) const {
    // 1. Deleted count, position, added count, split (Veach 1997, Ch. 11, bidirectional mutation).
    BidirMove m;
    if (!chooseBidirMove(xs.x.size(), u, &m)) return ProposalResult::NotApplicable;
    // 2. Camera side: the kept prefix and tp new vertices.
    if (!buildCameraSide(xs, m, u, arena, ys)) return ProposalResult::Zero;
    // 3. Light side: sp new vertices from the kept suffix (or from a light).
    LightSide l;
    if (!buildLightSide(xs, m, u, arena, &l)) return ProposalResult::Zero;
    // 4. The join of the two sides, y evaluated.
    if (!joinSides(xs, m, l, ys)) return ProposalResult::Zero;
    // 5. The Metropolis-Hastings ratio.
    return bidirRatio(xs, *ys, m, ratioOut);
}

int Mutator::pickDeletion(int n, Float r) const {
    int nd = 0;
    for (nd = 0; nd < n; ++nd) {
        r -= deletionProbability(n, nd);
        if (r < 0) break;
    }
    while (nd > 0 && positionCount(n, nd) == 0) --nd;
    return nd;
}

int Mutator::pickAddition(int n, int nd, int a, Float r) const {
    int last = -1;
    for (int k = 0; k <= set_.maxDepth + 2; ++k) {
        const Float p = additionProbability(n, nd, a, k);
        if (p == 0) continue;
        last = k;
        r -= p;
        if (r < 0) return k;
    }
    return last;
}

bool Mutator::chooseBidirMove(int n, Sampler &u, BidirMove *m) const {
    m->n = n;
    m->nd = pickDeletion(n, u.get1D());
    const int positions = positionCount(n, m->nd);
    if (positions == 0) return false;
    m->a = -1;
    for (int k = Pick(u.get1D(), positions), c = 0; m->a < n;) {
        ++m->a;
        if (allowedPosition(n, m->nd, m->a) && c++ == k) break;
    }
    m->na = pickAddition(n, m->nd, m->a, u.get1D());
    if (m->na < 0) return false;
    const int tmin = m->a == 0 ? 1 : 0;
    m->tp = tmin + Pick(u.get1D(), m->na + 1 - tmin);
    m->sp = m->na - m->tp;
    return true;
}

bool Mutator::traceVertices(PathVertex from, Vec3 dir, int until, bool lastMayEscape, TransportMode mode,
                            Sampler &u, Arena &arena, std::vector<PathVertex> *vs, std::vector<BSDF> *bs) const {
    // New vertices until vs holds `until`, scattering at each but the last.
    while (int(vs->size()) < until) {
        PathVertex v;
        BSDF b;
        const bool last = int(vs->size()) + 1 == until;
        if (!Trace(ctx_, from, dir, arena, last && lastMayEscape, &v, &b)) return false;
        vs->push_back(v);
        bs->push_back(b);
        if (!last && !Scatter(&vs->back(), b, -dir, mode, u, &dir)) return false;
        from = vs->back();
    }
    return true;
}

bool Mutator::buildCameraSide(const State &xs, const BidirMove &m, Sampler &u, Arena &arena, State *ys) const {
    const Path &x = xs.x;
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    y.v.assign(x.v.begin(), x.v.begin() + m.a);
    yb.assign(xs.bsdf.begin(), xs.bsdf.begin() + m.a);
    if (m.tp == 0) return true;
    const bool endsHere = m.suffixLen() == 0 && m.sp == 0;  // the camera side must end on an emitter
    Vec3 dir;
    if (m.a == 0) {
        CameraSample cs;
        cs.pFilm = film_.sample(u.get2D());
        cs.pLens = u.get2D();
        Ray ray;
        if (ctx_.camera->generateRay(cs, &ray) == 0) return false;
        y.v.push_back(LensVertex(ctx_, ray));
        yb.push_back(BSDF());
        dir = Normalize(ray.d);
    } else {
        PathVertex &end = y.v.back();
        if (!Scatter(&end, yb.back(), Dir(end, y.v[y.v.size() - 2]), TransportMode::Radiance, u, &dir)) return false;
    }
    return traceVertices(y.v.back(), dir, m.a + m.tp, endsHere, TransportMode::Radiance, u, arena, &y.v, &yb);
}

bool Mutator::emitLightVertex(const BidirMove &m, Sampler &u, PathVertex *e, Vec3 *dir) const {
    Float pmf;
    const Light *light = ctx_.lightSampler->sample(u.get1D(), &pmf);
    const Point2 u1 = u.get2D(), u2 = u.get2D();
    if (!light || pmf == 0) return false;
    // An emitter at infinity alone would be joined along a direction its
    // sampling did not choose (ValidSplit excludes that technique).
    if (m.sp == 1 && (light->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION))) return false;
    LightLeSample les;
    if (!light->sampleLe(u1, u2, &les) || les.pdfPos == 0 || les.pdfDir == 0 || les.L.isBlack()) return false;
    e->type = VertexType::Light;
    e->light = light;
    if (IsDeltaLight(light->flags)) e->flags |= VERTEX_DELTA_LIGHT;
    // Infinite and distant lights: a vertex on the scene's bounding disk (bidir.cpp).
    if (light->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION)) e->flags |= VERTEX_INFINITE;
    e->p = les.p;
    e->ng = e->ns = les.nLight;
    *dir = Normalize(les.ray.d);
    return true;
}

bool Mutator::buildLightSide(const State &xs, const BidirMove &m, Sampler &u, Arena &arena, LightSide *l) const {
    const int suffixStart = m.suffixStart();
    l->suffix.assign(xs.x.v.begin() + suffixStart, xs.x.v.end());
    if (m.sp == 0) return true;
    Vec3 dir;
    if (m.suffixLen() == 0) {
        PathVertex e;
        if (!emitLightVertex(m, u, &e, &dir)) return false;
        l->v.push_back(e);
        l->b.push_back(BSDF());
    } else {
        std::vector<PathVertex> &suffix = l->suffix;
        if (!Scatter(&suffix[0], xs.bsdf[size_t(suffixStart)], Dir(suffix[0], suffix[1]), TransportMode::Importance,
                     u, &dir))
            return false;
    }
    const PathVertex &from = l->v.empty() ? l->suffix[0] : l->v.back();
    return traceVertices(from, dir, m.sp, false, TransportMode::Importance, u, arena, &l->v, &l->b);
}

bool Mutator::joinSides(const State &xs, const BidirMove &m, const LightSide &l, State *ys) const {
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    for (int k = m.sp - 1; k >= 0; --k) {
        y.v.push_back(l.v[size_t(k)]);
        yb.push_back(l.b[size_t(k)]);
    }
    y.v.insert(y.v.end(), l.suffix.begin(), l.suffix.end());
    yb.insert(yb.end(), xs.bsdf.begin() + m.suffixStart(), xs.bsdf.end());
    const int np = y.size(), t = m.a + m.tp;
    if (np < 2 || np > set_.maxDepth + 2) return false;
    // The join: a shadow-tested edge between non-specular ends (or the camera
    // side's hit on an emitter).
    y.v.back().flags &= uint8_t(~VERTEX_DELTA);
    if (t < np) {
        y.v[size_t(t - 1)].flags &= uint8_t(~VERTEX_DELTA);
        y.v[size_t(t)].flags &= uint8_t(~VERTEX_DELTA);
        if (y.v[size_t(t - 1)].isInfiniteLight() || !Visible(ctx_, y.v[size_t(t - 1)], y.v[size_t(t)])) return false;
    }
    for (int i = 1; i < np; ++i) y.v[size_t(i)].wo = PackedVec3(Dir(y.v[size_t(i)], y.v[size_t(i - 1)]));
    if (!Evaluate(ctx_, film_, y, yb.data(), &ys->e)) return false;
    // Only techniques T counts may make y: a path from a split that is not one
    // (the emitter joined straight to the lens, bdpt's (1, 1)) would be
    // proposed with a density T leaves out, over-weighting such paths.
    return ValidSplit(ctx_, y, ys->e, t);
}

ProposalResult Mutator::bidirRatio(const State &xs, const State &ys, const BidirMove &m, double *ratioOut) const {
    // a = min(1, I(y) T(y -> x) / (I(x) T(x -> y))) (Metropolis-Hastings; Veach 1997, Ch. 11).
    const Float tFwd = bidirDensity(ys, m.a, m.nd, m.na, m.n);
    const Float tRev = bidirDensity(xs, m.a, m.na, m.nd, ys.x.size());
    if (!(tFwd > 0) || !(tRev > 0)) return ProposalResult::Zero;
    const double ratio = double(ys.e.I) * tRev / (double(xs.e.I) * tFwd);
    if (!std::isfinite(ratio) || !(ratio > 0)) return ProposalResult::Zero;
    *ratioOut = ratio;
    return ProposalResult::Proposed;
}

// ---------------------------------------------------------------- perturbations
bool LensPattern(const Path &x, int *cOut, int *mOut) {
    // c: the first non-specular vertex after the lens; m: the first
    // non-specular vertex from c on whose successor is connectible (or the emitter).
    const int n = x.size();
    int c = 1;
    while (c < n - 1 && x.v[size_t(c)].delta()) ++c;
    auto connectsAfter = [&](int k) { return k == n - 1 || !x.v[size_t(k + 1)].delta(); };
    int m = c;
    while (!connectsAfter(m)) {
        ++m;
        while (m < n - 1 && x.v[size_t(m)].delta()) ++m;
    }
    *cOut = c;
    *mOut = m;
    return m > c;
}

bool CausticPattern(const Path &x, int *cOut) {
    const int n = x.size();
    if (n < 4 || x.v[1].delta() || !x.v[2].delta()) return false;
    int c = 2;
    while (c < n - 1 && x.v[size_t(c)].delta()) ++c;
    *cOut = c;
    return !x.v[size_t(c)].isInfiniteLight();
}

bool Mutator::applies(MutationType type, const Path &x) const {
    int c, m;
    switch (type) {
    case MutationType::Bidirectional: return true;  // a full regeneration is always possible
    case MutationType::Lens:
    case MutationType::MultiChain: {
        const bool multi = LensPattern(x, &c, &m);
        // The perturbed x_m joins x_{m+1}: not a vertex at infinity (a direction).
        if (m + 1 < x.size() && x.v[size_t(m + 1)].isInfiniteLight()) return false;
        return multi == (type == MutationType::MultiChain);
    }
    case MutationType::Caustic: return CausticPattern(x, &c);
    case MutationType::Manifold: {
        int b, geom;
        return ManifoldPattern(x, set_.mscene, &b, &c, &geom);
    }
    }
    return false;
}

Float Mutator::selectionProbability(MutationType type, const Path &x, const Float *weights) const {
    Float sum = 0;
    for (int k = 0; k < kMutationTypes; ++k)
        if (applies(MutationType(k), x)) sum += weights[k];
    return applies(type, x) && sum > 0 ? weights[int(type)] / sum : 0;
}

bool Mutator::perturbedRay(const State &xs, Sampler &u, Ray *ray) const {
    const Point2 pFilm = PerturbFilm(xs.e.pRaster, set_.lensR1, set_.lensR2, u);
    const Point2 uLens = u.get2D();
    if (!film_.contains(pFilm)) return false;
    CameraSample cs;
    cs.pFilm = pFilm;
    cs.pLens = uLens;  // uniform lens points: a constant density, the same in both directions
    return ctx_.camera->generateRay(cs, ray) != 0;
}

bool Mutator::traceEyeChain(const State &xs, int b, const Ray &ray, Arena &arena, State *ys, SurfaceInteraction *siB,
                            double *hvJacobian) const {
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    y.v.assign(1, LensVertex(ctx_, ray));
    yb.assign(1, BSDF());
    Vec3 dir = Normalize(ray.d);
    for (int j = 1; j <= b; ++j) {
        PathVertex v;
        BSDF bsdf;
        if (!Trace(ctx_, y.v.back(), dir, arena, j == xs.x.size() - 1, &v, &bsdf, j == b ? siB : nullptr))
            return false;
        if (j < b) {
            const Path &x = xs.x;
            if (x.v[size_t(j)].delta()) {
                if (!FollowSpecular(x, j, &v, bsdf, -dir, TransportMode::Radiance, &dir)) return false;
            } else {
                // A near-specular vertex of G-MLT's shift (Fig. 5a): x's half vector, in the
                // local frames of both vertices (shift.h). Both paths' directions come
                // from their vertices (not the traced ray's, whose origin was offset), as
                // the shift back computes them.
                HalfVectorShift hv;
                const PathVertex &xj = x.v[size_t(j)];
                if (!bsdf || !ShiftHalfVectorWorld(xs.bsdf[size_t(j)], Dir(xj, x.v[size_t(j - 1)]),
                                                   Dir(xj, x.v[size_t(j + 1)]), bsdf, Dir(v, y.v.back()), &hv))
                    return false;
                dir = hv.wi;
                if (hvJacobian) *hvJacobian *= hv.jacobian;
            }
        }
        y.v.push_back(v);
        yb.push_back(bsdf);
    }
    return true;
}

ProposalResult Mutator::lens(const State &xs, bool multiChain, Sampler &u, Arena &arena, State *ys,
                             double *ratioOut) const {
    const Path &x = xs.x;
    const int n = x.size();
    int c, m;
    if (LensPattern(x, &c, &m) != multiChain) return ProposalResult::NotApplicable;
    Ray ray;
    if (!perturbedRay(xs, u, &ray) || !traceEyeChain(xs, c, ray, arena, ys, nullptr)) return ProposalResult::Zero;
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    for (int j = c + 1; j <= m; ++j) {
        // Multi-chain: at a non-specular vertex a new direction near the old
        // path's outgoing one, at a specular one the old path's lobe.
        PathVertex &prev = y.v.back();
        Vec3 dir;
        if (!x.v[size_t(j - 1)].delta()) {
            dir = PerturbDirection(Dir(x.v[size_t(j - 1)], x.v[size_t(j)]), set_.theta1, set_.theta2, u);
        } else if (!FollowSpecular(x, j - 1, &prev, yb.back(), Dir(prev, y.v[y.v.size() - 2]),
                                   TransportMode::Radiance, &dir)) {
            return ProposalResult::Zero;
        }
        PathVertex v;
        BSDF b;
        if (!Trace(ctx_, prev, dir, arena, j == n - 1, &v, &b)) return ProposalResult::Zero;
        y.v.push_back(v);
        yb.push_back(b);
    }
    if (m < n - 1 && !Visible(ctx_, y.v.back(), x.v[size_t(m + 1)])) return ProposalResult::Zero;
    y.v.insert(y.v.end(), x.v.begin() + m + 1, x.v.end());
    yb.insert(yb.end(), xs.bsdf.begin() + m + 1, xs.bsdf.end());
    for (int i = 1; i < n; ++i) y.v[size_t(i)].wo = PackedVec3(Dir(y.v[size_t(i)], y.v[size_t(i - 1)]));
    if (!Evaluate(ctx_, film_, y, yb.data(), &ys->e)) return ProposalResult::Zero;
    // Veach 1997, Ch. 11 (lens and multi-chain perturbations): with
    // symmetric kernels T(x -> y) / T(y -> x) = D(y) / D(x), D the density of
    // x_1 .. x_m per unit film area and per unit solid angle of each perturbed
    // direction: the camera's p_E(x_1), then p_E / P_lobe through a specular
    // vertex (its lobe is forced) or the solid angle -> area conversion.
    auto D = [&](const State &s) {
        double d = s.e.pE[1];
        for (int j = 2; j <= m; ++j)
            d *= s.x.v[size_t(j - 1)].delta() ? s.e.pE[size_t(j)] / s.e.lobeE[size_t(j - 1)]
                                              : ConvertDensity(1, s.x.v[size_t(j - 1)], s.x.v[size_t(j)]);
        return d;
    };
    const double ratio = (double(ys->e.I) / D(*ys)) / (double(xs.e.I) / D(xs));
    if (!std::isfinite(ratio) || !(ratio > 0)) return ProposalResult::Zero;
    *ratioOut = ratio;
    return ProposalResult::Proposed;
}

Mutator::ShiftStatus Mutator::shift(const State &xs, Point2 pFilm, Arena &arena, State *ys, double *jacobian,
                                    MutationStats *stats) const {
    const Path &x = xs.x;
    const int n = x.size();
    if (!film_.contains(pFilm)) return ShiftStatus::OffFilm;
    // x_0 and the lens point held, the film point moved (G-MLT Sec. 5.1).
    Ray ray;
    if (!ctx_.camera->rayThrough(x.v[0].p, pFilm, &ray)) return ShiftStatus::Mismatch;
    // Specular for the shift: Dirac and near-specular vertices (Fig. 5a).
    thread_local std::vector<ShiftClass> cls;
    cls.resize(size_t(n));
    for (int j = 0; j < n; ++j) cls[size_t(j)] = ShiftClassOf(x.v[size_t(j)], xs.bsdf[size_t(j)], set_.shiftThreshold);
    auto specular = [&](int j) { return cls[size_t(j)] != ShiftClass::Rough; };
    // The offset must have x's classes where it moved (x_1 .. x_last), or the
    // shift back would take another plan: not a bijection (Sec. 4.2.2).
    auto sameClasses = [&](int last) {
        for (int j = 1; j <= last; ++j)
            if (ShiftClassOf(ys->x.v[size_t(j)], ys->bsdf[size_t(j)], set_.shiftThreshold) != cls[size_t(j)])
                return false;
        return true;
    };
    auto shifted = [&](int last) {
        if (!std::isfinite(*jacobian) || !(*jacobian > 0)) return ShiftStatus::Blocked;
        const auto end = cls.begin() + last + 1;
        if (stats && std::find(cls.begin() + 1, end, ShiftClass::NearSpecular) != end) ++stats->nearSpecularShifts;
        return ShiftStatus::Shifted;
    };
    int b = 1;
    while (b < n - 1 && specular(b)) ++b;
    if (b < n - 1 && specular(b + 1)) {
        // A second chain S_m = x_{b+1} .. x_{c-1}: the manifold perturbation's
        // move for this film point; its Jacobian is the walk's (Eqs. 13-15).
        int bm, c, endGeom;
        if (!ManifoldPattern(x, set_.mscene, cls.data(), &bm, &c, &endGeom)) return ShiftStatus::Unsupported;
        MutationStats local;
        const ProposalResult r = manifoldMove(xs, b, c, endGeom, ray, arena, ys, jacobian, &local, true);
        if (stats) {
            stats->walks += local.walks;
            stats->walkFailures += local.walkFailures;
        }
        if (r != ProposalResult::Proposed) return local.walkFailures > 0 ? ShiftStatus::WalkFailed : ShiftStatus::Blocked;
        if (!sameClasses(c - 1)) return ShiftStatus::Mismatch;
        return shifted(c - 1);
    }
    // S_e then x_b' joined to the unchanged x_{b+1} (or x_b' the emitter).
    double hvJacobian = 1;
    if (!traceEyeChain(xs, b, ray, arena, ys, nullptr, &hvJacobian)) return ShiftStatus::Mismatch;
    if (!sameClasses(b)) return ShiftStatus::Mismatch;
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    if (b < n - 1) {
        if (y.v.back().type != VertexType::Surface) return ShiftStatus::Mismatch;
        const PathVertex &next = x.v[size_t(b + 1)];
        if (next.isInfiniteLight()) {
            // An emitter at infinity is a direction: the offset keeps it (the
            // environment shift of G-BDPT, shift.h) if it escapes; the direction's
            // measure is unchanged, so |T'| is still D_b(x) / D_b(y).
            const Vec3 w = Dir(x.v[size_t(b)], next);
            SurfaceInteraction hit;
            if (TraceSurface(*ctx_.scene, AsInteraction(y.v.back()).spawnRay(w), &hit)) return ShiftStatus::Blocked;
            PathVertex e = next;
            e.p = y.v.back().p + w * (next.p - x.v[size_t(b)].p).length();
            y.v.push_back(e);
            yb.push_back(xs.bsdf[size_t(b + 1)]);
        } else {
            if (!Visible(ctx_, y.v.back(), next)) return ShiftStatus::Blocked;
            y.v.insert(y.v.end(), x.v.begin() + b + 1, x.v.end());
            yb.insert(yb.end(), xs.bsdf.begin() + b + 1, xs.bsdf.end());
        }
    }
    for (int i = 1; i < n; ++i) y.v[size_t(i)].wo = PackedVec3(Dir(y.v[size_t(i)], y.v[size_t(i - 1)]));
    // Only x_1 .. x_b moved: F and the eye densities of the changed prefix (the rest is x's).
    if (!EvaluateChangedPrefix(ctx_, film_, y, yb.data(), xs.e, b, &ys->e)) return ShiftStatus::Blocked;
    // |d mu(y) / d mu(x)| = D_b(x) / D_b(y): x_1 .. x_b as functions of the
    // film point (whose shift has unit Jacobian) and of the copied half vectors
    // of near-specular vertices, x_{b+1} on held; the delta-free form of G-MLT
    // Eqs. 14-15 with the eye chain's specular vertices. D_b per unit half
    // vector is EyeDensity times |d h / d omega| at each copy: hvJacobian.
    *jacobian = EyeDensity(xs, b) / EyeDensity(*ys, b) * hvJacobian;
    return shifted(b);
}

ProposalResult Mutator::caustic(const State &xs, Sampler &u, Arena &arena, State *ys, double *ratioOut) const {
    const Path &x = xs.x;
    const int n = x.size();
    int c;
    if (!CausticPattern(x, &c)) return ProposalResult::NotApplicable;
    const PathVertex &xc = x.v[size_t(c)];
    Vec3 dir = PerturbDirection(Dir(xc, x.v[size_t(c - 1)]), set_.theta1, set_.theta2, u);
    // Trace from x_c back through the chain (light order), then join x_1' to the lens.
    std::vector<PathVertex> nv;
    std::vector<BSDF> nb;
    for (int j = c - 1; j >= 1; --j) {
        PathVertex v;
        BSDF b;
        if (!Trace(ctx_, nv.empty() ? xc : nv.back(), dir, arena, false, &v, &b)) return ProposalResult::Zero;
        if (j >= 2 && !FollowSpecular(x, j, &v, b, -dir, TransportMode::Importance, &dir))
            return ProposalResult::Zero;
        nv.push_back(v);
        nb.push_back(b);
    }
    if (!Visible(ctx_, nv.back(), x.v[0])) return ProposalResult::Zero;
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    y.v.assign(1, x.v[0]);
    yb.assign(1, BSDF());
    for (int k = int(nv.size()) - 1; k >= 0; --k) {
        y.v.push_back(nv[size_t(k)]);
        yb.push_back(nb[size_t(k)]);
    }
    y.v.insert(y.v.end(), x.v.begin() + c, x.v.end());
    yb.insert(yb.end(), xs.bsdf.begin() + c, xs.bsdf.end());
    for (int i = 1; i < n; ++i) y.v[size_t(i)].wo = PackedVec3(Dir(y.v[size_t(i)], y.v[size_t(i - 1)]));
    if (!Evaluate(ctx_, film_, y, yb.data(), &ys->e)) return ProposalResult::Zero;
    // Veach 1997, Ch. 11 (caustic perturbation): D per unit solid angle of
    // the perturbed direction at x_c: the conversion to area at x_{c-1}, then
    // p_L / P_lobe per specular vertex traced back to x_1.
    auto D = [&](const State &s) {
        double d = ConvertDensity(1, s.x.v[size_t(c)], s.x.v[size_t(c - 1)]);
        for (int j = 1; j <= c - 2; ++j) d *= s.e.pL[size_t(j)] / s.e.lobeL[size_t(j + 1)];
        return d;
    };
    const double ratio = (double(ys->e.I) / D(*ys)) / (double(xs.e.I) / D(xs));
    if (!std::isfinite(ratio) || !(ratio > 0)) return ProposalResult::Zero;
    *ratioOut = ratio;
    return ProposalResult::Proposed;
}

}  // namespace gradus::pmlt
