// The path integrator in scenes with participating media or BSSRDFs: pbrt-v3's
// volpath (Pharr et al., PBR 3rd ed., Sec. 15.3-15.5) with path.cpp's
// deferred MIS for emitters found by the scattering sample.
//
// Along every segment the medium it travels in samples a scattering distance
// (Medium::sample: spectral MIS for homogeneous media, delta tracking for
// grids); a scattering in the medium is a vertex with the HG phase function.
// Surfaces without a material are crossed (they change the medium when they
// are a transition) without counting a bounce. Next-event estimation
// multiplies by the transmittance of the shadow ray (Scene::transmittance:
// exact for homogeneous media, ratio tracking for grids). At a surface with a
// BSSRDF, a transmission sampled by its BSDF continues at the exit point that
// SampleSubsurfaceExit samples (pbrt-v3 Sec. 15.4, probe rays).
//
// MIS between next-event estimation and the scattering sample uses only
// directional densities: the light's solid-angle pdf against the BSDF's or
// phase function's (Veach 1997, Eq. 9.13, power heuristic). Both strategies
// see the same transmittance in expectation, so the weights (which sum to one
// per direction) keep the estimator unbiased.
#include <cstring>

#include "core/error.h"
#include "core/stats.h"
#include "integrators/path/path.h"
#include "integrators/path/subsurface.h"
#include "samplers/sampling.h"

namespace gradus {

Spectrum PathIntegrator::sampleLightVolumetric(const Interaction &it, const BSDF *bsdf, const Vec3 &shadingN,
                                               const HGPhase *phase, const Medium *medium,
                                               const SurfaceInteraction *surface, Sampler &sampler, RNG &rng) const {
    const Scene &scene = *scene_;
    Float pmf;
    const Light *light = lightSampler_.sample(it.p, sampler.get1D(), &pmf);
    const Point2 uLight = sampler.get2D();
    LightLiSample ls;
    if (!light || pmf <= 0 || !light->sampleLi(it, uLight, &ls) || ls.pdf <= 0 || ls.L.isBlack())
        return Spectrum(0);
    Spectrum f;
    Float scatterPdf;
    if (bsdf) {
        f = bsdf->f(it.wo, ls.wi) * AbsDot(ls.wi, shadingN);
        scatterPdf = bsdf->pdf(it.wo, ls.wi);
    } else {
        scatterPdf = phase->p(it.wo, ls.wi);
        f = Spectrum(scatterPdf);
    }
    if (f.isBlack()) return Spectrum(0);
    // The medium the shadow ray leaves in: a surface's side towards the light.
    const Medium *leaving = surface ? surface->mediumAfter(ls.wi, medium) : medium;
    const Spectrum tr = scene.transmittance(it, leaving, ls.pLight, rng);
    if (tr.isBlack()) return Spectrum(0);
    const Float lightPdf = pmf * ls.pdf;
    if (IsDeltaLight(light->flags)) return f * ls.L * tr / lightPdf;
    return f * ls.L * tr * (PowerHeuristic(1, lightPdf, 1, scatterPdf) / lightPdf);
}

// One path of LiVolumetric: its radiance so far, throughput, ray and medium,
// and what the deferred MIS of emission needs (the previous scattering).
struct PathIntegrator::VolumePath {
    // What a surface event left to do: go on (roulette, next bounce), go on
    // without counting a bounce (an interface was crossed), or end the path.
    enum class Step { Scattered, Crossed, End };

    VolumePath(const PathIntegrator &in, Sampler &sampler, Arena &arena, RNG &rng, StatCounterCell &nMediumVertices,
               StatCounterCell &nSubsurface, StatCounterCell &nStuck, const Ray &cameraRay)
        : in(in), scene(*in.scene_), sampler(sampler), arena(arena), rng(rng), nMediumVertices(nMediumVertices),
          nSubsurface(nSubsurface), nStuck(nStuck), ray(cameraRay), medium(scene.cameraMedium) {}

    const PathIntegrator &in;
    const Scene &scene;
    Sampler &sampler;
    Arena &arena;
    RNG &rng;
    StatCounterCell &nMediumVertices, &nSubsurface, &nStuck;
    Ray ray;
    const Medium *medium;
    Spectrum L = Spectrum(0), beta = Spectrum(1);
    bool specularBounce = true;
    Float prevScatterPdf = 0;
    Interaction prevIt;
    Float etaScale = 1;
    int crossings = 0;

    // Emission reached by the previous scattering sample, MIS-weighted against
    // next-event estimation from prevIt (path.cpp's scheme).
    void addEmission(const Spectrum &Le, const Light *light) {
        if (Le.isBlack()) return;
        if (specularBounce) {
            L += beta * Le;
            return;
        }
        const Float lightPdf = in.lightSampler_.pmf(prevIt.p, light) * light->pdfLi(prevIt, ray.d);
        L += beta * Le * PowerHeuristic(1, prevScatterPdf, 1, lightPdf);
    }

    // Scattering in the medium: next-event estimation, then a phase-function
    // direction; false: the path ends.
    bool scatterInMedium(const MediumInteraction &mi) {
        ++nMediumVertices;
        crossings = 0;
        L += beta * in.sampleLightVolumetric(mi, nullptr, Vec3(), &mi.phase, medium, nullptr, sampler, rng);
        sampler.get1D();  // the lobe choice of a surface vertex: keeps the dimensions per bounce fixed
        Vec3 wi;
        const Float pdf = mi.phase.sample(mi.wo, sampler.get2D(), &wi);
        if (!(pdf > 0)) return false;
        // Phase value = pdf: beta is unchanged.
        specularBounce = false;
        prevScatterPdf = pdf;
        prevIt = mi;
        ray = mi.spawnRay(wi);
        return true;
    }

    // The ray reached a surface (found) or escaped: emission, then an
    // interface crossing or a scattering at the surface.
    Step atSurface(SurfaceInteraction &isect, bool found, int bounces) {
        if (!found) {
            for (const Light *light : scene.infiniteLights) addEmission(light->Le(ray), light);
            return Step::End;
        }
        if (isect.areaLight) addEmission(isect.Le(-ray.d), isect.areaLight);
        if (bounces >= in.set_.maxDepth) return Step::End;
        if (!isect.material) {  // interface: cross it, changing the medium where it is a transition
            if (++crossings > kMaxInterfaceCrossings) {
                ++nStuck;
                return Step::End;
            }
            medium = isect.mediumAfter(ray.d, medium);
            ray = isect.spawnRay(ray.d);
            return Step::Crossed;
        }
        crossings = 0;
        return scatterAtSurface(isect) ? Step::Scattered : Step::End;
    }

    // Next-event estimation and the BSDF's direction at a surface (through a
    // subsurface body when the BSDF transmits into one); false: the path ends.
    bool scatterAtSurface(SurfaceInteraction &isect) {
        BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        if (!bsdf) return false;
        const Vec3 wo = isect.wo;
        if (bsdf.hasNonSpecular() && !scene.lights.empty()) {
            L += beta * in.sampleLightVolumetric(isect, &bsdf, Vec3(isect.shading.n), nullptr, medium, &isect,
                                                 sampler, rng);
        } else if (bsdf.hasNonSpecular()) {
            sampler.get1D();
            sampler.get2D();
        }
        const Float uc = sampler.get1D();
        const Point2 u = sampler.get2D();
        BSDFSample bs;
        if (!bsdf.sample(wo, uc, u, TransportMode::Radiance, &bs) || !bs.valid()) return false;
        beta *= bs.f * (AbsDot(bs.wi, isect.shading.n) / bs.pdf);
        specularBounce = bs.isSpecular();
        prevScatterPdf = bs.pdf;
        prevIt = isect;
        if (bs.isTransmission()) etaScale *= Sqr(bs.eta);
        const BSSRDF *bssrdf = bs.isTransmission() ? isect.material->getBSSRDF(isect, arena) : nullptr;
        if (bssrdf) return exitSubsurface(isect, *bssrdf);
        medium = isect.mediumAfter(bs.wi, medium);
        ray = isect.spawnRay(bs.wi);
        return true;
    }

    // Light enters the body and leaves at pi (pbrt-v3 Sec. 15.4): S / pdf,
    // then next-event estimation and the next direction from the exit BSDF.
    bool exitSubsurface(const SurfaceInteraction &isect, const BSSRDF &bssrdf) {
        SurfaceInteraction pi;
        BSDF Sw;
        Spectrum w;
        const Float u1 = sampler.get1D();
        const Point2 u2 = sampler.get2D();
        if (!SampleSubsurfaceExit(scene, bssrdf, isect, u1, u2, arena, &pi, &Sw, &w)) return false;
        beta *= w;
        if (beta.isBlack() || !beta.isFinite()) return false;
        ++nSubsurface;
        if (!scene.lights.empty())
            L += beta * in.sampleLightVolumetric(pi, &Sw, Vec3(pi.shading.n), nullptr, medium, &pi, sampler, rng);
        BSDFSample es;
        const Float euc = sampler.get1D();
        const Point2 eu = sampler.get2D();
        if (!Sw.sample(pi.wo, euc, eu, TransportMode::Radiance, &es) || !es.valid()) return false;
        beta *= es.f * (AbsDot(es.wi, pi.shading.n) / es.pdf);
        specularBounce = false;
        prevScatterPdf = es.pdf;
        prevIt = pi;
        medium = pi.mediumAfter(es.wi, medium);
        ray = pi.spawnRay(es.wi);
        return true;
    }
};

Spectrum PathIntegrator::LiVolumetric(const Ray &cameraRay, Sampler &sampler, Arena &arena, RNG &rng) const {
    GRADUS_STAT_COUNTER("Path/Paths", nPaths);
    GRADUS_STAT_COUNTER("Path/Medium scattering vertices", nMediumVertices);
    GRADUS_STAT_COUNTER("Path/Subsurface exits", nSubsurface);
    GRADUS_STAT_COUNTER("Path/Paths ended at the interface-crossing limit", nStuck);
    ++nPaths;
    const Scene &scene = *scene_;
    VolumePath p(*this, sampler, arena, rng, nMediumVertices, nSubsurface, nStuck, cameraRay);
    for (int bounces = 0;; ++bounces) {
        SurfaceInteraction isect;
        const bool found = scene.intersect(p.ray, &isect);
        MediumInteraction mi;
        if (p.medium) {
            Ray seg = p.ray;
            seg.tMax = found ? Dot(isect.p - p.ray.o, p.ray.d) / p.ray.d.lengthSquared() : Infinity;
            p.beta *= p.medium->sample(seg, rng, &mi);
        }
        if (p.beta.isBlack() || !p.beta.isFinite()) break;
        if (mi.valid()) {
            if (bounces >= set_.maxDepth) break;
            if (!p.scatterInMedium(mi)) break;
        } else {
            const VolumePath::Step step = p.atSurface(isect, found, bounces);
            if (step == VolumePath::Step::End) break;
            if (step == VolumePath::Step::Crossed) {  // no bounce
                --bounces;
                continue;
            }
        }
        if (!survivesRoulette(&p.beta, p.etaScale, bounces, sampler)) break;
    }
    return p.L;
}

}  // namespace gradus
