// Bidirectional path sampling shared by BDPT and its descendants: camera and
// light subpath generation, area-measure pdfs of vertices in both directions,
// the connection of light vertex s with camera vertex t for every strategy,
// and the MIS weight of a strategy.
//
// Notation (Veach 1997, ch. 10): a path x_0 ... x_{k} runs from the light
// (x_0) to the camera (x_k). Strategy (s, t) takes s vertices of the light
// subpath and t of the camera subpath: s = 0 is a camera path that hits an
// emitter, s = 1 samples a point on a light from the camera vertex (next-event
// estimation), t = 1 samples a lens point from the light vertex (light
// tracing, splatted to a raster position). (s, t) = (1, 1) is not evaluated.
//
// MIS: pbrt-v3's on-the-fly remapping (Veach 1997, Sec. 10.2 and Eq. 10.9):
// every vertex stores the area density with which its own subpath generated it
// (pdfFwd) and the density with which the opposite subpath would have
// (pdfRev); the weight of (s, t) is 1 / sum_i (p_i / p_s)^beta with the ratio
// p_i / p_{i+1} = pdfRev / pdfFwd of the vertex that changes sides (Eq. 10.9).
// A connection evaluates the four reverse pdfs that depend on the other
// subpath (both endpoints and their predecessors) without modifying the
// subpaths. Delta pdfs (specular lobes, delta lights) are stored as 0 and
// remapped to 1 in the ratios; strategies whose connection would touch a
// delta vertex are left out of the sum. Strategies that are never evaluated
// ((1,1), t = 0) and connections across near-coincident vertices (edge length
// below BidirContext::minConnectDist) are left out both from the estimate and
// from the MIS sums of all strategies of that path, so the weights of the
// evaluated strategies sum to one. Which strategies are in play at all (light
// tracing on or off, several light-tracing samples per camera sample, vertex
// merging) is a StrategySet: the MIS sums count exactly those.
//
// Participating media (pbrt-v3's BDPT, PBR 3rd ed. Sec. 16.3): each segment of
// a subpath samples a scattering distance in its medium; a scattering point is
// a Medium vertex (HG phase function: value = pdf, no cosines), surfaces
// without a material are crossed, changing the medium. Connections multiply by
// the transmittance (Scene::transmittance) instead of testing visibility. MIS
// as pbrt-v3: vertex densities are the directional ones converted to area
// (no cosine at medium vertices); the distance-sampling densities are left out
// of every strategy alike, so the weights still sum to one. Medium vertices
// are connectible, never mergeable. Random numbers of the media (distances,
// transmittance) come from a UniformSource the caller passes (a per-sample
// RNG; mlt: its primary samples); a scene without media takes none and runs
// the code it ran before.
#pragma once
#include <vector>

#include "core/arena.h"
#include "integrators/common/merge_kernel.h"
#include "integrators/common/path_vertex.h"
#include "lights/light_sampler.h"
#include "scene/scene.h"
#include "samplers/rng.h"
#include "samplers/sampler.h"
#include "samplers/uniform_source.h"

namespace gradus {

enum class MISHeuristic { Balance, Power };

// The strategies in play for one integrator, so that the MIS sums contain
// exactly the strategies it evaluates (leaving a strategy out of the
// estimate but not out of the sums loses its share of the energy). With n_k
// samples of strategy k per camera sample the weights are the multi-sample
// heuristics w_s = (n_s p_s)^beta / sum_k (n_k p_k)^beta (Veach 1997 Sec. 9.2,
// in the ratio form of Eq. 10.9); the caller divides each of its n_s samples'
// contributions by n_s.
struct StrategySet {
    // t = 1 strategies (light tracing: a lens point sampled from light vertex
    // s-1, splatted) in play; off, their terms leave every weight's sum and
    // MISWeight of a t = 1 strategy is 0 (G-BDPT Table 1 "w/o LTP").
    bool lightTracing = true;
    // n_LT: light-tracing samples per camera sample (1 for BDPT: one light
    // subpath per camera sample; a VCM pass with N_light light paths for N_pixel
    // camera samples has N_light / N_pixel). Scales the t = 1 terms.
    Float lightTracingSamples = 1;
    // Vertex merging (VCM, Georgiev et al. 2012; G-VCM gradient-domain-vcm.md
    // Eq. 12): each interior vertex x_j with a non-specular BSDF adds a merging
    // term eta_VCM p(x_j from the other side) p_VC,j, with mergeFactor =
    // eta_VCM = pi r^2 N_light (N_light light subpaths merged per camera
    // subpath, one connected). The sums then need the subpaths' BSDFs.
    bool merging = false;
    Float mergeFactor = 0;
    // G-VCM (Sec. 4): merges only at connectable vertices, those the shift's
    // classification left unmarked (subpath_shift.h PrepareSubpath marks
    // near-specular ones VERTEX_DELTA).
    bool mergeRoughOnly = false;
    // A kernel whose radius varies along the path (merge_kernel.h): when set,
    // eta_VCM at each vertex comes from it and mergeFactor is not used.
    const MergeKernel *kernel = nullptr;
};

// Everything the connection code needs besides the subpaths (read-only, shared by threads).
struct BidirContext {
    const Scene *scene = nullptr;
    const Camera *camera = nullptr;
    const LightSampler *lightSampler = nullptr;
    MISHeuristic heuristic = MISHeuristic::Balance;
    Float minConnectDist = 0;  // connections over shorter edges are rejected (set by Init)
    // Russian roulette in subpath generation after this many bounces (-1: off,
    // pbrt-v3's BDPT has none). A subpath continues with probability
    // min(1, max(0.05, |beta| / |beta_0|)) and its throughput is divided by it.
    // The MIS weights (which ignore it) still sum to one, so every strategy stays
    // unbiased: the continuation is an unbiased random weighting of the suffix.
    int rrDepth = -1;
    // The strategies in play (ConnectBDPT and MISWeight without a set use it).
    StrategySet strategies;
    // Sets scene/camera/light sampler and the near-coincidence threshold
    // (1e-5 of the scene's bounding-sphere diameter).
    void init(const Scene &s, const LightSampler &ls, MISHeuristic h);
};

// ---------------------------------------------------------------- subpaths
// Camera subpath from a camera ray: vertex 0 on the lens, then up to
// maxVertices - 1 scattering vertices (an escaped ray adds an infinite-light
// vertex when the scene has infinite lights). Returns the number of vertices.
// Sampler use per bounce: 1D (lobe) + 2D (direction).
// Sampler use per medium vertex: the same (1D unused, 2D phase direction).
// mediaRng: distance sampling (required when the scene has media, else unused).
// segFactors (optional, scenes with media): segFactors[i] = the product of
// Medium::sample's factors on the segment (through interfaces) that reached
// vertex i (sigma_s T / p(t) where it scattered, T / P(pass) elsewhere;
// G-BDPT's offsets scale them by T_y / T_x).
int GenerateCameraSubpath(const BidirContext &ctx, const Ray &ray, Sampler &sampler, Arena &arena,
                          int maxVertices, PathVertex *path, BSDF *bsdfs, UniformSource mediaRng = {},
                          Spectrum *segFactors = nullptr);
// Fixed blocks of sampler dimensions for one bidirectional sample taken from
// the pixel sampler (bdpt, gbdpt): the camera subpath from the sampler's
// dimension d0 at construction, the light subpath and each strategy's
// connection numbers (s = 1: 1D + 2D, t = 1: 2D) at offsets that do not
// depend on the subpaths' lengths, so that every strategy's numbers keep the
// sampler's stratification over a pixel's samples (consumed one after the
// other, they start wherever the camera subpath's random walk ended, which
// varies from sample to sample). A random-walk vertex takes at most 4
// dimensions (BSDF 1D + 2D, roulette 1D), a light subpath's origin 5. Checks
// that each subpath stayed within its block. No-op for samplers without
// dimensions (RNGSampler).
class BidirDimensions {
  public:
    BidirDimensions(const Sampler &sampler, int maxCameraVertices, int maxLightVertices);
    void startLightSubpath(Sampler &sampler) const;         // after the camera subpath
    void startConnection(Sampler &sampler, int s, int t);  // after the light subpath

  private:
    static constexpr int kWalkDims = 4, kLightOriginDims = 5, kConnectDims = 3;
    int d0_, light_, connect_, maxLight_;
    bool lightChecked_ = false;
};
// Light subpath: picks a light (1D), samples emission (2D position + 2D direction),
// then up to maxVertices - 1 scattering vertices. Returns the number of vertices.
int GenerateLightSubpath(const BidirContext &ctx, Sampler &sampler, Arena &arena, int maxVertices,
                         PathVertex *path, BSDF *bsdfs, UniformSource mediaRng = {});
// The per-sample RNG of the media for a camera sample (seed, film and lens position).
RNG CameraSampleMediaRNG(const Sampler &sampler, const CameraSample &cs);

// ---------------------------------------------------------------- media
// The medium of Scene::media index (PathVertex::mediumIndex; 0: none), and back.
const Medium *MediumAt(const Scene &scene, uint8_t index);
uint8_t MediumIndexOf(const Scene &scene, const Medium *m);
// The medium a ray leaving vertex v in direction d starts in (camera: the
// camera's; light: its interface's side of d; surface: its shape's interface,
// or the medium it was reached in where that is no transition; medium vertex: its own).
const Medium *MediumTowards(const BidirContext &ctx, const PathVertex &v, const Vec3 &d);
// Visibility between vertex a (interaction ia) and interaction ib: in a scene
// with media the transmittance from a's medium towards b (rng required), else 1 or 0.
Spectrum Transmittance(const BidirContext &ctx, const PathVertex &a, const Interaction &ia, const Interaction &ib,
                       UniformSource rng);
// |cos| of direction w at a scattering vertex (1 at medium vertices: no foreshortening).
inline Float ScatterCos(const PathVertex &v, const Vec3 &w) {
    return v.type == VertexType::Medium ? Float(1) : AbsDot(w, Vec3(v.ns));
}
// Solid-angle density of scattering from wo to wi at a surface (its BSDF) or
// medium vertex (its phase function).
Float ScatterPdf(const PathVertex &v, const BSDF &bsdf, const Vec3 &wo, const Vec3 &wi, TransportMode mode);

// ---------------------------------------------------------------- vertex queries
// Area density at `next` of sampling it from `cur` (arrived at from `prev`;
// ignored for camera and light vertices; nullptr at an emissive surface vertex
// makes it the origin of a light subpath), in the given transport mode.
Float PdfArea(const BidirContext &ctx, const PathVertex &cur, const BSDF *bsdf, const PathVertex *prev,
              const PathVertex &next, TransportMode mode);
// Density of `v` (an emitter: light vertex or emissive surface) as the origin of
// a light subpath that continues towards `next` (light pmf x position pdf; for
// infinite lights the directional density of all infinite lights).
Float PdfLightOrigin(const BidirContext &ctx, const PathVertex &v, const PathVertex &next);
// Area density at `next` of the emission direction sampled at emitter vertex `v`.
Float PdfLightDirection(const BidirContext &ctx, const PathVertex &v, const PathVertex &next);
// BSDF value at `cur` towards `next` (with the adjoint shading-normal correction
// in Importance mode, Veach 1997 Sec. 5.3.4), not multiplied by any cosine;
// at a medium vertex the phase function (bsdf unused).
Spectrum EvalBSDF(const PathVertex &cur, const BSDF &bsdf, const PathVertex &next, TransportMode mode);
// Emitted radiance from emitter vertex `v` towards `towards`.
Spectrum EmittedRadiance(const BidirContext &ctx, const PathVertex &v, const PathVertex &towards);
// The light whose emission a vertex carries (area light of a surface vertex, light of a light vertex).
const Light *EmitterOf(const BidirContext &ctx, const PathVertex &v);
// True when a connection can end at this vertex (non-specular BSDF, not a
// delta-direction light).
bool IsConnectible(const PathVertex &v, const BSDF *bsdf);

// A vertex at which a camera and a light subpath can be merged (VCM): a surface
// with a non-specular BSDF component (bsdf must be given).
bool IsMergeable(const PathVertex &v, const BSDF *bsdf);
// IsMergeable among the strategies of `set` (StrategySet::mergeRoughOnly).
inline bool MergeableIn(const StrategySet &set, const PathVertex &v, const BSDF *bsdf) {
    return IsMergeable(v, bsdf) && !(set.mergeRoughOnly && v.delta());
}
// A surface vertex of an intersection and its BSDF (what the random walks
// store; throughput and pdfs left zero).
void MakeSurfaceVertex(const BidirContext &ctx, const SurfaceInteraction &isect, const BSDF &bsdf, PathVertex *v);
// The vertex as an interaction (no ray offset off surfaces).
Interaction AsInteraction(const PathVertex &v);
// Solid-angle density at `from` towards `to` -> area density at `to` (Veach 1997,
// Eq. 8.10); towards an infinite-light vertex it stays directional.
Float ConvertDensity(Float pdf, const PathVertex &from, const PathVertex &to);
// Arena storage for a subpath of n vertices and BSDFs, uninitialised: the
// subpath generators fill every vertex and BSDF they create (index < n returned).
void AllocSubpath(Arena &arena, int n, PathVertex **v, BSDF **b);
// A lens vertex sampled towards surface vertex qs (light tracing, t = 1):
// throughput We / pdf, pdfFwd 1.
bool SampleLensVertex(const BidirContext &ctx, const PathVertex &qs, Point2 u, PathVertex *v, CameraWiSample *cws);
// A light vertex sampled from pt (next-event estimation, s = 1): *weight = L / (pdf pmf),
// pdfFwd = PdfLightOrigin.
bool SampleLightVertex(const BidirContext &ctx, const PathVertex &pt, Float uSel, Point2 u, PathVertex *v,
                       LightLiSample *ls, Spectrum *weight);

// Rebuilds the surface interaction and the BSDF of a stored surface vertex
// (for integrators that store vertices across an iteration). Returns an empty
// BSDF for non-surface vertices.
BSDF RebuildBSDF(const BidirContext &ctx, const PathVertex &v, TransportMode mode, Arena &arena);

// ---------------------------------------------------------------- connections
struct ConnectSamples {
    Float uLightSelect = 0;  // s = 1: light choice
    Point2 uLight;           // s = 1: point on the light
    Point2 uLens;            // t = 1: lens point
    // The connection edge is known to be unoccluded (a shifted path that
    // reuses its base's edge, G-BDPT): no shadow ray is traced.
    bool knownVisible = false;
    // Transmittance estimates (scenes with media; the sample's media RNG, or
    // mlt's connection stream).
    UniformSource rng;
    // s = 1: only a sampled infinite or distant light contributes (M-BDPT's
    // next-event estimation through the matrix covers the other lights).
    bool infiniteLightsOnly = false;
    // Optional: the weight's parts for camera subpaths that share this one's
    // vertices from misSplit + 1 on (MISSplit; used when misSplit + 2 <= t - 1).
    int misSplit = -1;
    struct MISSplit *misParts = nullptr;
};

struct ConnectResult {
    Spectrum L;            // MIS-weighted contribution
    Spectrum unweighted;   // contribution of the strategy alone (L / weight)
    Float weight = 0;      // MIS weight
    bool splat = false;    // t = 1: add L at pRaster on the film (light tracing)
    Point2 pRaster;
    bool shadowRayTraced = false;
};

// Connects light vertex s-1 with camera vertex t-1 (strategy (s, t)) and
// weights it over ctx.strategies; s = 1 and t = 1 sample a fresh light/lens
// vertex with `u`. Works on any pair of
// subpaths with BSDFs (stored subpaths: rebuild them first). Returns false when
// the strategy contributes nothing.
bool ConnectBDPT(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t,
                 const ConnectSamples &u, ConnectResult *res);

// MIS weight of strategy (s, t) for the path formed by light[0..s-1] and
// camera[t-1..0], over the strategies of `set`. `sampled` replaces light[s-1]
// (s = 1) or camera[t-1] (t = 1) when the connection sampled a new endpoint
// (nullptr: use the subpath's).
Float MISWeight(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s, int t,
                const PathVertex *sampled, int split = -1, struct MISSplit *parts = nullptr);
// Weight of merging at camera[t-1] with a light subpath whose vertex after
// light[s-1] landed there (VCM; s >= 1, t >= 2, set.merging), for the path
// light[0..s-1] camera[t-1..0]: N p_VM over the connections and merges of that
// path (G-VCM Eq. 13). The O(n) reference of vcm's recursive weights.
Float MergeWeight(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s,
                  int t);
// The same over the context's strategies.
inline Float MISWeight(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t,
                       const PathVertex *sampled) {
    return MISWeight(ctx, ctx.strategies, light, camera, s, t, sampled);
}

// Incremental weights of camera subpaths that differ only below a vertex
// (G-BDPT's offsets share the base's vertices from the reconnection on).
// With rho_j = pdfRev_j / pdfFwd_j, MISWeight's camera terms of strategy (s, t)
// split at m (m + 2 <= t - 1; with merging, SplitSupported) into those with endpoints above m,
// which involve only vertices m + 1 .. t - 1 and the light subpath, and
// prod_{j=m+1}^{t-1} rho_j times CameraPrefixSum(camera, m):
//   w_st = 1 / (1 + shared + product * CameraPrefixSum(m))   (Veach Eq. 10.9).
// A camera subpath y that agrees with x in positions, flags and BSDFs from
// vertex m on and in pdfFwd and pdfRev from m + 1 on has x's shared and
// product, so its weight costs O(1) per strategy once CameraPrefixSum(y, m) is
// known (G-BDPT's offsets with reconnection vertex r: m = r + 1).
struct MISSplit {
    Float shared = 0;   // light terms + camera terms with endpoint index > m (mis applied)
    Float product = 0;  // mis(prod_{j=m+1}^{t-1} rho_j)
    bool valid = false;
    Float weight(Float prefixSum) const { return 1 / (1 + shared + product * prefixSum); }
};
Float MISWeight(const BidirContext &ctx, const StrategySet &set, SubpathView light, SubpathView camera, int s, int t,
                const PathVertex *sampled, int split, MISSplit *parts);
// With merging, the split holds for a kernel whose eta is the same at every
// vertex (merge_kernel.h): the merge terms at C[1..m] join the prefix sum.
inline bool SplitSupported(const StrategySet &set) { return !set.merging || !set.kernel || !set.kernel->varies(); }
Float CameraPrefixSum(const BidirContext &ctx, const StrategySet &set, SubpathView camera, int split);

// True when strategy (s, t) of the full path could produce it: both endpoints
// connectible and the connection edge not degenerate - not shorter than
// minConnectDist, not in the tangent plane of a surface end (|cos| < 1e-6)
// (used by the connections, MISWeight and tests).
bool EdgeConnectible(const BidirContext &ctx, const PathVertex &a, const PathVertex &b);

}  // namespace gradus
