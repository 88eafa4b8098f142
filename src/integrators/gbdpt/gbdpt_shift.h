// The G-BDPT shift mapping (gradient-domain-bdpt.md Sec. 3.1) applied to
// camera subpaths (cases (i) and (ii) of Sec. 3.2, Eqs. 6 and 7) and to
// light-tracing paths (case (iii)), on the shared path vertices of common/.
//
// Vertex classes: a surface vertex is "diffuse" (Rough) when the lowest
// roughness of its BSDF is >= shiftthreshold, otherwise "specular"; camera and
// light vertices are diffuse. a = 0 (the eye), b and c are the next two
// diffuse vertices along the path from the eye.
//
// Manifold shift ("manifold", Lehtinen et al. 2013 / Sec. 3.1): the image-plane
// point moves by one pixel, the first half-vector chain (a, b) is re-traced
// with the base's half vectors (ideal specular vertices reflect/refract as the
// base did), and the offset's b reconnects to the base's c through the second
// chain by a manifold walk. Half-vector shift ("halfvector", Kettunen et al.
// 2015): half vectors are copied at every vertex until the base has two
// consecutive diffuse vertices k-1, k, and the offset reconnects to x_k.
//
// Measure. Throughputs are kept in the camera-side direction parameterisation
// of the base (image-plane point, then the solid angle of every non-delta
// sampled direction; ideal specular directions are not variables). In it
//   f(y)|T'|/p(x) = prod_i f_y,i |cos_y,i| J_i / p_x,i                 (Eq. 5)
// with J_i = |d omega_y,i / d omega_x,i|: 1 for the image-plane shift and at
// ideal specular vertices, the half-vector Jacobian at copied glossy
// vertices, the reconnection Jacobian for an empty second chain, and for a
// walked chain of ideal specular vertices
//   J_b = (G(y_b<->..<->x_c)/|cos_y,b|) / (G(x_b<->..<->x_c)/|cos_x,b|),
// the ratio of generalised geometry terms (JM12) per solid angle at b. This
// equals |dy/dx| of Eq. 5 (the reparameterisation Jacobians of LKL13 in the
// reduced measure), and it is checked against finite differences in
// tests/gbdpt. The prefix product up to b is Eq. 7, up to c Eq. 6.
//
// Gradient MIS ratio rho = |T'| p_st(y) / p_st(x) (Eq. 8): the product over
// the shifted sampled directions of J_i p_y,i / p_x,i (discrete lobe
// probabilities at ideal specular vertices), so the weight of Eq. 8 is
//   w_ij,st(x) = 1 / (1 / w_st(x) + rho / w_st(y))
// with w_st the balance-heuristic BDPT weights of base and offset. The
// weights of all strategies of one path sum to one only if every strategy uses
// the same |T'| in the measure of the MIS densities of common/ (area measure,
// Dirac factors remapped to 1): light-tracing paths take the camera side's
// effective |T'| (ShiftLightTracingPath), and a path either uses Eq. 8 for all
// its strategies or falls back for all (failures depend on the path only).
//
// Limitations: second chains must consist of ideal specular vertices (a glossy
// vertex below the threshold there makes the path fall back); glossy
// refraction is not half-vector copied; the half-vector shift falls back for
// paths with a specular vertex between b and its reconnection vertex (their
// light-tracing strategy is not shifted across specular chains); infinite
// lights are not shifted (fallback).
#pragma once
#include <cstdint>

#include "integrators/common/bidir.h"
#include "integrators/manifold/manifold_scene.h"
#include "integrators/gradient/shift.h"

namespace gradus {

struct GBDPTShiftContext {
    const BidirContext *bidir = nullptr;
    const EmbreeManifoldScene *mscene = nullptr;
    Float threshold = 0.001;
    bool manifold = true;        // manifold walk (else half-vector shift)
    bool trySpecular = true;     // scene has specular or near-specular surfaces
    ManifoldWalkOptions walk;
};

// Counters of one sample (flushed into the integrator's totals).
struct GBDPTLocalStats {
    LocalShiftStats shift;
    uint64_t caseAttempts[3] = {}, caseSuccesses[3] = {};  // (i), (ii), (iii) gradient samples
    uint64_t walks = 0, walkFailures = 0;
    uint64_t walkStatus[size_t(ManifoldStatus::Count)] = {};
    uint64_t unsupportedChains = 0;  // glossy vertex in a second chain: fallback
};

// A subpath with the per-vertex data the shift needs.
struct ShiftSubpath {
    PathVertex *v = nullptr;
    BSDF *b = nullptr;
    uint8_t *deltaSample = nullptr;  // the direction sampled at v[i] came from a Dirac lobe
    int n = 0;
    SubpathView view() const { return {v, b, n}; }
};

// Sets deltaSample and marks specular (class != Rough) surface vertices with
// VERTEX_DELTA so that MIS and connections leave them out (Sec. 3.2).
void PrepareSubpath(const GBDPTShiftContext &ctx, ShiftSubpath *p);
// Rough (diffuse) for shift purposes.
bool IsDiffuseVertex(const GBDPTShiftContext &ctx, const PathVertex &v, const BSDF *b);

// Offset camera subpath of one neighbour.
struct CameraShift {
    ShiftSubpath y;       // offset vertices (arena storage, n = base n)
    int validUpTo = -1;   // connections at camera vertex k <= validUpTo may use y
    int r = -1;           // reconnection vertex: y.v[k] = x.v[k] for k >= r (-1: none)
    Float *rho = nullptr; // rho[k]: gradient-MIS ratio for paths ending their camera part at k
};

// Shifts the camera subpath `x` (generated from camera sample cs) to the
// neighbour at pixel offset `off`. Vertices before a failure stay valid.
void ShiftCameraSubpath(const GBDPTShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                        Arena &arena, CameraShift *out, GBDPTLocalStats *st);

// s = 1 (next-event) connection with a given light point, for base and offset
// paths alike (the offset reconnects to the base's light point).
struct LightPoint {
    PathVertex v;          // light vertex (pdfFwd = PdfLightOrigin)
    const Light *light = nullptr;
    Float pmf = 0, pdf = 0;  // light choice and solid-angle pdf at the base vertex
    Spectrum Li;             // radiance/intensity arriving at the base vertex
    Point3 basePoint;        // the base vertex the pdf refers to
    Point2 u;                // light-sampling numbers (delta lights are re-evaluated)
    bool delta = false, infinite = false;
};
bool SampleLightPoint(const GBDPTShiftContext &ctx, const PathVertex &pt, Float uSel, Point2 u, LightPoint *lp);
// f / p_base (unweighted) and the BDPT weight of strategy (1, t) on `cam`.
bool ConnectLightPoint(const GBDPTShiftContext &ctx, const LightPoint &lp, SubpathView cam, int t,
                       ConnectResult *res);

// Shift of a light-tracing path (strategy (s, 1), case (iii)): light vertices
// 0..s-1 of `light`, lens vertex `lens`, raster position pRaster, base
// unweighted value fx. Returns false when the shift fails or the offset is
// black/blocked. fy = f(y)|T'|/p(x), wy = BDPT weight of the offset, rho as above.
bool ShiftLightTracingPath(const GBDPTShiftContext &ctx, const ShiftSubpath &light, int s, const PathVertex &lens,
                           Point2 pRaster, const Spectrum &fx, Point2i off, Arena &arena, Spectrum *fy, Float *wy,
                           Float *rho, GBDPTLocalStats *st);

// Building blocks exposed for the finite-difference tests.
// Solid angle at a chain's start per unit area at its end, G / |cos_0| (JM12);
// the ratio offset/base is the Jacobian J_b of the second chain.
Float ChainSolidAnglePerArea(const ManifoldChain &c);
// dA_b/ds of a pinhole camera at `lens` with axis n0 (cos^4 / G of
// ShiftJacobianFactor for an empty eye chain, up to the focal constant).
Float EyeAreaFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb, const Vec3 &ngb);

// p_{s+t-1,1}(x) / p_{s,t}(x): the light-tracing strategy's density relative
// to strategy (s, t) of the same full path, in the MIS densities of common/
// (the product of MISWeight's ratios down to one camera vertex); 0 when the
// path has no light-tracing strategy (x_1 specular or not connectible).
// `sampled` is the light vertex of s = 1. Lets "lighttracing false" leave the
// t = 1 strategies out of all weights: w' = w / (1 - ratio w).
Float LightTracingRatio(const GBDPTShiftContext &ctx, SubpathView light, SubpathView cam, int s, int t,
                        const PathVertex *sampled);

// Combined gradient/BDPT MIS (Eq. 8) and the simpler variant (Eq. 9).
inline Float CombinedWeight(Float wx, Float wy, Float rho) {
    if (!(wx > 0)) return 0;
    if (!(wy > 0) || !(rho > 0) || !std::isfinite(rho)) return wx;
    return 1 / (1 / wx + rho / wy);
}

}  // namespace gradus
