#include "integrators/path/subsurface.h"

#include <cmath>

#include "core/stats.h"

namespace gradus {

bool SampleSubsurfaceExit(const Scene &scene, const BSSRDF &bssrdf, const SurfaceInteraction &po, Float u1, Point2 u2,
                          Arena &arena, SurfaceInteraction *pi, BSDF *Sw, Spectrum *weight) {
    GRADUS_STAT_COUNTER("Subsurface/Exit samples", nSamples);
    GRADUS_STAT_COUNTER("Subsurface/Exit samples without exit", nMissed);
    ++nSamples;
    // Projection axis: the probe runs along vz, the disk of radius r spans vx, vy.
    Vec3 vx, vy, vz;
    if (u1 < 0.5) {
        vx = bssrdf.ss(), vy = bssrdf.ts(), vz = bssrdf.ns();
        u1 *= 2;
    } else if (u1 < 0.75) {
        vx = bssrdf.ts(), vy = bssrdf.ns(), vz = bssrdf.ss();
        u1 = (u1 - 0.5) * 4;
    } else {
        vx = bssrdf.ns(), vy = bssrdf.ss(), vz = bssrdf.ts();
        u1 = (u1 - 0.75) * 4;
    }
    // Colour channel whose profile is sampled; u1 is re-used for the hit choice.
    const int nc = BSSRDF::kChannels;
    int ch = Clamp(int(u1 * nc), 0, nc - 1);
    u1 = Clamp<Float>(u1 * nc - ch, 0, 1);

    Float r = bssrdf.sampleSr(ch, u2.x);
    // The profile is cut where 99.9% of its mass is reached (pbrt-v3's bound).
    Float rMax = bssrdf.sampleSr(ch, 0.999);
    if (!(r >= 0) || !(r < rMax)) {
        ++nMissed;
        return false;
    }
    Float phi = 2 * Pi * u2.y;
    Float l = 2 * std::sqrt(rMax * rMax - r * r);
    Interaction base;
    base.p = po.p + (vx * std::cos(phi) + vy * std::sin(phi)) * r - vz * (l / 2);
    const Point3 target = base.p + vz * l;

    // Walk the segment; choose uniformly among the hits on the same material with a
    // single uniform (reservoir of size one: the k-th hit replaces the kept one with
    // probability 1/k, and u1 is rescaled to stay uniform).
    int nFound = 0;
    SurfaceInteraction hit;
    for (int k = 0; k < kMaxSubsurfaceProbeHits; ++k) {
        Ray ray = base.spawnRayTo(target);
        if (ray.d.lengthSquared() == 0 || !scene.intersect(ray, &hit)) break;
        base = Interaction(hit.p, hit.n, hit.wo);
        if (hit.material != bssrdf.material()) continue;
        ++nFound;
        Float keep = Float(1) / nFound;
        if (u1 < keep) {
            *pi = hit;
            u1 = u1 / keep;
        } else {
            u1 = (u1 - keep) / (1 - keep);
        }
        u1 = Clamp<Float>(u1, 0, 1);
    }
    if (nFound == 0) {
        ++nMissed;
        return false;
    }
    Float pdf = bssrdf.pdfSp(pi->p, pi->n) / nFound;
    Spectrum sp = bssrdf.Sp(pi->p);
    if (!(pdf > 0) || sp.isBlack()) {
        ++nMissed;
        return false;
    }
    *weight = sp / pdf;
    pi->wo = Vec3(pi->shading.n);
    *Sw = BSDF(*pi, arena.make<SubsurfaceExitBxDF>(bssrdf.eta()));
    return true;
}

}  // namespace gradus
