// Shift of a camera subpath to a neighbouring pixel (G-BDPT, gradient-domain-
// bdpt.md Sec. 3.1-3.2, cases (i) and (ii), Eqs. 6 and 7); measure, Jacobians
// and rho as in subpath_shift.h.
//
// Manifold shift ("manifold", Lehtinen et al. 2013 / Sec. 3.1): the image-plane
// point moves by one pixel, the first half-vector chain (a, b) is re-traced
// with the base's half vectors (ideal specular vertices reflect/refract as the
// base did), and the offset's b reconnects to the base's c through the second
// chain by a manifold walk. Half-vector shift ("halfvector", Kettunen et al.
// 2015): half vectors are copied at every vertex until the base has two
// consecutive diffuse vertices k-1, k, and the offset reconnects to x_k.
//
// Limitations: second chains must consist of ideal specular vertices (a glossy
// vertex below the threshold there makes the path fall back); glossy
// refraction is not half-vector copied; the half-vector shift falls back for
// paths with a specular vertex between b and its reconnection vertex (their
// light-tracing strategy is not shifted across specular chains either);
// infinite lights are not reconnected to (fallback).
#pragma once
#include "integrators/gradient/subpath_shift.h"

namespace gradus {

// Offset camera subpath of one neighbour.
struct CameraShift {
    ShiftSubpath y;       // offset vertices (arena storage, n = base n)
    int validUpTo = -1;   // connections at camera vertex k <= validUpTo may use y
    int r = -1;           // reconnection vertex: y.v[k] = x.v[k] for k >= r (-1: none)
    Float *rho = nullptr; // rho[k]: gradient-MIS ratio for paths ending their camera part at k
};

// Shifts the camera subpath `x` (generated from camera sample cs) to the
// neighbour at pixel offset `off`. Vertices before a failure stay valid; the
// offset's pdfFwd/pdfRev are its own area densities (for its BDPT weights).
// With media (ctx.media): x.segFactor must be set; rng draws the
// transmittance-ratio estimates (medium_shift.h).
void ShiftCameraSubpath(const SubpathShiftContext &ctx, const ShiftSubpath &x, const CameraSample &cs, Point2i off,
                        Arena &arena, CameraShift *out, SubpathShiftStats *st, UniformSource rng = {});

}  // namespace gradus
