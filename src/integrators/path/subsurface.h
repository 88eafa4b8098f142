// The scene-dependent half of pbrt-v3's separable BSSRDF: where light that entered a
// subsurface material at po leaves it (pbrt-v3's SeparableBSSRDF::Sample_S), found by
// probe rays through the Scene. The profile and its densities are in materials/bssrdf.h.
#pragma once
#include "core/arena.h"
#include "materials/bssrdf.h"
#include "scene/scene.h"

namespace gradus {

// Samples where light that entered at po (after the BSDF at po sampled a transmission)
// leaves. A probe segment of length 2 sqrt(rMax^2 - r^2) is cast along one axis of po's
// frame (ns, ss, ts with probabilities .5, .25, .25) through a point at radius r (sampled
// from one colour channel's profile, chosen uniformly) and angle 2 pi u2.y; one of its hits
// on a surface with the BSSRDF's material is chosen uniformly. On success *pi is that exit
// interaction (material, shading frame, pi->wo = its shading normal), *Sw its exit BSDF
// (SubsurfaceExitBxDF in the arena, including the eta^2 of radiance transport) and
// *weight = Sp(|po - pi|) / pdf, pdf the area density of pi summed over the 3 axes x 3
// channels divided by the number of hits (no cosine at pi; the (1 - Fr) at po is the
// entry BSDF's transmission). Returns false when no exit was found.
bool SampleSubsurfaceExit(const Scene &scene, const BSSRDF &bssrdf, const SurfaceInteraction &po, Float u1, Point2 u2,
                          Arena &arena, SurfaceInteraction *pi, BSDF *Sw, Spectrum *weight);

// Probe hits beyond which a probe segment stops (guards against a ray that makes no
// progress through coincident geometry; pbrt-v3 has no bound).
constexpr int kMaxSubsurfaceProbeHits = 256;

}  // namespace gradus
