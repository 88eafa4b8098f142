// Transmittance terms of shifts through participating media (gpt with media,
// gpt.h "Participating media").
//
// A shifted path y changes some of the base path x's segments. In f(y)/p(x)
// the base's distance densities hold the transmittance T_x of its segments
// (delta tracking samples p(t) = sigma_t(t) T_x(t) without knowing T_x in
// closed form), f(y) holds T_y: the shift needs T_y / T_x = exp(-(tau_y - tau_x)).
// TransmittanceRatio estimates it without bias: exactly for homogeneous media;
// for the rest (density grids) by ratio tracking of the difference of the two
// optical depths (the Poisson estimator of exp(-integral c), Novak et al. 2014
// Sec. 4.2 with a signed integrand): both polylines are parametrised by
// u in [0, 1] (arc length over their total length L_y, L_x), c(u) = L_y
// sigma_y(u) - L_x sigma_x(u), |c| <= mu = max(L_y max sigma_y, L_x max sigma_x);
// with tentative points of a Poisson process of rate mu on [0, 1],
// E[prod (1 - c(u_k) / mu)] = exp(-mu) sum_n mu^n / n! (1 - integral c / mu)^n
// = exp(-integral c). Each factor lies in [0, 2]; for nearby segments c ~ 0
// and the estimate is close to the exact ratio.
#pragma once
#include "core/geometry.h"
#include "core/interaction.h"
#include "core/spectrum.h"
#include "media/medium.h"
#include "samplers/uniform_source.h"
#include "scene/scene.h"

namespace gradus {

// A straight piece of a path inside one medium (nullptr: vacuum): from o along
// the unit direction d for len (world units; Infinity for an escaped ray).
struct MediumPiece {
    Point3 o;
    Vec3 d;
    Float len = 0;
    const Medium *medium = nullptr;
};

// Most pieces of one path segment (interfaces crossed + 1).
constexpr int kMaxMediumPieces = kMaxInterfaceCrossings + 2;

// Unbiased estimate of T(y pieces) / T(x pieces) (see above); 0 where the
// y pieces have infinite optical depth. The x pieces must have finite optical
// depth (they are a sampled base path).
Spectrum TransmittanceRatio(const MediumPiece *y, int ny, const MediumPiece *x, int nx, UniformSource rng);

// ---- Segments of bidirectional subpaths (G-BDPT with media) ----------------
// What ends a segment between two scattering vertices.
enum class SegmentEnd { Surface, Medium, Escape };

// The pieces of the straight segment from `from` (leaving in medium m) to the
// interaction `to` (a surface point, or a point in a medium: zero normal), or
// towards infinity along d (atInfinity), through interfaces (surfaces without
// a material). Returns their number, 0 where a surface with a material is in
// the way or the crossings exceed kMaxInterfaceCrossings.
int TraceSegmentPieces(const Scene &scene, const Interaction &from, const Medium *m, const Interaction &to,
                       bool atInfinity, const Vec3 &d, MediumPiece *pieces);

// An offset segment in lockstep with the base's nx pieces xp (Gruson et al.
// 2018's volumetric shift, as gpt's): from `ray` in medium m it crosses as
// many interfaces, then ends as the base does: on a surface with a material
// (Surface: *hit), escaping (Escape), or scattering (Medium) at the base's
// free-flight distance along its own last piece (|T'| = 1: *pMedium), which
// fails if it meets a surface first, is in another medium or sigma_t is 0
// there. Its pieces go to yp (nx of them), *mEnd is the medium it ends in.
bool LockstepSegment(const Scene &scene, Ray ray, const Medium *m, const MediumPiece *xp, int nx, SegmentEnd end,
                     MediumPiece *yp, SurfaceInteraction *hit, Point3 *pMedium, const Medium **mEnd);

}  // namespace gradus
