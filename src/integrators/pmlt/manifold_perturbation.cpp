// The manifold perturbation of pmlt (Jakob and Marschner 2012, Sec. 5; the
// "manifold perturbation" of gradient-domain-mlt.md Sec. 5.1-5.2).
//
// Path pattern E S* D S+ (D | L): the eye chain x_1 .. x_b (S* then the
// non-specular x_b), the second chain x_{b+1} .. x_{c-1} (specular), x_c
// non-specular and kept with everything after it. The film position moves by
// the lens perturbation's symmetric kernel, the eye chain is re-traced with
// the old lobes to x_b', and a manifold walk (integrators/manifold) moves the
// second chain, its half-vectors held, until it joins x_b' to x_c. Walks that
// fail or do not walk back to x (the walk may find another solution) are
// rejected, so the move is a bijection for each film offset.
//
// Acceptance. In the delta-free measure of path.h the specular vertices of the
// second chain are fixed by their Dirac constraints given x_b and x_c;
// integrating them out leaves the factor K = (d omega_b / dA_c) / P_trace,
// where d omega_b / dA_c is the chain's solid angle at x_b per unit area at x_c
// (JM12's generalised geometry term over |cos_b|; ChainSolidAnglePerArea) and
// P_trace the delta-free density of x_{b+1} .. x_c traced from a unit
// solid-angle density at x_b (the same factors the lens perturbation uses:
// one solid angle -> area conversion, then p_E / P_lobe per specular vertex).
// With D_b the density of x_1 .. x_b per film area (as for the lens
// perturbation) and the symmetric film kernel,
//   a = min(1, [I(y) K(y) / D_b(y)] / [I(x) K(x) / D_b(x)]),
// the Metropolis-Hastings ratio of a deterministic move with a symmetric
// random parameter (G-MLT Eqs. 12-15 give the same Jacobian in the measure
// with the specular vertices eliminated).
#include <algorithm>
#include <cmath>

#include "integrators/gradient/subpath_shift.h"
#include "integrators/pmlt/mutations.h"

namespace gradus::pmlt {

namespace {

// Density of x_j traced from x_{j-1}: through a Dirac vertex p_E / P_lobe
// (the delta-free conversion of path.h), through a non-Dirac one (G-MLT's
// near-specular vertices, whose half vector is the variable) a unit
// solid-angle density at x_{j-1}.
double TracedVertexDensity(const State &s, int j) {
    const PathVertex &prev = s.x.v[size_t(j - 1)];
    return prev.delta() ? s.e.pE[size_t(j)] / s.e.lobeE[size_t(j - 1)] : ConvertDensity(1, prev, s.x.v[size_t(j)]);
}

}  // namespace

double TraceDensity(const State &s, int b, int c) {
    double d = ConvertDensity(1, s.x.v[size_t(b)], s.x.v[size_t(b + 1)]);
    for (int j = b + 2; j <= c; ++j) d *= TracedVertexDensity(s, j);
    return d;
}

double EyeDensity(const State &s, int b) {
    double d = s.e.pE[1];
    for (int j = 2; j <= b; ++j) d *= TracedVertexDensity(s, j);
    return d;
}

namespace {

template <class IsSpecular>
bool PatternOf(const Path &x, const EmbreeManifoldScene *mscene, IsSpecular specular, int *bOut, int *cOut,
               int *endGeom) {
    const int n = x.size();
    if (!mscene) return false;
    int b = 1;
    while (b < n - 1 && specular(b)) ++b;
    if (b >= n - 1 || !specular(b + 1)) return false;
    int c = b + 1;
    while (c < n - 1 && specular(c)) ++c;
    const PathVertex &xc = x.v[size_t(c)];
    *endGeom = xc.type == VertexType::Surface ? xc.geomId
               : xc.type == VertexType::Light  ? mscene->geomOfLight(xc.light)
                                               : -1;
    *bOut = b;
    *cOut = c;
    // Point and infinite emitters have no surface for the chain to end on.
    return !xc.isInfiniteLight() && *endGeom >= 0 && c - b + 1 <= kMaxManifoldVertices;
}

}  // namespace

bool ManifoldPattern(const Path &x, const EmbreeManifoldScene *mscene, int *bOut, int *cOut, int *endGeom) {
    return PatternOf(x, mscene, [&](int j) { return x.v[size_t(j)].delta(); }, bOut, cOut, endGeom);
}

bool ManifoldPattern(const Path &x, const EmbreeManifoldScene *mscene, const ShiftClass *cls, int *bOut, int *cOut,
                     int *endGeom) {
    return PatternOf(x, mscene, [&](int j) { return cls[j] != ShiftClass::Rough; }, bOut, cOut, endGeom);
}

ProposalResult Mutator::manifold(const State &xs, Sampler &u, Arena &arena, State *ys, double *ratioOut,
                                 MutationStats *stats) const {
    int b, c, endGeom;
    if (!ManifoldPattern(xs.x, set_.mscene, &b, &c, &endGeom)) return ProposalResult::NotApplicable;
    Ray ray;
    if (!perturbedRay(xs, u, &ray)) return ProposalResult::Zero;
    double jacobian = 0;
    const ProposalResult r = manifoldMove(xs, b, c, endGeom, ray, arena, ys, &jacobian, stats);
    if (r != ProposalResult::Proposed) return r;
    // a = [I(y) K(y) / D_b(y)] / [I(x) K(x) / D_b(x)] (symmetric film kernel).
    const double ratio = double(ys->e.I) / double(xs.e.I) * jacobian;
    if (!std::isfinite(ratio) || !(ratio > 0)) return ProposalResult::Zero;
    *ratioOut = ratio;
    return ProposalResult::Proposed;
}

ProposalResult Mutator::manifoldMove(const State &xs, int b, int c, int endGeom, const Ray &ray, Arena &arena,
                                     State *ys, double *jacobian, MutationStats *stats, bool prefixOnly) const {
    const Path &x = xs.x;
    const int n = x.size();
    const PathVertex &xc = x.v[size_t(c)];

    // The eye chain along the ray first (a move whose eye chain fails costs
    // no chain set-up and no walk).
    SurfaceInteraction siYb;
    double hvJacobian = 1;
    if (!traceEyeChain(xs, b, ray, arena, ys, &siYb, &hvJacobian)) return ProposalResult::Zero;
    if (ys->x.v.back().type != VertexType::Surface) return ProposalResult::Zero;

    // The base chain x_b .. x_c.
    ManifoldSettings sc;
    sc.mscene = set_.mscene;
    sc.threshold = set_.shiftThreshold;
    const Scene &scene = *ctx_.scene;
    const int k = c - b - 1;
    ChainInterior in;
    for (int j = 0; j < k; ++j) {
        const int i = b + 1 + j;
        const PathVertex &v = x.v[size_t(i)];
        if (!VertexInteraction(scene, v, x.v[size_t(i - 1)].p, &in.si[j])) return ProposalResult::Zero;
        in.bsdf[j] = &xs.bsdf[size_t(i)];
        in.wo[j] = Dir(v, x.v[size_t(i - 1)]);
        in.wi[j] = Dir(v, x.v[size_t(i + 1)]);
        in.transmit[j] = Transmits(in.wo[j], in.wi[j], Vec3(xs.bsdf[size_t(i)].ns()));
        in.specular[j] = v.delta();  // else near-specular (G-MLT's shift): its half vector is kept
        in.geomId[j] = v.geomId;
    }
    SurfaceInteraction siXb;
    if (!VertexInteraction(scene, x.v[size_t(b)], x.v[size_t(b - 1)].p, &siXb)) return ProposalResult::Zero;
    ManifoldChain base;
    if (!BuildChain(sc, set_.mscene->fromInteraction(siXb), in, k, EndpointSP(xc.p, Vec3(xc.ng), endGeom), &base))
        return ProposalResult::Zero;

    // The walk of the second chain to x_c.
    ManifoldWalkResult walk;
    WalkedInterior walked;
    const ChainShiftFailure failure = ShiftChain(sc, scene, base, set_.mscene->fromInteraction(siYb), base.back().sp,
                                                 in, TransportMode::Radiance, arena, &walk, &walked);
    if (stats) {
        stats->walks += 1;
        stats->walkFailures += walk.ok() ? 0 : 1;
    }
    if (failure != ChainShiftFailure::None) return ProposalResult::Zero;  // the walk failed or is not reversible (stats)
    const ManifoldChain &offset = walk.chain;
    // Jacobian of the second chain in the camera-side direction measure (Eq. 5 of G-BDPT).
    const Float ax = ChainDirectionsPerArea(base), ay = ChainDirectionsPerArea(offset);
    if (!(ax > 0) || !(ay > 0)) return ProposalResult::Zero;
    const Float J = ay / ax;
    Path &y = ys->x;
    std::vector<BSDF> &yb = ys->bsdf;
    for (int j = 0; j < k; ++j) {
        PathVertex v;
        MakeSurfaceVertex(ctx_, walked.si[j], walked.bsdf[j], &v);
        if (in.specular[j]) v.flags |= VERTEX_DELTA;
        y.v.push_back(v);
        yb.push_back(walked.bsdf[j]);
    }
    y.v.insert(y.v.end(), x.v.begin() + c, x.v.end());
    yb.insert(yb.end(), xs.bsdf.begin() + c, xs.bsdf.end());
    for (int i = 1; i < n; ++i) y.v[size_t(i)].wo = PackedVec3(Dir(y.v[size_t(i)], y.v[size_t(i - 1)]));
    if (!(prefixOnly ? EvaluateChangedPrefix(ctx_, film_, y, yb.data(), xs.e, c - 1, &ys->e)
                     : Evaluate(ctx_, film_, y, yb.data(), &ys->e)))
        return ProposalResult::Zero;
    // K(y) / D_b(y) over K(x) / D_b(x) with K = Phi / P_trace: Phi the chain's
    // sampled directions (at x_b and at each near-specular vertex g) per unit
    // area at x_c and per unit of the kept half vectors O_g
    // (ChainDirectionsPerArea; J = Phi(y) / Phi(x) from the walk, G-MLT Eq. 14's
    // chain factor), P_trace their density traced from x_b (TraceDensity).
    // D_b per unit of the eye chain's copied half vectors: EyeDensity times
    // |d h / d omega| at each copy, whose ratio is hvJacobian (Eq. 14's eye factor).
    *jacobian = J * (TraceDensity(xs, b, c) / TraceDensity(*ys, b, c)) * (EyeDensity(xs, b) / EyeDensity(*ys, b)) *
                hvJacobian;
    return ProposalResult::Proposed;
}

}  // namespace gradus::pmlt
