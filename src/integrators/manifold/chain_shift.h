// Chain assembly for every integrator that walks a specular chain (G-BDPT's
// and G-MLT's second chains, G-VCM's case-2 photon chains, path-space MLT's
// manifold perturbation): the base chain built from a path's vertices, the
// walk, the reversibility check, the offset interior re-traced and evaluated
// (ShiftChain), and the chain Jacobians in the measures those integrators use.
// The walk itself is scene-free (manifold.h); this part needs the renderer's
// Scene and BSDFs and is compiled into gradus_render with manifold_scene.cpp.
#pragma once
#include "core/arena.h"
#include "integrators/manifold/manifold.h"
#include "integrators/manifold/manifold_scene.h"
#include "materials/bsdf.h"

namespace gradus {

// What a chain shift needs to know: the scene adapter, the near-specular
// threshold (roughness below it: treated as specular, its half-vector kept)
// and the walk's options. Integrators embed it (SubpathShiftContext) or fill it.
struct ManifoldSettings {
    const EmbreeManifoldScene *mscene = nullptr;
    Float threshold = kDefaultShiftThreshold;
    ManifoldWalkOptions walk;
};

// Solid angle at a chain's start per unit area at its end, G / |cos_0| (JM12).
Float ChainSolidAnglePerArea(const ManifoldChain &c);
// Phi = |d(omega_0, omega_g..) / d(A_end, O_g..)|: the sampled directions of a
// chain (at its start and at every near-specular interior vertex g) per unit
// area at its end and per unit of the glossy half-vectors O_g. The map is block
// triangular (omega at a segment's start depends on the segment's end only), so
//   Phi = prod over the segments between glossy vertices of ChainSolidAnglePerArea
//         * |dx_g / dO_g| (HalfVectorJacobian, both chain ends fixed; G-MLT Eq. 14).
// Without glossy vertices Phi = ChainSolidAnglePerArea. Base and offset share
// A_end and O_g, so the ratio offset/base is the Jacobian J_b of the second
// chain in the camera-side direction measure (Eq. 5).
Float ChainDirectionsPerArea(const ManifoldChain &c);

inline bool Transmits(const Vec3 &wo, const Vec3 &wi, const Vec3 &n) { return Dot(wo, n) * Dot(wi, n) < 0; }

// The Dirac lobe of an ideal specular BSDF for a known event (reflection or
// refraction): value f |cos| and discrete probability.
bool DeltaLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *s);

// Endpoint of a chain: geometric normal (area measure), no curvature.
ManifoldSurfacePoint EndpointSP(const Point3 &p, const Vec3 &ng, int geomId);
// The interior vertices of a base chain (ideal specular, or near-specular
// glossy ones that the walk treats as specular: their half-vectors are kept,
// Sec. 3.1), from its start towards its end: interactions, BSDFs, the
// directions towards the start (wo) and the end (wi), the event (refraction or
// reflection), whether the vertex is ideal specular, and the geometry.
struct ChainInterior {
    SurfaceInteraction si[kMaxManifoldVertices];
    const BSDF *bsdf[kMaxManifoldVertices];
    Vec3 wo[kMaxManifoldVertices], wi[kMaxManifoldVertices];
    bool transmit[kMaxManifoldVertices];
    bool specular[kMaxManifoldVertices];
    int geomId[kMaxManifoldVertices];
};
// Builds the base chain start, interior[0..k-1], end; records the index of
// refraction of refracting interiors (the Dirac lobe's, or BSDF::eta for glossy ones).
bool BuildChain(const ManifoldSettings &ctx, const ManifoldSurfacePoint &start, const ChainInterior &interior, int k,
                const ManifoldSurfacePoint &end, ManifoldChain *chain);

// Interactions, BSDFs and the vertex factors of a walked offset interior
// (re-traced from the chain's start, each vertex with the base's event), in
// the chain's direction (wo towards its start, wi towards its end).
struct WalkedInterior {
    SurfaceInteraction si[kMaxManifoldVertices];
    BSDF bsdf[kMaxManifoldVertices];
    Spectrum fcos[kMaxManifoldVertices];  // f |cos wi|: the Dirac coefficient at an ideal specular vertex
    Float pdf[kMaxManifoldVertices];      // its discrete lobe probability, or the glossy solid-angle density
    Spectrum factor{1};  // prod of the ideal specular vertices' fcos
    Float prob = 1;      // prod of their discrete lobe probabilities
};
// Re-traces a chain's interior from its start through its positions (ending
// at `end`) and evaluates each vertex with the event of transmit[] (chain_shift.cpp).
bool EvaluateWalked(const Scene &scene, const ManifoldChain &off, const Point3 &end, const bool *transmit,
                    const int *geomIds, Arena &arena, TransportMode mode, WalkedInterior *w);


// Why ShiftChain failed.
enum class ChainShiftFailure : uint8_t {
    None,
    Walk,           // the walk failed or was not reversible (the walk result's status says why)
    Evaluation,     // the re-traced interior did not match or has a black/zero-density vertex
    ClassMismatch,  // an offset vertex is rough where the base's is not: no bijection
};

// The shift of a base chain: walk it from `start` (its own start, or a moved
// one) until its end reaches `target` (same surface as the base's end), with
// every interior half-vector kept; keep it only if it is reversible (JM12 Sec. 5:
// the walk may converge to another solution; only reversible walks keep the
// shift a bijection; tolerance 1e-4 of the scene scale); re-trace and evaluate
// the offset interior with the base's events in `mode` (EvaluateWalked, the
// offset ending at target.p); require the base's vertex classes. Chains with
// near-specular vertices are walked to 1e-11 (see chain_shift.cpp).
// *walk holds the walk (its status also when the check failed).
ChainShiftFailure ShiftChain(const ManifoldSettings &s, const Scene &scene, const ManifoldChain &base,
                             const ManifoldSurfacePoint &start, const ManifoldSurfacePoint &target,
                             const ChainInterior &interior, TransportMode mode, Arena &arena,
                             ManifoldWalkResult *walk, WalkedInterior *walked);

}  // namespace gradus
