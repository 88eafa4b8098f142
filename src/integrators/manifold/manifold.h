// Specular-chain solver: manifold perturbation (Jakob & Marschner 2012, "JM12")
// as used by the gradient-domain shifts of G-MLT (Lehtinen et al. 2013, Sec. 5),
// G-BDPT (Manzi et al. 2015, Sec. 3.1) and G-VCM (Sun et al. 2017, Sec. 4).
//
// A chain is x_0, x_1 .. x_k, x_{k+1}: two endpoints and k interior vertices that
// are specular or near-specular (glossy below the shift threshold). Each interior
// vertex carries the constraint
//     c_i = [s_i . H_i, t_i . H_i] - o_i,        H_i = +-normalize(eta_a w_i + eta_b w_o)
// (JM12 Sec. 4.1: the generalised half-vector projected on the tangent frame),
// with w_i, w_o the unit directions towards x_{i-1}, x_{i+1}, eta_a / eta_b the
// indices of refraction on their sides (1 for reflection) and H oriented to the
// shading normal's side. o_i = 0 for an ideal specular configuration; for a glossy
// vertex o_i is the half-vector offset that a manifold walk keeps fixed.
//
// The integrators reach the walk through manifold/chain_shift.h (ManifoldSettings,
// BuildChain, ShiftChain: build -> walk -> reversibility -> evaluation). What
// each computes with it (all quantities in double):
//   G-BDPT (camera-subpath shift between diffuse vertices b and c): build the base
//     chain x_b .. x_c with MakeChain, then ManifoldWalk(scene, base, offset x_b,
//     target = base x_c). Jacobian of the shift: ShiftJacobianFactor on the base and
//     on the offset (G-MLT Eqs. 13-15 / G-BDPT Eq. 5); the ratio offset/base is
//     |dy/dx|.
//   G-VCM (photon perturbation, Sec. 4 "y_s is unconnectable"): base chain y_d ..
//     y_{s+1}; ManifoldWalk(scene, base, y_d, target = z_b^off); CheckReversible for
//     the reversibility test; J_y of Eq. 20 = HalfVectorJacobian(base) /
//     HalfVectorJacobian(offset).
//   G-MLT (shift and manifold-perturbation mutation): same walk; Eq. 14 factors
//     from ShiftJacobianFactor; GeneralizedGeometryTerm for Eq. 15.
//
// The walk re-traces the chain with rays from the (possibly moved) start vertex,
// reconstructing each outgoing direction from the stored half-vector, so every
// vertex lies on real geometry and the half-vector constraints hold exactly; the
// only unknown is the position of x_1, adjusted until x_{k+1} reaches the target.
// Failure is always explicit (ManifoldStatus), never a silently wrong vertex.
//
// Two tangent frames per vertex. The constraint measures H in the shading frame
// (s, t) around the shading normal n. A vertex moves in its geometric tangent
// plane (ps, pt: orthonormal, around the geometric normal ng), where the surface
// really is: on a triangle with interpolated normals the two planes differ (a
// few degrees on typical meshes), and a step in the shading plane leaves the
// triangle. Derivatives with respect to a vertex position are per unit length
// along ps and pt, so 2x2 determinants of them are area ratios.
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "core/geometry.h"

namespace gradus {

// Differential geometry at a chain vertex. n: unit shading normal; ng: unit
// geometric normal (zero: the same as n); dpdu/dpdv: any (not necessarily
// orthonormal) basis of the geometric tangent plane; dndu/dndv: derivatives of
// the unit shading normal n along the same parameters (SurfaceInteraction's
// shading.dnhatdu, not pbrt-v3's dndu). eta*: index of refraction on each side of n.
struct ManifoldSurfacePoint {
    Point3 p;
    Normal3 n;
    Normal3 ng;
    Vec3 dpdu, dpdv;
    Vec3 dndu, dndv;
    Float etaInterior = 1, etaExterior = 1;
    int primitiveId = -1;  // a different id on re-trace means the vertex left its surface
};

// Unit geometric normal of a surface point, on the shading normal's side.
inline Vec3 GeometricNormal(const ManifoldSurfacePoint &sp) {
    Vec3 ng(sp.ng), n(sp.n);
    if (!(ng.lengthSquared() > 0)) return n;
    return Dot(ng, n) < 0 ? -ng : ng;
}

// Implemented by the renderer (Embree, hits refined in double) and by the tests
// (analytic shapes). intersect() must ignore the surface the ray starts on at
// t ~ 0 (the usual ray epsilon) and return false on a miss.
class ManifoldScene {
  public:
    virtual ~ManifoldScene() = default;
    virtual bool intersect(const Ray &r, ManifoldSurfacePoint *hit) const = 0;
    virtual bool visible(const Point3 &a, const Point3 &b) const = 0;
    // Diagonal of the bounds of a surface (primitiveId): a predicted step longer
    // than this leaves it. Infinity when unknown.
    virtual Float extent(int /*primitiveId*/) const { return Infinity; }
};

// 2x2 matrix [a b; c d]; columns are motion along a vertex's (s, t) tangent axes.
struct Mat2 {
    Float a = 0, b = 0, c = 0, d = 0;
    static Mat2 Identity() { return {1, 0, 0, 1}; }
    Float det() const { return a * d - b * c; }
    Mat2 inverse() const {
        Float inv = 1 / det();
        return {d * inv, -b * inv, -c * inv, a * inv};
    }
    Mat2 operator*(const Mat2 &m) const {
        return {a * m.a + b * m.c, a * m.b + b * m.d, c * m.a + d * m.c, c * m.b + d * m.d};
    }
    Vec2 operator*(const Vec2 &v) const { return {a * v.x + b * v.y, c * v.x + d * v.y}; }
    Mat2 operator+(const Mat2 &m) const { return {a + m.a, b + m.b, c + m.c, d + m.d}; }
    Mat2 operator-(const Mat2 &m) const { return {a - m.a, b - m.b, c - m.c, d - m.d}; }
    Mat2 operator-() const { return {-a, -b, -c, -d}; }
    Float maxAbs() const {
        return std::max(std::max(std::abs(a), std::abs(b)), std::max(std::abs(c), std::abs(d)));
    }
};

struct ManifoldVertex {
    ManifoldSurfacePoint sp;
    bool reflect = true;    // interior vertices: reflection or refraction along this chain
    bool specular = true;   // ideal (Dirac) vertex: eliminated from |dx/dO| (JM12, G-MLT Sec. 5.2)
    // Tangent frame s = normalize(frameRef - n (n . frameRef)), t = n x s. The
    // reference axis is fixed per chain position and copied to shifted chains, so
    // base and offset measure half-vectors in the same frame field (this makes
    // walks exactly reversible also for glossy vertices).
    Vec3 frameRef;
    Vec3 s, t;          // derived: orthonormal shading tangent frame (measures H)
    Vec3 ps, pt;        // derived: orthonormal axes of the geometric tangent plane (vertex motion)
    Vec3 dnds, dndt;    // derived: derivative of the unit shading normal along ps and pt
    Vec2 o;             // interior vertices: half-vector offset (constraint target)
};

constexpr int kMaxManifoldVertices = 12;  // endpoints included

// Fixed capacity, no heap allocation (one per walk per thread).
struct ManifoldChain {
    int size = 0;
    std::array<ManifoldVertex, kMaxManifoldVertices> v;
    int interiorCount() const { return size - 2; }
    const ManifoldVertex &front() const { return v[0]; }
    const ManifoldVertex &back() const { return v[size - 1]; }
};

// Fill the derived fields of a vertex. frameRef == nullptr: use dpdu.
void SetupManifoldVertex(ManifoldVertex *v, const ManifoldSurfacePoint &sp,
                         const Vec3 *frameRef = nullptr);

// Build a chain from surface points (start, interior..., end). reflect/specular
// give the interior vertex types (index i refers to chain vertex i+1). The
// half-vector offsets o_i are computed from the positions. Returns false if the
// chain is too long or degenerate (coincident vertices, wrong side, eta ratio 1).
bool MakeChain(const ManifoldSurfacePoint *points, int count, const bool *reflect,
               const bool *specular, ManifoldChain *chain);

// Constraint value at interior vertex i (1 <= i <= k) without the offset, i.e.
// the projected half-vector [s.H, t.H]. ok = false on a degenerate configuration.
Vec2 ProjectedHalfVector(const ManifoldChain &c, int i, bool *ok = nullptr);

// Analytic derivative blocks of the projected half-vector at vertex i with
// respect to x_{i-1}, x_i, x_{i+1}, each moving along its motion axes (ps, pt)
// (JM12 Sec. 4.2, the rows of the block-tridiagonal matrix).
bool ConstraintDerivatives(const ManifoldChain &c, int i, Vec2 *value, Mat2 *dPrev, Mat2 *dSelf,
                           Mat2 *dNext);

// dx_1/dx_{k+1} (2x2, motion axes) with x_0 fixed and all constraints held,
// by a block-tridiagonal (block Thomas) solve. Identity for k = 0.
bool FirstVertexDerivative(const ManifoldChain &c, Mat2 *dx1dxEnd);

// dx_1/dx_0 (x_{k+1} fixed) and dx_1/dx_{k+1} (x_0 fixed) from one assembly of
// the constraint matrix; false for k = 0 or a singular matrix.
bool FirstVertexDerivatives(const ManifoldChain &c, Mat2 *dx1dx0, Mat2 *dx1dxEnd);

// det of the 2k x 2k constraint matrix dc/dx_{1..k} (endpoints fixed); 1 for k = 0.
Float ConstraintDeterminant(const ManifoldChain &c);

// |dx/dO| of the half-vector reparameterisation of the interior vertices with both
// endpoints fixed (G-MLT Eq. 13-14, G-VCM Eq. 20). Ideal specular vertices are
// eliminated (not integration variables): |dx_g/dO_g| = |det A_pp| / |det A|
// (Schur complement). 1 for k = 0; 0 if the matrix is singular.
Float HalfVectorJacobian(const ManifoldChain &c);

// Generalised geometry term G(x_0 <-> ... <-> x_{k+1}) (JM12): the projected
// solid angle at x_0 per unit area at x_{k+1}, with all half-vectors held:
// |cos th_0| |cos th_1| / |x_1 - x_0|^2 * |det dx_1/dx_{k+1}|, th_1 against x_1's
// geometric normal (area measure). For a camera endpoint, x_0's normal is the
// camera axis.
Float GeneralizedGeometryTerm(const ManifoldChain &c);

// G-MLT Eqs. 14-15 (G-BDPT Eq. 5): per-path factor
//   F = |dx_b/ds| |dx/dO| = cos^4(th_0) / G(x_0 <-> ... <-> x_b) * |dx/dO|_eye * |dx/dO|_second
// for a pinhole camera x_0 (normal = camera axis; s on the image plane at unit
// distance). eyeChain: x_0 .. x_b; secondChain: x_b .. x_c or nullptr when empty.
// The shift Jacobian |d y / d x| is F(offset) / F(base).
Float ShiftJacobianFactor(const ManifoldChain &eyeChain, const ManifoldChain *secondChain);

// Why a walk ended. A walk that fails reports the reason that ended it: the
// cap, or the trial failure that drove the step below its floor.
enum class ManifoldStatus : uint8_t {
    Success = 0,
    LeftSurface,              // a ray missed all geometry
    Occluded,                 // a ray hit a primitive other than the chain's one
    TotalInternalReflection,  // refraction impossible with the fixed half-vector
    WrongSide,                // reconstructed direction on the wrong side of the surface
    Degenerate,               // singular derivatives, coincident vertices, eta ratio 1
    IterationCap,             // maxIterations trial steps without converging
    Fold,                     // the trials crossed a fold (det dx_1/dx_end changed sign)
    StepFloor,                // trials traced but did not approach the target down to minStep
    StepLeavesSurface,        // the predicted step of x_1 is longer than its surface (ManifoldScene::extent)
    NotReversible,            // walking back did not return the base chain
    InvalidInput,             // too long, or endpoints not usable
    Count
};
const char *ToString(ManifoldStatus s);

enum class ManifoldSolver : uint8_t {
    Newton,     // direct Newton on x_1 with block-tridiagonal derivatives and JM12 step control
    CeresTiny,  // ceres::TinySolver (Levenberg-Marquardt) on the same residual and Jacobian
};

struct ManifoldWalkOptions {
    ManifoldSolver solver = ManifoldSolver::Newton;  // the faster one (see bench/manifold)
    int maxIterations = 20;          // Newton iterations (trial steps)
    Float relativeTolerance = 1e-7;  // |x_end - target| / scale
    Float minStep = 1.0 / 64;        // Newton: fail when the step factor falls below this
};

struct ManifoldWalkResult {
    ManifoldStatus status = ManifoldStatus::InvalidInput;
    int iterations = 0;       // solver iterations
    int traces = 0;           // chain re-traces
    Float relativeError = Infinity;
    ManifoldChain chain;      // the walked chain (valid only on Success)
    bool ok() const { return status == ManifoldStatus::Success; }
};

// Re-trace a chain from `start` along `dir` (unit) using tmpl's interior vertex
// types, primitive ids, frame references and half-vector offsets. The end vertex
// is the hit after the last interior vertex and must be on tmpl.back()'s
// primitive. Result written to out (start vertex included).
ManifoldStatus TraceChain(const ManifoldScene &scene, const ManifoldSurfacePoint &start,
                          const Vec3 &dir, const ManifoldChain &tmpl, ManifoldChain *out);

// Manifold walk: keep every interior half-vector of `base`, start at `newStart`
// (may equal base.front(): then base is the first iterate, not re-traced), and
// move the end vertex to `target` (same primitive as base.back()). Converged
// when |x_end - target| / scale < relativeTolerance, scale = max(|start|_inf,
// |target|_inf, |target - start|), and (Newton) the next correction of x_1 is
// below it too. Newton: x_1 steps in its geometric tangent
// plane and the re-trace projects it onto the surface; a trial that fails,
// moves away or crosses a fold halves the step, an accepted one doubles it (cap
// 1) and its derivative is the next iteration's (one assembly per trace). It
// fails fast: at the step floor (the last rejection's reason: Fold, StepFloor
// when the trials traced but did not approach, or the trace's failure), on a
// predicted step longer than x_1's surface, and at the iteration cap (IterationCap).
ManifoldWalkResult ManifoldWalk(const ManifoldScene &scene, const ManifoldChain &base,
                                const ManifoldSurfacePoint &newStart,
                                const ManifoldSurfacePoint &target,
                                const ManifoldWalkOptions &opts = {});

// Walk `offset` back to base's endpoints and compare every vertex to base
// (relative tolerance on the scene scale). Success or the failure reason.
ManifoldStatus CheckReversible(const ManifoldScene &scene, const ManifoldChain &base,
                               const ManifoldChain &offset, const ManifoldWalkOptions &opts = {},
                               Float relTolerance = 1e-5);

// Counters (relaxed atomics, a handful of increments per walk). Walks that
// CheckReversible makes are counted apart (reverse); the rest are forward.
constexpr int kManifoldIterationBins = 33;  // iterations of successful walks, the last bin >= 32
struct ManifoldWalkCounts {
    uint64_t walks = 0, successes = 0, iterations = 0, traces = 0, nanoseconds = 0;
    std::array<uint64_t, size_t(ManifoldStatus::Count)> byStatus{};
    std::array<uint64_t, kManifoldIterationBins> successIterations{};
    uint64_t failures() const { return walks - successes; }
    // q-quantile (0..1) of the iterations of successful walks (-1 without any).
    int iterationQuantile(double q) const;
};
struct ManifoldStatsSnapshot : ManifoldWalkCounts {
    ManifoldWalkCounts reverse;
};
ManifoldStatsSnapshot GetManifoldStats();
void ResetManifoldStats();
// Multi-line report of forward (and reverse) walks: success rate, iterations of
// successes (median, 90th percentile, share within 3), failure reasons, time.
std::string FormatManifoldStats(const ManifoldStatsSnapshot &s, const std::string &indent = "  ");

}  // namespace gradus
