// Vertex connection and merging (Georgiev, Krivanek, Davidovic, Slusallek 2012;
// the G-VCM paper's Sec. 2.3, gradient-domain-vcm.md), on the shared
// bidirectional core (integrators/common/) and the pass-based render loop.
//
// One iteration = one pass = one sample per pixel:
//   1. light pass: N light subpaths (N = sampled pixels; RNG keyed by
//      (seed, pass, subpath)), each vertex with a non-specular BSDF stored as a
//      compact LightVertex (128 bytes: geometry, throughput, what RebuildBSDF
//      needs, and the recursive MIS quantities below); light tracing (t = 1)
//      splats from every stored vertex;
//   2. the photon hash grid over the stored vertices (cell = 2r, counting sort,
//      integrators/common/photon_grid.h), when merging is in play;
//   3. camera pass: each pixel's camera subpath (pixel sampler) evaluates at
//      every vertex z_u: emission (s = 0), next-event estimation (s = 1),
//      connections to the vertices of its own light subpath (subpath index =
//      pixel index, Eq. 10), and merges with every light vertex within r
//      (Eq. 11), estimate beta_L f(z_u) beta_C / (pi r^2 N).
// MIS (balance or power heuristic, G-VCM Eqs. 12-13) in O(1) per connection and
// merge by recursive partial sums; the O(n) reference is MISWeight/MergeWeight
// (common/bidir.h), against which tests/vcm checks them. For a subpath
// v_0 v_1 ... (own side) and the strategy whose own endpoint is v_m, let
// S(m) = sum over the strategies that move the junction towards v_0 (fewer own
// vertices) and the merges at v_1..v_m, relative to the current one. With
// own(v) the density of v from its own subpath (pdfFwd), other(v) the density
// from the opposite one (pdfRev), R_m = other(v_m) / own(v_m) (deltas as 1),
// c_m in {0, 1} whether the connection with own endpoint v_m is a strategy,
// g_m whether v_m can be merged at, and eta = pi r^2 N (eta_VCM):
//   S(m) = eta g_m other(v_m) + R_m (c_{m-1} + S(m-1)),   S(-1) = 0,
// and B_m = c_{m-2} + S(m-2) only involves the subpath itself, so it is stored
// with each light vertex (and computed along the camera subpath):
//   B_{m+2} = c_m + eta g_m other(v_m) + R_m B_{m+1},  B_0 = 0, B_1 = c_{-1}.
// A connection of light endpoint y_i and camera endpoint z_u then costs two
// steps on each side with the densities that depend on the connection:
//   w_VC = 1 / (1 + S_L(i) + S_C(u)),  S(m) = eta g_m o_m + R_m (c_{m-1} + eta g_{m-1} o_{m-1} + R_{m-1} B_m);
// a merge of light vertex y_m at z_u is weighted against the connection of
// y_{m-1} and z_u: w_VM = eta o(z_u) / (c + S_L(m-1) + S_C(u)), with o(z_u) the
// light vertex's own density (pdfFwd of y_m). With the power heuristic every
// ratio and merge term is squared. This is the role of Georgiev's dVCM, dVC,
// dVM, written with the area densities (pdfFwd/pdfRev) the rest of the
// bidirectional code stores.
// A kernel that varies along the path (G-VCM Sec. 6, merge_kernel.h) makes
// eta a per-vertex eta_j, in camera order eta_{j} = eta_{j+1} sigma(v_{j+1})
// on the light side: the camera subpath knows its own eta_u; a light vertex's
// depend on the camera-side radius at the junction. So the light side keeps
// B in two parts, B_i = Bc_i + h^beta Be_i with h = eta at y_{i-1}:
//   Bc_{i+1} = c_{i-1} + R_{i-1} Bc_i,
//   Be_{i+1} = sigma_i^beta (g_{i-1} o_{i-1}^beta + R_{i-1} Be_i)   (eta at y_{i-1} = h_i sigma_i),
// and S_L(i) of a connection takes h = eta at y_i = eta_u sigma(z_u) of the
// camera endpoint z_u (a merge at z_u: eta at y_{m-1} = eta_u sigma(z_u); light
// tracing: the footprint eta at y_i). With one radius (sigma = 1) this is the
// recursion above.
//
// Radius: r_1 = `radius` (scene units) or, if 0, `radiusscale` times the
// median pixel footprint at the primary hits (the G-VCM paper's Sec. 6,
// "about one pixel"); iteration i (1-based, the global sample index + 1, so
// partial renders merge exactly) uses r_i^2 = r_1^2 i^(alpha - 1) (alpha =
// `radiusalpha`; Knaus and Zwicker's schedule, as in Georgiev's reference code;
// pbrt-v3's SPPM shrinks per pixel instead). The G-VCM paper's Sec. 6
// (merge_kernel.h) as options: `kernel adaptive` shrinks the radius per vertex
// along the camera subpath, `footprint path` replaces r_1 by the path's own
// pixel width at its first mergeable camera vertex (at most 2 r_i). Both off
// by default: on the three SDS benchmark scenes neither lowers relMSE at equal
// time (bench/gvcm/RESULTS.md, "Merging kernel").
// Participating media (common/bidir.h): medium vertices on both subpaths are
// stored and connected (their merge terms are absent from every sum: merging
// stays on surfaces); connections carry transmittance. Modes vcm and vc with
// the fixed kernel render media; mode vm and the varying kernels refuse them.
// Merging is left out (the grid is not built, statistics say so) in mode vcm
// when the scene has no specular or near-specular surface: without specular
// chains merging adds no path that connections cannot sample.
//
// Parameters (bidirectional family, integrators/common/bidir_family.h):
//   integer maxdepth 5              maximum path depth (edges - 1)
//   string lightsamplestrategy "power"  uniform | power | spatial (= power)
//   string misheuristic "balance"   balance (pbrt-v3) | power (exponent 2)
//   bool visualizestrategies false  not supported by vcm (must stay false)
//   bool visualizeweights false     not supported by vcm (must stay false)
//   integer rrdepth 3               Russian roulette on subpaths after this many bounces (-1: off)
//   integer pixelbounds []          accepted (use --cropwindow instead)
// vcm's own:
//   string mode "vcm"               vcm | vc (connections only: BDPT) | vm (merging only: progressive photon mapping)
//   float radius 0                  initial merging radius in scene units (0: from the pixel footprint)
//   float radiusscale 1             the footprint radius in pixels (radius 0)
//   float radiusalpha 0.75          radius reduction r_i^2 = r_1^2 i^(alpha - 1) (0.9 with radiusschedule "radius")
//   string radiusschedule "area"    area: r_i^2 = r_1^2 i^(alpha - 1) | radius: r_i = r_1 i^(alpha - 1) (the G-VCM authors' code)
//   bool normalfilter false         merge only photons whose geometric normal n_y has n_y . n_z >= 0.1 with the
//                                   camera vertex's n_z (the G-VCM authors' code; merge_kernel.h)
//   string kernel "fixed"           fixed (r_1 at every vertex) | adaptive (G-VCM Sec. 6: r_j = 0.5^(kernelshrink tau) r_{j-1})
//   float kernelshrink 10           adaptive: the exponent's factor (tau: roughness at the previous vertex)
//   string footprint "median"       radius 0: r_1 from the median primary-hit footprint | path (each path's own, Sec. 6)
//   integer numiterations 0         iterations (samples per pixel) unless --spp is given; 0: the sampler's (pbrt-v3 sppm)
//   integer photonsperiteration -1  pbrt-v3 sppm: light subpaths per iteration; only -1 (one per sampled pixel)
//   integer imagewritefrequency 0   pbrt-v3 sppm: accepted; intermediate images are not written
#pragma once
#include <atomic>
#include <string>
#include <vector>

#include "integrators/common/bidir_family.h"
#include "integrators/common/merge_kernel.h"
#include "integrators/common/photon_grid.h"
#include "render/integrator.h"

namespace gradus {

enum class VCMMode { VCM, VC, VM };

// How the merging radius shrinks with the iteration i (VCMRadius).
enum class RadiusSchedule {
    Area,    // r_i^2 = r_1^2 i^(alpha - 1) (Knaus and Zwicker; Georgiev's VCM)
    Radius,  // r_i = r_1 i^(alpha - 1) (the G-VCM authors' code, alpha 0.9 there)
};

// The merging radius of vcm and gvcm (set by MergeRadiusParams).
struct MergeRadiusSettings {
    Float radius, radiusScale, radiusAlpha;
    RadiusSchedule schedule;
    bool adaptiveKernel;  // G-VCM Sec. 6's shrink (merge_kernel.h)
    Float kernelShrink;
    bool pathFootprint;   // G-VCM Sec. 6's per-path footprint r_1
    bool normalFilter;    // merge only photons whose normal agrees (PhotonNormalAgrees, merge_kernel.h)
};
ParamTable<MergeRadiusSettings> MergeRadiusParams();
// The kernel of 1-based iteration i: r_i (VCMRadius) from the median footprint
// radius r1; adaptive: footprint radius per path (unless `radius` is given),
// clamped to 2 r_i, and the shrink. The photon grid is built for r_i.
// Located errors for merging-radius parameters that the others leave unused.
void CheckMergeRadiusParams(const EntityDesc &desc, const MergeRadiusSettings &s);
// The kernel's description for statistics.
std::string KernelName(const MergeRadiusSettings &s);
MergeKernel VCMKernel(const MergeRadiusSettings &s, Float r1, int iteration, int64_t nLight, const Camera &camera,
                      bool merging);

struct VCMSettings : BidirSettings, MergeRadiusSettings {
    VCMMode mode;
    int iterations, photonsPerIteration, imageWriteFrequency;
};

// One stored light vertex y_i (i >= 1, non-specular BSDF or in a medium). 128 bytes.
struct LightVertex {
    Point3 p;
    PackedVec3 ng, ns, wo;  // wo: towards y_{i-1}
    float beta[3];          // light subpath throughput up to and including y_i
    int32_t geomId, primId;
    float b1, b2;
    double pdfFwd;          // own(y_i)
    double prevPdfFwd;      // own(y_{i-1})
    double prevGeom;        // solid angle at y_i -> area at y_{i-1} (|cos| / d^2; 1 for an infinite light)
    double B;               // B_i = B + eta(y_{i-1})^beta Be (above), with the heuristic's exponent
    float Be;
    uint8_t depth;          // i (edges from the light; maxdepth <= 255 with merging)
    uint8_t flags;          // kPrev*, kMedium below
    int8_t betaExp;         // beta's exponent (PackThroughput, path_vertex.h)
    uint8_t mediumIndex;    // PathVertex::mediumIndex
    // kMedium: y_i is a medium vertex (connected, never merged: not in the photon grid's answers).
    static constexpr uint8_t kPrevDelta = 1, kPrevMergeable = 2, kPrevEdgeOK = 4, kMedium = 8,
                             kSpawnOffset = 16;  // b2 holds the vertex's spawn offset (PathVertex)
    bool inMedium() const { return flags & kMedium; }
    Spectrum throughput() const { return UnpackThroughput(beta, betaExp); }
};

// The recursive MIS quantities of the derivation above (exposed for tests/vcm).
struct VCMWeights {
    const MergeKernel *kernel;  // eta_VCM = pi r^2 N per vertex (merge_kernel.h); null without merging
    bool merging;     // merges are strategies
    bool connecting;  // connections (and light tracing) are strategies
    bool power;       // power heuristic (exponent 2)
    bool roughOnly = false;  // merges only at vertices not marked VERTEX_DELTA (G-VCM, StrategySet::mergeRoughOnly)
    bool mergeable(const PathVertex &v, const BSDF *b) const { return IsMergeable(v, b) && !(roughOnly && v.delta()); }
    Float sigma(const BSDF *b) const { return kernel ? kernel->sigma(b) : Float(1); }
};
// Appends the stored vertices y_i (i >= 1, non-specular BSDF or medium) of a light subpath
// with their B_i to *out; returns how many.
int VCMLightVertices(const BidirContext &ctx, const PathVertex *v, const BSDF *b, int n, const VCMWeights &w,
                     std::vector<LightVertex> *out);
// S_L(i-1) for light vertex y_i given o_{i-1} (density of y_{i-1} from y_i
// towards it) and h = eta at y_{i-1}, and whether the connection of y_{i-1}
// and y_i is a strategy (c_{i-1}).
Float VCMLightPrevSum(const LightVertex &lv, Float oim1, Float h, const VCMWeights &w);
bool VCMPrevConnectible(const LightVertex &lv);
// S_L(i) of a connection ending at light vertex y_i, given o_i (density of y_i
// from the camera side), o_{i-1}, h = eta at y_i and sigma(y_i).
Float VCMLightSum(const LightVertex &lv, Float oi, Float oim1, Float h, Float sigmaI, const VCMWeights &w);
// eta at each vertex of the camera subpath z[0..nC) (merge_kernel.h; all 0 without merging).
void VCMCameraEta(const VCMWeights &w, const PathVertex *z, const BSDF *zb, int nC, Float *eta);
// B_u of the camera subpath z[0..nC) with its eta.
void VCMCameraB(const BidirContext &ctx, const PathVertex *z, const BSDF *zb, int nC, const VCMWeights &w,
                const Float *eta, Float *B);
// What S_C(u) needs of camera vertex z_u besides the connection (once per vertex).
struct VCMCameraTerms {
    bool cPrev, cPrevEmitter;  // c_{u-1} for a connection / merge at z_u, and with z_u as the light origin
    bool gPrev;                // merging at z_{u-1} is a strategy
    Float ownU, ownPrev;       // own(z_u), own(z_{u-1}) (deltas as 1)
    Float B;                   // B_u
    Float etaU = 0, etaPrev = 0;  // eta at z_u, z_{u-1}
    Float H = 0;               // eta of the next vertex after z_u: the light side's junction, eta_u sigma(z_u)
};
VCMCameraTerms VCMCameraAt(const BidirContext &ctx, const PathVertex *z, const BSDF *zb, int u, Float Bu,
                           const Float *eta, const VCMWeights &w);
// S_C(u) given o_u (density of z_u from the light side) and o_{u-1}; gu: merging
// at z_u is a strategy; emitter: z_u is the light origin (s = 0).
Float VCMCameraSum(const VCMCameraTerms &c, Float oz, Float oPrev, bool gu, bool emitter, const VCMWeights &w);

// r_1 from the pixel footprint: `scale` times the median distance between the
// primary hits of neighbouring pixels (16 x 16 probes; G-VCM Sec. 6, "about one pixel").
Float VCMFootprintRadius(const Scene &scene, const Bounds2i &bounds, Float scale);
// A light pass's vertices gathered in subpath order while it runs
// (PassContext::forEachItem): the subpaths of chunk c append to buffer(item),
// and chunkMerged() moves chunk c's buffer to the end of *vertices as soon as
// the chunks before it are merged, so besides the vertices only the merge
// window's buffers exist (not every chunk and then a copy of all of them).
// *vertices keeps its capacity from pass to pass;
// subpath j owns (*vertices)[(*pathStart)[j], (*pathStart)[j + 1]).
class LightVertexGather {
  public:
    LightVertexGather(int64_t subpaths, int maxDepth, std::vector<LightVertex> *vertices,
                      std::vector<uint32_t> *pathStart);
    std::vector<LightVertex> &buffer(int64_t item) { return chunks_[size_t(item / PassContext::kItemChunk)]; }
    void setCount(int64_t item, int count) { (*pathStart_)[size_t(item) + 1] = uint32_t(count); }
    // forEachItem's chunkMerged.
    PassContext::ChunkFn chunkMerged() {
        return [this](int64_t c) { merged(c); };
    }

  private:
    void merged(int64_t chunk);
    std::vector<std::vector<LightVertex>> chunks_;
    int64_t n_;
    std::vector<LightVertex> *vertices_;
    std::vector<uint32_t> *pathStart_;
};
// The photon hash grid over a pass's light vertices (cell 2r), built in parallel.
void BuildLightVertexGrid(PassContext &ctx, const std::vector<LightVertex> &vertices, Float radius, PhotonGrid *grid);
// Radius of 1-based iteration i: r_i^2 = r_1^2 i^(alpha - 1) (Area) or
// r_i = r_1 i^(alpha - 1) (Radius).
Float VCMRadius(Float r1, Float alpha, int iteration, RadiusSchedule schedule = RadiusSchedule::Area);

// The light vertices merged at camera vertex z within radius r (vcm and gvcm):
// fn(index, vertex) for every stored light vertex closer than r to z.p, in the
// grid's order, except, with normalFilter, those whose geometric normal
// disagrees with z's (PhotonNormalAgrees).
template <typename Fn>
void ForEachMergeCandidate(const PhotonGrid &grid, const std::vector<LightVertex> &vertices, const PathVertex &z,
                           Float r, bool normalFilter, Fn &&fn) {
    grid.query(z.p, r, [&](uint32_t k, Float) {
        const LightVertex &lv = vertices[k];
        if (normalFilter && !PhotonNormalAgrees(Vec3(lv.ng), Vec3(z.ng))) return;
        fn(k, lv);
    });
}

class VCMIntegrator : public PixelSampleIntegrator, public BidirFamily {
  public:
    explicit VCMIntegrator(const EntityDesc &desc);
    std::string name() const override { return "vcm"; }
    void preprocess(const Scene &scene, Film &film) override;
    int samplesPerPass(const RenderOptions &) const override { return 1; }  // one iteration = 1 spp
    int defaultSamplesPerPixel() const override { return set_.iterations; }
    void runPass(PassContext &ctx) override;
    std::string statistics() const override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    // Medium vertices connect (vcm, vc); vm (merging only, on surfaces) and the
    // varying kernels (their junction radius at a medium vertex) do not render media.
    bool rendersMedia() const override {
        return set_.mode != VCMMode::VM && !set_.adaptiveKernel && !set_.pathFootprint;
    }

    // Merging radius of 1-based iteration i.
    Float radiusAt(int iteration) const;

  private:
    void lightPass(PassContext &ctx);
    struct CameraPath;  // one camera sample's subpath and strategies (estimate())
    VCMSettings set_;
    FileLoc loc_;
    bool merging_ = false, connecting_ = true;
    Float radius1_ = 0, radius_ = 0;
    MergeKernel kernel_;
    Bounds2i bounds_;
    std::vector<LightVertex> vertices_;
    std::vector<uint32_t> pathStart_;  // light subpath j: vertices_[pathStart_[j], pathStart_[j+1])
    PhotonGrid grid_;
    std::string skipped_;
    mutable std::atomic<uint64_t> nMerges_{0}, nConnections_{0};
    uint64_t nLightVertices_ = 0;
    int passes_ = 0;
};

}  // namespace gradus
