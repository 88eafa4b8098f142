// The mutations of path-space MLT (Veach and Guibas 1997; Veach 1997,
// Ch. 11) on pmlt::Path, each with its acceptance probability
// a(x -> y) = min(1, I(y) T(y -> x) / (I(x) T(x -> y))) (Metropolis-Hastings).
//
// Bidirectional mutation: deletes the vertices [a, a + n_d)
// and inserts n_a new ones, t' sampled from the kept camera prefix and
// s' = n_a - t' from the kept light suffix, joined by a shadow-tested edge.
// T(x -> y) = P_d(n_d) P_pos(a) P_a(n_a) sum_{t'} P_split(t') p_{t'}(y), the sum
// over every split that could have produced the new vertices,
// p_{t'} the product of their densities in that technique (path.h).
//
// Perturbations (lens, caustic, multi-chain) regenerate a run of vertices from a
// perturbed film position or direction, tracing specular vertices with the
// lobe (reflection or transmission) the old path took. The perturbation
// kernels are symmetric (film offset of density ~ 1/r in [r1, r2]; direction
// offset of density ~ 1/theta in [theta1, theta2], uniform azimuth), so
// T(x -> y) / T(y -> x) = D(y) / D(x), D the density of the regenerated
// vertices given the perturbed variables: the camera's density of x_1 per
// film area, one solid angle -> area conversion per perturbed direction and
// p_E / P_lobe (p_L / P_lobe) per vertex traced through a specular one.
//   lens:       paths E S* D (D | L) ...: regenerate x_1 .. x_c, connect x_c - x_{c+1}
//   multichain: lens, then at every D followed by S perturb the old outgoing
//               direction and trace the next chain, up to a connectible pair
//   caustic:    paths E D S+ (D | L) ...: perturb the direction at x_c towards
//               x_{c-1}, trace the chain back to x_1, connect x_1 to the lens
//   manifold:   paths E S* D S+ (D | L) ... (Jakob and Marschner 2012): the film
//               offset of the lens perturbation moves x_b (after the eye chain
//               S*), then a manifold walk moves the second chain S+ so that it
//               joins x_b to the unchanged x_c (manifold_perturbation.cpp)
// A mutation applies to a path by its pattern of specular vertices alone,
// which every perturbation keeps: the selection probabilities cancel.
#pragma once
#include <cstdint>
#include <vector>

#include "core/arena.h"
#include "integrators/manifold/manifold_scene.h"
#include "integrators/pmlt/path.h"
#include "samplers/sampler.h"

namespace gradus::pmlt {

enum class MutationType { Bidirectional, Lens, Caustic, MultiChain, Manifold };
constexpr int kMutationTypes = 5;
const char *MutationName(MutationType t);

struct MutationSettings {
    int maxDepth = 5;
    Float lensR1 = 0.1, lensR2 = 0;      // film offsets in pixels (r2 0: 10% of the film's larger side)
    Float theta1 = 1e-4, theta2 = 0.1;  // direction offsets in radians
    const EmbreeManifoldScene *mscene = nullptr;  // manifold perturbation (none: not applicable)
    // G-MLT's shift: a non-Dirac vertex whose BSDF's roughness is below this is
    // near-specular (gradient-domain-mlt.md Sec. 5, Fig. 5a; ShiftClassOf).
    Float shiftThreshold = kDefaultShiftThreshold;
};

// How G-MLT's shift treats a vertex (gradient-domain-mlt.md Sec. 5, Fig. 5a):
// Dirac (scatters through a Dirac lobe: VERTEX_DELTA), NearSpecular (a non-Dirac
// surface vertex whose BSDF has a roughness in (0, threshold): treated as
// specular, its half vector kept) or Rough (everything else, also camera and
// emitter vertices and BSDFs that mix a Dirac lobe with rough ones).
enum class ShiftClass { Rough, Dirac, NearSpecular };
ShiftClass ShiftClassOf(const PathVertex &v, const BSDF &b, Float threshold);

// Counters a proposal adds to (manifold walks).
struct MutationStats {
    int64_t walks = 0, walkFailures = 0;
    int64_t nearSpecularShifts = 0;  // G-MLT shifts that moved a near-specular vertex (Fig. 5a)
};

// A state of a chain: the path, its evaluation and its BSDFs (which point
// into an arena that outlives the state's use).
struct State {
    Path x;
    PathEval e;
    std::vector<BSDF> bsdf;
};

enum class ProposalResult { Proposed, NotApplicable, Zero };

class Mutator {
  public:
    Mutator(const BidirContext &ctx, const FilmDomain &film, const MutationSettings &s);
    // Proposes y from x with the mutation `type`; on Proposed, *ratio =
    // I(y) T(y -> x) / (I(x) T(x -> y)) > 0 for this mutation (the acceptance
    // probability is min(1, ratio x the selection probability ratio, below))
    // and y holds the new path (its new BSDFs allocated in `arena`). Zero:
    // the proposal carries nothing or its reverse move is impossible.
    ProposalResult propose(MutationType type, const State &x, Sampler &u, Arena &arena, State *y, double *ratio,
                           MutationStats *stats = nullptr) const;
    // G-MLT's shift (gradient-domain-mlt.md Sec. 5.1): the path moved to film
    // position pFilm with x_0 held: the eye chain S_e re-traced to x_b', then
    // x_b' joined to x_{b+1} (no second chain) or the second chain S_m walked
    // so that x_c onward stays (manifold perturbation). S_e and S_m are the
    // vertices of class Dirac or NearSpecular (ShiftClassOf, Fig. 5a): the eye
    // chain follows x's lobe at a Dirac vertex and copies x's half vector at a
    // near-specular one; the walk keeps every half vector of S_m. On Shifted,
    // y is the offset with F, I > 0 and the camera side's densities evaluated
    // on its changed prefix (EvaluateChangedPrefix; not a chain state: no light
    // side) and *jacobian = |d mu(y) / d mu(x)|
    // in the delta-free measure of path.h: D(x) / D(y), D the density of the
    // moved vertices per film area and per unit of the kept half vectors
    // (G-MLT Eqs. 12-15). Failures depend on the path's pattern, an offset
    // with x's vertex classes and a reversible walk only, so a pair that fails
    // from one side fails from the other (Sec. 4.2.2).
    enum class ShiftStatus { Shifted, Blocked, Mismatch, WalkFailed, Unsupported, OffFilm };
    ShiftStatus shift(const State &x, Point2 pFilm, Arena &arena, State *y, double *jacobian,
                      MutationStats *stats = nullptr) const;
    // Whether `type` applies to the path (its pattern of specular vertices and
    // emitter; perturbations keep it, the bidirectional mutation always applies).
    bool applies(MutationType type, const Path &x) const;
    // Probability of selecting `type` at x among the applicable mutations with
    // these weights (a mutation that changes the pattern multiplies its ratio
    // by selectionProbability(y) / selectionProbability(x)).
    Float selectionProbability(MutationType type, const Path &x, const Float *weights) const;

    // Transition density pieces of the bidirectional mutation (tests).
    Float deletionProbability(int n, int nd) const;
    int positionCount(int n, int nd) const;
    Float additionProbability(int n, int nd, int a, int na) const;
    // The rules behind them (tests compare the closed forms with them).
    bool allowedPosition(int n, int nd, int a) const;
    bool allowedAddition(int n, int nd, int a, int na) const;

  private:
    ProposalResult bidirectional(const State &x, Sampler &u, Arena &arena, State *y, double *ratioOut) const;
    // The bidirectional mutation's stages (mutations.cpp): the move's choices,
    // the camera side (kept prefix and new vertices), the light side (new
    // vertices in light order and the kept suffix), the join, the ratio.
    struct BidirMove;
    struct LightSide;
    bool chooseBidirMove(int n, Sampler &u, BidirMove *m) const;
    int pickDeletion(int n, Float r) const;
    int pickAddition(int n, int nd, int a, Float r) const;
    bool buildCameraSide(const State &x, const BidirMove &m, Sampler &u, Arena &arena, State *y) const;
    bool buildLightSide(const State &x, const BidirMove &m, Sampler &u, Arena &arena, LightSide *l) const;
    bool emitLightVertex(const BidirMove &m, Sampler &u, PathVertex *e, Vec3 *dir) const;
    bool traceVertices(PathVertex from, Vec3 dir, int until, bool lastMayEscape, TransportMode mode, Sampler &u,
                       Arena &arena, std::vector<PathVertex> *vs, std::vector<BSDF> *bs) const;
    bool joinSides(const State &x, const BidirMove &m, const LightSide &l, State *y) const;
    ProposalResult bidirRatio(const State &x, const State &y, const BidirMove &m, double *ratioOut) const;
    ProposalResult lens(const State &x, bool multiChain, Sampler &u, Arena &arena, State *y, double *ratioOut) const;
    ProposalResult caustic(const State &x, Sampler &u, Arena &arena, State *y, double *ratioOut) const;
    ProposalResult manifold(const State &x, Sampler &u, Arena &arena, State *y, double *ratioOut,
                            MutationStats *stats) const;
    // The eye chain x_1 .. x_b re-traced along `ray` with x's specular lobes
    // (lens, multi-chain and manifold perturbations, the G-MLT shift); a
    // non-Dirac vertex before x_b (G-MLT's near-specular ones) gets x's half
    // vector, and *hvJacobian (when given) the product of those copies'
    // |d omega_y / d omega_x| (shift.h).
    bool traceEyeChain(const State &x, int b, const Ray &ray, Arena &arena, State *y, SurfaceInteraction *siB,
                       double *hvJacobian = nullptr) const;
    // A camera ray through a perturbed film position (lens perturbation's
    // kernel) and a uniform lens point.
    bool perturbedRay(const State &x, Sampler &u, Ray *ray) const;
    // The manifold move of a path of ManifoldPattern (b, c): the eye chain
    // re-traced along `ray`, the second chain walked to x_c (its non-Dirac
    // vertices, G-MLT's near-specular ones, keep their half vectors).
    // *jacobian = [K(y) / D_b(y)] / [K(x) / D_b(x)] (manifold_perturbation.cpp).
    // prefixOnly (the shift): y evaluated on its changed prefix x_0 .. x_c only
    // (EvaluateChangedPrefix: F and the camera side; y is not a chain state).
    ProposalResult manifoldMove(const State &x, int b, int c, int endGeom, const Ray &ray, Arena &arena, State *y,
                                double *jacobian, MutationStats *stats, bool prefixOnly = false) const;
    Float bidirDensity(const State &s, int a, int nd, int na, int n) const;

    const BidirContext &ctx_;
    FilmDomain film_;
    MutationSettings set_;
    std::vector<double> deleteNorm_;  // per path size n: sum of the deletion weights with a position
    std::vector<double> addPrefix_;   // prefix sums of the addition weights over delta = na - nd
    int addOffset_ = 0;               // addPrefix_[delta + addOffset_] = sum of weights below delta
};

// Traces from `from` along dir and makes the vertex hit (an infinite-light
// vertex for an escaped ray when allowed and the scene has infinite lights);
// si, when given, receives the hit's interaction.
bool Trace(const BidirContext &ctx, const PathVertex &from, const Vec3 &dir, Arena &arena, bool allowInfinite,
           PathVertex *v, BSDF *b, SurfaceInteraction *si = nullptr);
// Follows the specular lobe (reflection or transmission) that x took at its
// vertex j, at the new vertex v arrived at from wo; marks v specular.
bool FollowSpecular(const Path &x, int j, PathVertex *v, const BSDF &b, const Vec3 &wo, TransportMode mode,
                    Vec3 *wi);

// Path patterns of the perturbations (indices as in mutations.h / manifold_perturbation.cpp).
// Lens: true when x_c is followed by a specular vertex (multi-chain), c and m set.
bool LensPattern(const Path &x, int *c, int *m);
bool CausticPattern(const Path &x, int *c);
bool ManifoldPattern(const Path &x, const EmbreeManifoldScene *mscene, int *b, int *c, int *endGeom);
// The same pattern with the vertices of class Dirac or NearSpecular
// specular (G-MLT's shift; the above: VERTEX_DELTA alone).
bool ManifoldPattern(const Path &x, const EmbreeManifoldScene *mscene, const ShiftClass *cls, int *b, int *c,
                     int *endGeom);

// Densities of a state's vertices per film area (x_1 .. x_b, the eye chain
// and its end: p_E(x_1), then p_E / P_lobe through each specular vertex) and
// of x_{b+1} .. x_c traced from x_b with a unit solid-angle density
// (manifold_perturbation.cpp). Through a non-Dirac vertex of either chain
// (G-MLT's near-specular ones) the next vertex has a unit solid-angle density.
double EyeDensity(const State &s, int b);
double TraceDensity(const State &s, int b, int c);

// Builds the BSDFs of every vertex of x (Radiance mode) in arena.
void BuildBSDFs(const BidirContext &ctx, const Path &x, Arena &arena, std::vector<BSDF> *bsdf);

}  // namespace gradus::pmlt
