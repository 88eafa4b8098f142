// The merging kernel of vertex merging (vcm, gvcm): its radius at each vertex
// of a path, as eta_j = pi r_j^2 N_light (VCM's eta_VCM per vertex).
//
// Without options: r_j = r_i (one radius per iteration i) at every vertex.
// The G-VCM paper's Sec. 6, in two independent parts. With the path in camera
// order x_0 (lens), x_1, ... and x_b its first mergeable vertex:
//   footprint: r_b^2 = min(k_i F_b^2, r_max^2)   (the pixel's width at x_b);
//           F_b^2 = l^2 Omega(w_0): Omega(w_0) = 1 / (p_dir(w_0) N_pixels) the
//           pixel's solid angle in the first direction, l the length of the
//           chain x_0 .. x_b unfolded (the ray differential of the chain
//           without the curvature of its specular vertices). The kernel's
//           projection onto the sensor is then k_i^(1/2) pixels wide along its
//           longest axis whatever the angle at x_b ("about the pixel filter
//           size", Sec. 6); an area match (F^2 / cos) would stretch it at
//           grazing angles (measured: 1.5x the merges on glass-cube with G-PM).
//           k_i = radiusscale^2 times the iteration's shrink i^(alpha - 1). A
//           ray through the filter margin (p_dir 0) takes the iteration's r_i.
//   shrink: r_j = 0.5^(s tau(x_{j-1})) r_{j-1} for j > b (s = `shrink`, 10 in
//           the paper), tau the BSDF's roughness (0 specular, 1 diffuse;
//           BSDF::roughness: a mixture's smallest lobe roughness).
// A path's radii depend on the path alone (not on which strategy sampled it),
// as its MIS sums require: camera subpaths compute them from their own
// vertices, the light side of a connection or merge from the camera-side
// radius at the junction (vcm.h), the O(n) reference from the whole path.
#pragma once
#include <cmath>

#include "cameras/camera.h"
#include "core/geometry.h"
#include "materials/bsdf.h"

namespace gradus {

struct MergeKernel {
    Float piN = 0;          // pi N_light (0: no merging)
    Float r2 = 0;           // fixed r^2 of this iteration (footprint: the filter-margin fallback)
    Float footprint2 = 0;   // k_i (> 0: r_b from the pixel footprint; 0: r_b^2 = r2)
    Float r2Max = 0;        // clamp of r_b^2 (the photon grid's reach)
    Float shrink = 0;       // s of r_j = 0.5^(s tau) r_{j-1}; 0: no shrink
    Float pixels = 0;       // N_pixels of the camera's full film
    const Camera *camera = nullptr;

    // Whether eta differs between vertices or paths (else it is piN r2 at every vertex).
    bool varies() const { return shrink > 0 || footprint2 > 0; }
    // r_{j+1}^2 / r_j^2 after a vertex with BSDF b: 0.25^(s tau).
    Float sigma(const BSDF *b) const {
        if (shrink <= 0 || !b || !*b) return 1;
        const Float tau = b->roughness();
        return tau > 0 ? std::exp2(-2 * shrink * tau) : Float(1);  // 0.25^(s tau)
    }
    // eta at the first mergeable vertex x_b: lens point, first direction (unit),
    // unfolded length l of x_0 .. x_b.
    Float firstEta(const Point3 &lens, const Vec3 &dir0, Float length) const {
        if (footprint2 <= 0 || !camera) return piN * r2;
        Float pdfPos = 0, pdfDir = 0;
        camera->pdfWe(Ray(lens, dir0), &pdfPos, &pdfDir);
        if (!(pdfDir > 0) || !(pixels > 0)) return piN * r2;
        const Float f2 = length * length / (pdfDir * pixels);
        const Float r = footprint2 * f2;
        return piN * (std::isfinite(r) ? std::min(r, r2Max) : r2Max);
    }
};

// The photon-normal filter of the G-VCM authors' public code (gdvcm, not in
// the paper): a light vertex y is merged at camera vertex z only if their
// unit geometric normals (each as its surface orients it) satisfy
// n_y . n_z >= 0.1. It drops photons on perpendicular or opposite-facing
// surfaces within the kernel (corners, the far side of thin solids); like the
// kernel itself a bias that vanishes as r -> 0 on smooth surfaces. The MIS
// weights are left as they are (as in that code).
constexpr Float kPhotonNormalMinDot = 0.1;
inline bool PhotonNormalAgrees(const Vec3 &ny, const Vec3 &nz) { return Dot(ny, nz) >= kPhotonNormalMinDot; }

// eta_j at every vertex j of a camera-order path (n vertices, vertex(0) on the
// lens): 0 before the first vertex with mergeable(j), then as MergeKernel says.
// vertex(j) -> const PathVertex &, bsdf(j) -> const BSDF * (may be null).
template <typename VertexFn, typename BsdfFn, typename MergeableFn>
void PathMergeEta(const MergeKernel &k, int n, VertexFn &&vertex, BsdfFn &&bsdf, MergeableFn &&mergeable, Float *eta) {
    Float length = 0;
    int b = -1;
    for (int j = 0; j < n; ++j) {
        eta[j] = 0;
        if (j == 0) continue;
        if (b >= 0) {
            eta[j] = eta[j - 1] * k.sigma(bsdf(j - 1));
            continue;
        }
        const Vec3 seg = vertex(j).p - vertex(j - 1).p;
        const Float len = seg.length();
        length += len;
        if (!mergeable(j) || !(len > 0)) continue;
        b = j;
        const Vec3 d0 = Normalize(vertex(1).p - vertex(0).p);
        eta[j] = k.firstEta(vertex(0).p, d0, length);
    }
}

}  // namespace gradus
