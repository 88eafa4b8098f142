// Shifts of bidirectional subpaths (the G-BDPT shift mapping of
// gradient-domain-bdpt.md Sec. 3.1) on the shared path vertices of common/:
// the context, statistics and vertex/chain building blocks shared by the
// camera-subpath shift (camera_shift.h, cases (i) and (ii) of Sec. 3.2) and
// the light-tracing-path shift (lighttracing_shift.h, case (iii)), for G-BDPT,
// G-VCM and G-MLT.
//
// Vertex classes: a surface vertex is "diffuse" (Rough) when the lowest
// roughness of its BSDF is >= shiftthreshold, otherwise "specular"; camera and
// light vertices are diffuse. a = 0 (the eye), b and c are the next two
// diffuse vertices along the path from the eye.
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
// the ratio of generalised geometry terms (JM12) per solid angle at b
// (ChainSolidAnglePerArea). This equals |dy/dx| of Eq. 5 (the
// reparameterisation Jacobians of LKL13 in the reduced measure); it is checked
// against finite differences in tests/gbdpt. A second chain with near-specular
// glossy vertices g (treated as specular, Sec. 3.1: the walk keeps their
// half-vectors) has the directions at b and at every g as variables; its
// J_b = Phi(y)/Phi(x) (ChainDirectionsPerArea, which adds |dx_g/dO_g|, G-MLT
// Eq. 14) multiplies f_y,g |cos_y,g| / p_x,g of each g. The prefix product up
// to b is Eq. 7, up to c Eq. 6.
//
// Gradient MIS ratio rho = |T'| p_st(y) / p_st(x) (Eq. 8): the product over
// the shifted sampled directions of J_i p_y,i / p_x,i (discrete lobe
// probabilities at ideal specular vertices); CombinedWeight (shift.h) turns it
// into the weight of Eq. 8. The weights of all strategies of one path sum to
// one only if every strategy uses the same |T'| in the measure of the MIS
// densities of common/ (area measure, Dirac factors remapped to 1): the
// light-tracing shift takes the camera side's effective |T'|, and a path
// either uses Eq. 8 for all its strategies or falls back for all (failures
// depend on the path only).
#pragma once
#include <algorithm>
#include <cstdint>
#include <new>
#include <string>

#include "integrators/common/bidir.h"
#include "integrators/gradient/shift.h"
#include "integrators/manifold/chain_shift.h"

namespace gradus {

// The walk's settings (mscene, threshold, walk options: manifold/chain_shift.h)
// and the subpath shifts' own switches.
struct SubpathShiftContext : ManifoldSettings {
    const BidirContext *bidir = nullptr;
    bool manifold = true;        // manifold walk (else half-vector shift)
    bool trySpecular = true;     // scene has specular or near-specular surfaces
    // The scene has participating media: the shifts take their medium
    // vertices and transmittance ratios (camera_shift.h, lighttracing_shift.h);
    // without media they run the surface-only code.
    bool media = false;
};

// Counters of one sample's shifts (flushed into an integrator's totals).
struct SubpathShiftStats {
    LocalShiftStats shift;
    uint64_t walks = 0, walkFailures = 0;
    uint64_t walkStatus[size_t(ManifoldStatus::Count)] = {};
    uint64_t glossyChains = 0;  // second chains walked with near-specular (glossy) vertices
    uint64_t longChains = 0;    // second chains longer than the walk takes (kMaxManifoldVertices): fallback
    uint64_t mediaChains = 0;   // non-empty second chains in a scene with media: fallback (camera_shift.h)
    void recordWalk(const ManifoldWalkResult &r);
    void add(const SubpathShiftStats &o);
    // The manifold-walk lines of the end-of-render report.
    std::string formatWalks(bool walksTried) const;
};

// A subpath with the per-vertex data the shift needs.
struct ShiftSubpath {
    PathVertex *v = nullptr;
    BSDF *b = nullptr;
    uint8_t *deltaSample = nullptr;  // the direction sampled at v[i] came from a Dirac lobe
    // Scenes with media, camera subpaths: the distance-sampling factors of the
    // segment that reached v[i] (GenerateCameraSubpath's segFactors).
    Spectrum *segFactor = nullptr;
    int n = 0;
    SubpathView view() const { return {v, b, n}; }
};

// Sets deltaSample and marks specular (class != Rough) surface vertices with
// VERTEX_DELTA so that MIS and connections leave them out (Sec. 3.2).
void PrepareSubpath(const SubpathShiftContext &ctx, ShiftSubpath *p);
// The directions sampled at camera vertices 1 .. last all came from Dirac
// lobes: an emitter at vertex last + 1 (strategy s = 0) is seen through an
// ideal specular chain (or directly, last = 0), light separated from the
// reconstruction (gradient_film.h). The camera-subpath shift copies
// deltaSample vertex by vertex and takes the same Dirac lobe at each
// (camera_shift.cpp), so a base and its offsets are classified alike and so
// is the inverse shift's pair: dropping both halves of a separated base's
// gradient keeps the symmetric estimator, for the image without that light.
inline bool DiracCameraChain(const ShiftSubpath &cam, int last) {
    for (int i = 1; i <= last; ++i)
        if (!cam.deltaSample[i]) return false;
    return true;
}
// Separated light by its own estimator (gbdpt/gvcm "separatedsamples"): a
// camera walk from `ray` that samples each BSDF and goes on only while the
// sampled lobe is Dirac (BSDFSample::isSpecular, the test that sets the
// camera subpath's deltaSample), adding throughput x emitted radiance at every
// emitter it reaches (area lights; the infinite lights where it escapes) at
// depth <= maxDepth: the emitter at vertex j is strategy (0, j + 1) of depth
// j - 1, exactly the s = 0 contributions that DiracCameraChain separates.
// No next-event estimation, no roulette. Scenes without media only (the
// caller's check). Random numbers from `rng`; BSDFs in `arena`.
Spectrum DiracCameraWalk(const BidirContext &ctx, Ray ray, int maxDepth, RNG &rng, Arena &arena);
// f |cos| at a surface vertex (its BSDF, shading normal), the phase function
// at a medium vertex, towards wi from wo; *pdf: the solid-angle density of wi.
Spectrum ScatterValue(const PathVertex &v, const BSDF &b, const Vec3 &wo, const Vec3 &wi, Float *pdf);
// Rough (diffuse) for shift purposes.
bool IsDiffuseVertex(const SubpathShiftContext &ctx, const PathVertex &v, const BSDF *b);

// dA_b/ds of a pinhole camera at `lens` with axis n0 (cos^4 / G of
// ShiftJacobianFactor for an empty eye chain, up to the focal constant).
Float EyeAreaFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb, const Vec3 &ngb);
// The same for a point b in a medium (no cosine at b, as ConvertDensity).
Float EyeVolumeFactor(const Point3 &lens, const Vec3 &n0, const Point3 &pb);

// ---- Building blocks of the subpath shifts -------------------------------
constexpr Float kShiftDirTol = 1e-4;  // 1 - cos between a recomputed and an expected direction

// n default-constructed Ts in the arena (at least one).
template <typename T>
T *ArenaArray(Arena &arena, int n) {
    T *p = static_cast<T *>(arena.alloc(sizeof(T) * size_t(std::max(n, 1)), alignof(T)));
    for (int i = 0; i < std::max(n, 1); ++i) new (&p[i]) T();
    return p;
}
// Interaction of a vertex (no ray offset off surfaces).
Interaction VertexIt(const PathVertex &v);
// Component-wise a / b (0 where b is 0).
Spectrum SafeDiv(const Spectrum &a, const Spectrum &b);
// Closest hit that skips material-less interfaces (as the subpath random walk does).
bool TraceSurface(const Scene &scene, Ray ray, SurfaceInteraction *si);
// Surface interaction of a stored vertex (mesh: from barycentrics; else by a ray from `from`).
bool VertexInteraction(const Scene &scene, const PathVertex &v, const Point3 &from, SurfaceInteraction *si);
// Empty second chain: the offset vertex yFrom (base: xFrom) reconnects to the
// base vertex `target` (ShiftReconnect's Jacobian) if it sees it. Counts the
// attempt and a failure in `st` (the success is the caller's).
bool ReconnectToVertex(const Scene &scene, const Point3 &xFrom, const Interaction &yFrom, const PathVertex &target,
                       LocalShiftStats *st, ReconnectionShift *rc);
// Second chain of an offset: the manifold walk from `start` to the base
// chain's end, kept only if it is reversible (JM12 Sec. 5: the walk may
// converge to another solution of the chain; only reversible walks keep the
// shift a bijection), then the re-traced interior (`walked`) and
// J = ChainDirectionsPerArea(offset) / ChainDirectionsPerArea(base), the
// Jacobian of the chain's sampled directions with its end and its glossy
// half-vectors fixed. Records the walk and a failure in `st`.
bool WalkSecondChain(const SubpathShiftContext &ctx, const ManifoldChain &base, const ManifoldSurfacePoint &start,
                     const ChainInterior &interior, Arena &arena, SubpathShiftStats *st, ManifoldChain *offset,
                     WalkedInterior *walked, Float *J);

}  // namespace gradus
