// Shift of a light-tracing path (strategy (s, 1), case (iii) of G-BDPT,
// gradient-domain-bdpt.md Sec. 3.2): the light subpath's last vertex b = x_1
// moves to the neighbouring pixel's first hit, and reconnects to the next
// diffuse light vertex c directly or through a chain of ideal specular
// vertices by a manifold walk (measure, Jacobians and rho as in
// subpath_shift.h). The light-tracing strategy's rho uses the camera side's
// effective |T'| so that it pairs with the camera-subpath shift of the same
// path's other strategies (their Eq. 8 weights sum to one).
#pragma once
#include "integrators/gradient/subpath_shift.h"

namespace gradus {

// Light vertices 0..s-1 of `light`, lens vertex `lens`, raster position pRaster,
// base unweighted value fx. Returns false when the shift fails or the offset is
// black/blocked. fy = f(y)|T'|/p(x), wy = BDPT weight of the offset (with the
// strategies of ctx.bidir), rho = |T'| p(y)/p(x) (Eq. 8). The light subpath's
// vertices are swapped in place for the offset's weight and restored.
// With media (ctx.media): an empty second chain only, T_y / T_x on both
// changed segments (lighttracing_shift.cpp); rng draws the ratio estimates.
bool ShiftLightTracingPath(const SubpathShiftContext &ctx, const ShiftSubpath &light, int s, const PathVertex &lens,
                           Point2 pRaster, const Spectrum &fx, Point2i off, Arena &arena, Spectrum *fy, Float *wy,
                           Float *rho, SubpathShiftStats *st, UniformSource rng = {});

}  // namespace gradus
