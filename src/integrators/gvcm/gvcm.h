// Gradient-domain vertex connection and merging (Sun et al. 2017,
// gradient-domain-vcm.md), Algorithm 1 on G-BDPT (integrators/gbdpt/) and
// VCM's light-vertex store, hash grid and recursive MIS (integrators/vcm/).
//
// One iteration = one pass = one sample per pixel:
//   1. light pass (lines 1-8): one light subpath per sampled pixel (RNG keyed
//      by (seed, pass, subpath), so any subpath can be regenerated exactly),
//      classified like G-BDPT's (near-specular vertices marked specular),
//      its connectable vertices stored as VCM's 128-byte LightVertex records
//      and a hash grid built over them;
//   2. camera pass (lines 9-25): G-BDPT's sample (base camera subpath, its
//      four shifts, connections with their light-tracing shifts) with VCM's
//      MIS sums (merging terms at connectable vertices, eta = pi r^2 N per
//      vertex, merge_kernel.h), then
//      merges at every connectable camera vertex z_u with each light vertex
//      y_m within r_u (Eq. 5; the base weight is VCM's, Eq. 13) and their
//      offsets per neighbour:
//        case 1 (Sec. 4, u >= c, the shift's reconnection vertex): the offset
//          shares z_u, the kernel and the light vertex; Eqs. 16-17 with the
//          offset camera throughput (which carries |T'| in the base's measure);
//        case 2 (u = b): the offset is the physical path y_0 .. y_d, y'_{d+1}
//          .. y'_s, z'_b .. z'_0 with y_d the last connectable vertex before
//          the photon: an empty chain (y_s connectable, Eq. 18) reconnects
//          y_s to z'_b; a chain of ideal specular vertices is walked (JM12)
//          from y_d to z'_b keeping its half-vectors, reversibility checked
//          (Eqs. 19-20, J_y = 1: Dirac chains have no interior variables in
//          the generalised-geometry measure). The offset estimate is
//          f(x')/p'(x*) = beta_L(y_m) T(x')/T(x) f(z'_b) beta'_C / eta, with
//          T = E(y_d -> chain) G~ prod f|cos| the chain's contribution from
//          y_d to the photon's position (G~: solid angle at y_d per area at
//          the photon end, ChainSolidAnglePerArea).
//        Case 2 costs a walk (and its reversibility walk) per photon and
//          offset, so at most `case2budget` photons per merge vertex and offset
//          take it: K of the n found, by systematic sampling (each with
//          probability K/n), their differences weighted n/K; an unbiased
//          estimate of the sum over all n whose cost does not grow with the
//          photons in the kernel (the primal and case 1 keep every photon).
//      Gradient weights: Eq. 23 as CombinedWeight(w_x, w_y, rho) with w_x, w_y
//      the base's and the offset's VCM weights (Eqs. 21-22) and rho = |T'|
//      p_y / p_x (the camera shift's rho, times the photon density ratio in
//      case 2, times eta_y / eta_x: each merge's density with its own kernel,
//      as in w_y); a failed offset falls back to a zero offset with the base's
//      weight (as G-BDPT).
// Separated light (gbdpt.h, gradient_film.h): s = 0 paths and G-PM's chain
// emission through Dirac scattering only take no gradients and are added
// after the reconstruction.
// G-PM (mode "mergeonly", Sec. 7): no light subpath per camera sample and no
// connections; merges at the first connectable camera vertex z_b only and
// emission through specular chains, every weight 1 (the unused strategies'
// densities are 0), gradients with CombinedWeight(1, 1, rho).
//
// Radius: r_i = `radius` or `radiusscale` times the median pixel footprint
// (vcm.h), r_i^2 = r_1^2 i^(alpha - 1) for the global iteration i. Sec. 6 as
// options (merge_kernel.h; off by default, as measured in bench/gvcm):
// `footprint path` takes each path's pixel width at its first connectable
// camera vertex z_b times `radiusscale` (at most 2 r_i), `kernel adaptive`
// shrinks the radius by 0.5^(10 tau) per vertex after z_b. An offset's estimate
// keeps the base's kernel (the one that found the photon); its weight takes
// the offset path's own radii (what its own pixel would have used, Eq. 22).
// Without specular or near-specular surfaces no merging is done (gvcm is then
// gbdpt; the statistics say so).
//
// Limitations (see statistics): the footprint follows the chain's unfolded
// length (a ray differential without the specular vertices' curvature);
// case 2 falls back (zero
// offset, base weight) for photons whose chain starts at an infinite light,
// contains a glossy (near-specular, non-Dirac) vertex, or whose offset target
// z'_b lies on another surface than the photon (the walk keeps its end on one
// surface), and when the walk fails. A case-2 offset's weight w_y takes the
// offset's own light-side densities (the direction at y_d and the walked chain
// change them from y_{d-1} on, so the photon's stored B_m does not apply):
// MergeWeight's O(m + u) sums on the offset path (case2Weight).
//
// Parameters (bidirectional family, bidir_family.h; MIS the balance heuristic):
//   integer maxdepth 5               maximum path depth (edges - 1)
//   string lightsamplestrategy "power"  uniform | power | spatial (= power)
//   integer rrdepth 3                Russian roulette after this many bounces (-1: off)
//   integer pixelbounds []           accepted (use --cropwindow)
// (gradient family, gradient_params.h):
//   float shiftthreshold 0.001       roughness below which a vertex is not connectable (Sec. 2.4)
//   string reconstruction "hybrid"   hybrid | l1 | l2 | weighted: the image in the unprefixed R,G,B
//   float alpha 0.2                  screened-Poisson primal weight
//   string pixelfilter "film"        film: the scene's PixelFilter; box: own pixel only
// (gbdpt, gbdpt.h; they apply to the connections):
//   string shift "manifold"          manifold | halfvector
//   string manifoldsolver "newton"   newton | ceres
//   bool lighttracing true           false: no light-tracing paths (in no MIS sum either)
//   string mis "combined"            combined (Eq. 8) | simple (Eq. 9); merges always use Eq. 23
//   integer separatedsamples 0       K extra Dirac-only camera walks per sample for the separated
//                                    light (gradient_family.h; scenes without media)
// (gvcm):
//   string mode "vcm"                vcm (G-VCM) | mergeonly (G-PM)
//   float radius 0                   initial merging radius in scene units (0: from the pixel footprint)
//   float radiusscale 1              the footprint radius in pixels (radius 0)
//   float radiusalpha 0.75           radius reduction r_i^2 = r_1^2 i^(alpha - 1) (0.9 with radiusschedule "radius")
//   string radiusschedule "area"     area | radius: r_i = r_1 i^(alpha - 1) (the G-VCM authors' code; vcm.h)
//   bool normalfilter false          merge only photons whose geometric normal agrees with the camera
//                                    vertex's (dot >= 0.1; the authors' code, merge_kernel.h), in G-VCM and G-PM
//   string kernel "fixed"            fixed | adaptive (Sec. 6, above)
//   float kernelshrink 10            adaptive: r_j = 0.5^(kernelshrink tau) r_{j-1}
//   string footprint "median"        median | path (Sec. 6, above)
//   integer case2budget 1            case-2 shifts per merge vertex and offset: K of the n photons
//                                    found, by systematic sampling, differences weighted n/K (0: all;
//                                    a merge's walks then no longer grow with the photons in the
//                                    kernel; bench/gvcm/RESULTS.md)
#pragma once
#include <atomic>
#include <string>
#include <utility>
#include <vector>

#include "integrators/common/photon_grid.h"
#include "integrators/gbdpt/gbdpt.h"
#include "integrators/vcm/vcm.h"

namespace gradus {

struct GVCMSettings : GBDPTSettings, MergeRadiusSettings {
    bool mergeOnly;
    int case2Budget;  // photons shifted through z'_b per merge vertex (0: all)
};

class GVCMIntegrator : public GBDPTIntegrator {
  public:
    explicit GVCMIntegrator(const EntityDesc &desc);
    std::string name() const override { return "gvcm"; }
    // Its merges count surface photons only (README, media); gbdpt's media support is not inherited.
    bool rendersMedia() const override { return false; }
    void preprocess(const Scene &scene, Film &film) override;
    int samplesPerPass(const RenderOptions &) const override { return 1; }  // one iteration = 1 spp
    void runPass(PassContext &ctx) override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    std::string statistics() const override;
    Float radiusAt(int iteration) const {
        return VCMRadius(radius1_, gset_.radiusAlpha, iteration, gset_.schedule);
    }

  protected:
    void addStrategies(const CameraState &st, GradientSample *out) const override;

  private:
    friend struct GVCMTestAccess;  // tests/gvcm: the estimator's pieces
    GVCMIntegrator(const EntityDesc &desc, const GVCMSettings &set);
    struct Offset;     // defined below (after Counter)
    struct Case2Base;
    struct SampleMerges;
    struct VertexMerges;
    struct PhotonSubpath;
    using Found = std::vector<std::pair<uint32_t, Spectrum>>;
    void lightPass(PassContext &ctx);
    // Light subpath j of the current pass, regenerated (its first maxLight vertices) and classified.
    void regenerate(uint32_t j, int maxLight, Arena &arena, ShiftSubpath *L) const;
    Spectrum emitFrom(const ShiftSubpath &L, int d, const Vec3 &dir, Float *pdf) const;
    // The stages of addStrategies, in its order: G-PM's emission through a
    // specular chain at z_u; the merges at z_u (false: no kernel there), the
    // kernel's photons, and per photon the base and each offset (case 1 or 2).
    void chainEmission(const CameraState &st, int u, GradientSample *out) const;
    bool mergesAt(SampleMerges &sm, int u, GradientSample *out) const;
    void gatherPhotons(const PathVertex &zu, const BSDF &bu, int u, Float etaU, Found *found) const;
    void mergePhoton(SampleMerges &sm, VertexMerges &vm, uint32_t idx, const Spectrum &f, bool chosen,
                     GradientSample *out) const;
    // Eq. 13 (vcm.h) for the merge of light vertex y_m = lv at camera vertex z
    // (from zPrev; BSDF bz) with z's camera terms t: the base's w_x, and a
    // case-1 offset's w_y with the offset's own terms (Eq. 22).
    static Float mergeWeight(const VCMCameraTerms &t, const PathVertex &z, const PathVertex &zPrev, const BSDF &bz,
                             const LightVertex &lv, const VCMWeights &W);
    // The offsets' B_u and eta (whole subpath), camera terms at z'_u: computed when first needed.
    const Float *offsetB(SampleMerges &sm, int k) const;
    const VCMCameraTerms *offsetTerms(SampleMerges &sm, VertexMerges &vm, int k) const;
    // Case 1 (header comment) for the shift sh at z_u: bu the BSDF at z_u, f its
    // value for the base, w the camera ray weight, etaX the base's eta at z_u;
    // terms: the offset's camera terms at z'_u (nullptr: no connections, weight 1).
    bool case1(const CameraShift &sh, int u, const BSDF &bu, const LightVertex &lv, const Spectrum &f, Float w,
               Float etaX, const VCMCameraTerms *terms, const VCMWeights &W, Offset *o) const;
    // Case 2 of offset k: the photon's subpath regenerated once per merge, then case2Base and case2.
    bool case2Offset(SampleMerges &sm, VertexMerges &vm, int k, uint32_t idx, PhotonSubpath *ph, Offset *o) const;
    // Case 2 (header comment): the base's half, once per photon y_m = L.v[m]
    // (false: every offset falls back, cb->failure says why), then each
    // offset (false: fall back). terms: the offset's camera terms at z'_u
    // (nullptr: no connections, weight 1); etaX: the base's eta at z_u (the
    // kernel that found the photon). The offset's f excludes the camera ray weight.
    bool case2Base(const ShiftSubpath &L, int m, Arena &arena, Case2Base *cb) const;
    bool case2(const ShiftSubpath &L, const Case2Base &cb, const CameraShift &sh, int u, const LightVertex &lv,
               const VCMCameraTerms *terms, Float etaX, Arena &arena, Offset *o) const;
    // w_y of a case-2 offset (Eq. 13 on the offset path: y_0 .. y_d, the walked interior of
    // k vertices (walked; null for k = 0), z'_u .. z'_0; pY: the offset's directional density at y_d).
    Float case2Weight(const ShiftSubpath &L, int d, int k, const WalkedInterior *walked, Float pY,
                      const CameraShift &sh, int u, Arena &arena) const;

    GVCMSettings gset_;
    bool merging_ = false;
    Float radius1_ = 0, radius_ = 0;
    MergeKernel kernel_;
    Bounds2i bounds_;
    std::vector<LightVertex> vertices_;
    std::vector<uint32_t> pathStart_;
    PhotonGrid grid_;
    size_t gridBytes_ = 0;  // the last pass's grid (statistics, after finish() released it)
    uint64_t lightKey_ = 0;
    int lightPassIndex_ = 0, passes_ = 0;
    uint64_t nLightVertices_ = 0;
    std::string skipped_;
    // Counters (relaxed atomics; order-independent sums).
    enum Counter {
        Merges, Case1, Case1Shifted, Case2, Case2Skipped, Case2Empty, Case2Chain, Case2Shifted, FallbackShift, FallbackInfinite,
        FallbackGlossy, FallbackLong, FallbackWalk, FallbackBlocked, FallbackMismatch, Regenerated, NumCounters
    };
    mutable std::atomic<uint64_t> counters_[NumCounters] = {};
    mutable std::atomic<uint64_t> walkStatus_[size_t(ManifoldStatus::Count)] = {};
    void count(Counter c, uint64_t n = 1) const { counters_[c].fetch_add(n, std::memory_order_relaxed); }

    // An offset merge: value f(y)|T'|/p(x) (times the camera weight), its VCM
    // weight and rho = |T'| p_y / p_x (Eq. 23 through CombinedWeight).
    struct Offset {
        Spectrum f;
        Float w = 1, rho = 1;
    };
    // The base's half of a case-2 offset (case2Base).
    struct Case2Base {
        int d = 0, k = 0;
        ChainInterior in;      // the chain's interior (k > 0)
        ManifoldChain chain;   // y_d .. y_m (k > 0)
        Vec3 dirX;             // direction at y_d
        Float gX = 0, pX = 0;  // G~ and y_d's directional density
        Spectrum fcosX{1};     // prod f|cos| of the chain's Dirac vertices
        Float probX = 1;       // prod of their lobe probabilities
        Spectrum tX{0};        // T(x) = E(y_d -> dirX) fcosX G~
        Counter failure = NumCounters;  // NumCounters: none
    };
};

}  // namespace gradus
