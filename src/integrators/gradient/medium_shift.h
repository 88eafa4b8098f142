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

}  // namespace gradus
