// G-BDPT-specific pieces of the shift (gradient-domain-bdpt.md Sec. 3): the
// s = 1 (next-event) connection of base and offset paths with one light point.
// The shifts of path vertices (camera subpaths, light-tracing paths) live in
// gradient/ (camera_shift.h, lighttracing_shift.h) for G-VCM and G-MLT too.
#pragma once
#include "integrators/common/bidir.h"
#include "integrators/gradient/camera_shift.h"
#include "integrators/gradient/lighttracing_shift.h"

namespace gradus {

// s = 1 (next-event) connection with a given light point, for base and offset
// paths alike (the offset reconnects to the base's light point).
struct LightPoint {
    PathVertex v;          // light vertex (pdfFwd = PdfLightOrigin)
    const Light *light = nullptr;
    Float pmf = 0, pdf = 0;  // light choice and solid-angle pdf at the base vertex
    Spectrum Li;             // radiance/intensity arriving at the base vertex
    Point3 basePoint;        // the base vertex the pdf refers to
    Point2 u;                // light-sampling numbers (delta lights are re-evaluated)
    bool delta = false, infinite = false;
};
bool SampleLightPoint(const SubpathShiftContext &ctx, const PathVertex &pt, Float uSel, Point2 u, LightPoint *lp);
// f / p_base (unweighted) and the BDPT weight of strategy (1, t) on `cam`;
// knownVisible: the edge is the base's (no shadow ray); misParts: the weight's
// parts split at misSplit (bidir.h MISSplit, if misSplit + 2 <= t - 1).
// With media (ctx.media) cam's vertex may be a medium vertex and the edge's
// transmittance is estimated with rng (unless knownVisible).
bool ConnectLightPoint(const SubpathShiftContext &ctx, const LightPoint &lp, SubpathView cam, int t,
                       ConnectResult *res, bool knownVisible = false, int misSplit = -1, MISSplit *misParts = nullptr,
                       UniformSource rng = {});

}  // namespace gradus
