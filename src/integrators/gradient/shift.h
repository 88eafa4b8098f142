// Shift mappings for gradient-domain rendering, on a generic vertex
// description so that G-PT, G-BDPT, G-VCM and G-MLT share them.
//
// A shift T_ij maps a base path x sampled for pixel i to an offset path
// y = T_ij(x) through pixel j. Gradient estimates need f(y) |T'_ij(x)| and
// the offset's own sampling pdf (gradient MIS). All Jacobians here are in
// solid angle at the vertex whose outgoing direction is shifted: they are the
// factor |d omega_y / d omega_x| that multiplies f(y) / p(x).
//
// Vertex classification (Kettunen et al. 2015, Sec. 5; DESIGN "Numbers"):
// a vertex is Rough when the lowest roughness of its BSDF components is at
// least `shiftThreshold` (default kDefaultShiftThreshold, materials/bsdf.h);
// smooth and near-specular vertices are shifted by half-vector copy (or
// replay), rough ones may be reconnected.
#pragma once
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/geometry.h"
#include "core/spectrum.h"
#include "materials/bsdf.h"

namespace gradus {

// Guard for Jacobian denominators (double precision, see DESIGN).
constexpr Float kShiftEps = 1e-14;

enum class ShiftVertexClass {
    Rough,      // reconnectable (diffuse/glossy above the threshold; also a point at infinity)
    NonRough,   // specular or near-specular: shifted by half-vector copy / replay
    Invalid,    // no BSDF (interface, camera) - the shift cannot pass it
};

// Generic path vertex as the shifts see it.
struct ShiftVertex {
    Point3 p;              // position (a unit direction when atInfinity)
    Normal3 n;             // geometric normal (zero: point light / camera / infinity)
    const BSDF *bsdf = nullptr;
    bool atInfinity = false;
};

ShiftVertexClass ClassifyBSDF(const BSDF *bsdf, Float shiftThreshold);
inline ShiftVertexClass ClassifyVertex(const ShiftVertex &v, Float shiftThreshold) {
    return v.atInfinity ? ShiftVertexClass::Rough : ClassifyBSDF(v.bsdf, shiftThreshold);
}

// ---- Reconnection --------------------------------------------------------
// The offset vertex yPrev connects to the base's vertex `target`, which the
// base reached from xPrev. Jacobian of omega_x -> omega_y (solid angle):
//   |T'| = (|cos theta_y| / d_y^2) / (|cos theta_x| / d_x^2)
// (ratio of geometry terms at the shared vertex; G-MLT Sec. 5.2 / G-PT).
// A target at infinity keeps the direction (environment-map shift, |T'| = 1).
struct ReconnectionShift {
    Vec3 wi;          // unit direction from yPrev towards the target
    Float dist2 = 0;  // squared distance yPrev-target (0 at infinity)
    Float jacobian = 0;
};
bool ShiftReconnect(const Point3 &xPrev, const Point3 &yPrev, const ShiftVertex &target, ReconnectionShift *out);

// ---- Half-vector copy ----------------------------------------------------
// In the local shading frames of the base and offset vertices: keeps the
// (generalised) half vector of (woX, wiX) and applies it to woY.
//   reflection:  h = normalize(wo + wi), wiY = reflect(woY, h),
//                |T'| = |wiY.h| / |wiX.h|              (d omega_h/d omega_i = 1/(4|wi.h|))
//   refraction:  h = normalize(wo + eta wi) (eta = eta on wi's side / wo's side),
//                wiY = refract(woY, h, eta),
//                |T'| = |wiX.h| (woY.h + eta wiY.h)^2 / (|wiY.h| (woX.h + eta wiX.h)^2)
//                (Walter et al. 2007, Eq. 16, d omega_h/d omega_i = eta^2 |wi.h| / |h_u|^2)
// Refraction needs woY on the same side as woX and eta != 1; fails on total
// internal reflection. Inverse: ShiftHalfVector(woY, wiY, woX, eta) gives wiX.
struct HalfVectorShift {
    Vec3 wi;  // local direction at the offset vertex
    Float jacobian = 0;
    bool refraction = false;
};
bool ShiftHalfVector(const Vec3 &woX, const Vec3 &wiX, const Vec3 &woY, Float eta, HalfVectorShift *out);
// The same on world directions at a base vertex with BSDF bx and an offset
// vertex with BSDF by: eta from bx (BSDF::eta: inside over outside, taken
// on wo's side). False also for a refraction whose index bx does not report
// (eta 1: no half vector to copy). out->wi is in world space.
bool ShiftHalfVectorWorld(const BSDF &bx, const Vec3 &woX, const Vec3 &wiX, const BSDF &by, const Vec3 &woY,
                          HalfVectorShift *out);

// ---- Random-number replay -------------------------------------------------
// The offset samples its BSDF with the base's random numbers. In primary
// sample space the shift is the identity, so in path space
// |T'| = p_x(omega_x) / p_y(omega_y) (ratio of the sampling densities).
struct ReplayShift {
    BSDFSample sample;  // the offset's sample (world space)
    Float jacobian = 0;
};
bool ShiftReplay(const BSDF &offsetBsdf, const Vec3 &woY, Float uc, Point2 u, Float basePdf, TransportMode mode,
                 ReplayShift *out);

// ---- Gradient MIS ----------------------------------------------------------
// Combined weight for a gradient sample taken with technique t of the base
// (G-BDPT Eq. 8, with the power heuristic instead of the balance heuristic):
//   w = p_t(x)^2 / sum_s [ p_s(x)^2 + (p_s(y) |T'|)^2 ]
// Arguments are the per-technique pdfs of the last segment in one measure;
// `ratio` = prod over earlier segments of p_y |T'| / p_x, times the last
// segment's |T'|. With ratio 0 (failed shift) this is the base's own MIS weight.
// The symmetric estimator then adds w (f(y)|T'| - f(x)) / p_t(x) (Eq. 3-4), and
// w_ij(x) + w_ji(T_ij x) = 1 holds by construction.
inline Float GradientMISWeight(Float pTechX, Float pOtherX, Float pTechY, Float pOtherY, Float ratio) {
    Float den = Sqr(pTechX) + Sqr(pOtherX) + Sqr(ratio) * (Sqr(pTechY) + Sqr(pOtherY));
    return den > 0 ? Sqr(pTechX) / den : 0;
}

// Combined gradient/BDPT weight of G-BDPT Eq. 8 with the balance heuristic,
//   w_ij,st(x) = p_st(x) / sum_k [p_k(x) + p_k(y) |T'|] = 1 / (1 / w_st(x) + rho / w_st(y)),
// from the BDPT weights wx, wy of base and offset and rho = |T'| p_st(y) / p_st(x).
// A failed or blocked offset (wy or rho not positive) falls back to wx (Sec. 4).
inline Float CombinedWeight(Float wx, Float wy, Float rho) {
    if (!(wx > 0)) return 0;
    if (!(wy > 0) || !(rho > 0) || !std::isfinite(rho)) return wx;
    return 1 / (1 / wx + rho / wy);
}

// ---- Statistics ------------------------------------------------------------
enum class ShiftType { Reconnection = 0, Environment, HalfVector, Replay, Count };
enum class ShiftFailure {
    Occluded = 0,     // reconnection or environment ray blocked
    ClassMismatch,    // offset vertex classified differently: not invertible
    Geometry,         // TIR, degenerate half vector, zero pdf/BSDF, camera ray failed
    Escaped,          // offset left the scene where the base did not (or reverse)
    Count
};
const char *ShiftTypeName(ShiftType t);
const char *ShiftFailureName(ShiftFailure f);

// Thread-safe counters; integrators accumulate a LocalShiftStats per sample and flush it.
struct LocalShiftStats {
    uint64_t attempts[int(ShiftType::Count)] = {};
    uint64_t successes[int(ShiftType::Count)] = {};
    uint64_t failures[int(ShiftFailure::Count)] = {};
    uint64_t offsetPaths = 0;
    void attempt(ShiftType t) { ++attempts[int(t)]; }
    void success(ShiftType t) { ++successes[int(t)]; }
    void fail(ShiftFailure f) { ++failures[int(f)]; }
};
class ShiftStats {
  public:
    void add(const LocalShiftStats &l);
    std::string format(const std::string &title) const;
    void reset();

  private:
    std::atomic<uint64_t> attempts_[int(ShiftType::Count)] = {};
    std::atomic<uint64_t> successes_[int(ShiftType::Count)] = {};
    std::atomic<uint64_t> failures_[int(ShiftFailure::Count)] = {};
    std::atomic<uint64_t> offsetPaths_{0};
};

}  // namespace gradus
