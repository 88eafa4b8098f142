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

Spectrum PathIntegrator::LiVolumetric(const Ray &cameraRay, Sampler &sampler, Arena &arena, RNG &rng) const {
    GRADUS_STAT_COUNTER("Path/Paths", nPaths);
    GRADUS_STAT_COUNTER("Path/Medium scattering vertices", nMediumVertices);
    GRADUS_STAT_COUNTER("Path/Subsurface exits", nSubsurface);
    GRADUS_STAT_COUNTER("Path/Paths ended at the interface-crossing limit", nStuck);
    ++nPaths;
    const Scene &scene = *scene_;
    Spectrum L(0), beta(1);
    Ray ray = cameraRay;
    const Medium *medium = scene.cameraMedium;
    bool specularBounce = true;
    Float prevScatterPdf = 0;
    Interaction prevIt;
    Float etaScale = 1;
    int crossings = 0;
    // Emission reached by the previous scattering sample, MIS-weighted against
    // next-event estimation from prevIt (path.cpp's scheme).
    auto addEmission = [&](const Spectrum &Le, const Light *light) {
        if (Le.isBlack()) return;
        if (specularBounce) {
            L += beta * Le;
            return;
        }
        const Float lightPdf = lightSampler_.pmf(prevIt.p, light) * light->pdfLi(prevIt, ray.d);
        L += beta * Le * PowerHeuristic(1, prevScatterPdf, 1, lightPdf);
    };
    for (int bounces = 0;; ++bounces) {
        SurfaceInteraction isect;
        const bool found = scene.intersect(ray, &isect);
        MediumInteraction mi;
        if (medium) {
            Ray seg = ray;
            seg.tMax = found ? Dot(isect.p - ray.o, ray.d) / ray.d.lengthSquared() : Infinity;
            beta *= medium->sample(seg, rng, &mi);
        }
        if (beta.isBlack() || !beta.isFinite()) break;

        if (mi.valid()) {
            // Scattering in the medium.
            if (bounces >= set_.maxDepth) break;
            ++nMediumVertices;
            crossings = 0;
            L += beta * sampleLightVolumetric(mi, nullptr, Vec3(), &mi.phase, medium, nullptr, sampler, rng);
            sampler.get1D();  // the lobe choice of a surface vertex: keeps the dimensions per bounce fixed
            Vec3 wi;
            const Float pdf = mi.phase.sample(mi.wo, sampler.get2D(), &wi);
            if (!(pdf > 0)) break;
            // Phase value = pdf: beta is unchanged.
            specularBounce = false;
            prevScatterPdf = pdf;
            prevIt = mi;
            ray = mi.spawnRay(wi);
        } else {
            if (!found) {
                for (const Light *light : scene.infiniteLights) addEmission(light->Le(ray), light);
                break;
            }
            if (isect.areaLight) addEmission(isect.Le(-ray.d), isect.areaLight);
            if (bounces >= set_.maxDepth) break;
            if (!isect.material) {  // interface: cross it, changing the medium where it is a transition
                if (++crossings > kMaxInterfaceCrossings) {
                    ++nStuck;
                    break;
                }
                medium = isect.mediumAfter(ray.d, medium);
                ray = isect.spawnRay(ray.d);
                --bounces;
                continue;
            }
            crossings = 0;
            BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
            if (!bsdf) break;
            const Vec3 wo = isect.wo;
            if (bsdf.hasNonSpecular() && !scene.lights.empty()) {
                L += beta * sampleLightVolumetric(isect, &bsdf, Vec3(isect.shading.n), nullptr, medium, &isect,
                                                  sampler, rng);
            } else if (bsdf.hasNonSpecular()) {
                sampler.get1D();
                sampler.get2D();
            }
            const Float uc = sampler.get1D();
            const Point2 u = sampler.get2D();
            BSDFSample bs;
            if (!bsdf.sample(wo, uc, u, TransportMode::Radiance, &bs) || !bs.valid()) break;
            beta *= bs.f * (AbsDot(bs.wi, isect.shading.n) / bs.pdf);
            specularBounce = bs.isSpecular();
            prevScatterPdf = bs.pdf;
            prevIt = isect;
            if (bs.isTransmission()) etaScale *= Sqr(bs.eta);
            const BSSRDF *bssrdf = bs.isTransmission() ? isect.material->getBSSRDF(isect, arena) : nullptr;
            if (!bssrdf) {
                medium = isect.mediumAfter(bs.wi, medium);
                ray = isect.spawnRay(bs.wi);
            } else {
                // Light enters the body and leaves at pi (pbrt-v3 Sec. 15.4): S / pdf,
                // then next-event estimation and the next direction from the exit BSDF.
                SurfaceInteraction pi;
                BSDF Sw;
                Spectrum w;
                const Float u1 = sampler.get1D();
                const Point2 u2 = sampler.get2D();
                if (!SampleSubsurfaceExit(scene, *bssrdf, isect, u1, u2, arena, &pi, &Sw, &w)) break;
                beta *= w;
                if (beta.isBlack() || !beta.isFinite()) break;
                ++nSubsurface;
                if (!scene.lights.empty())
                    L += beta * sampleLightVolumetric(pi, &Sw, Vec3(pi.shading.n), nullptr, medium, &pi, sampler,
                                                      rng);
                BSDFSample es;
                const Float euc = sampler.get1D();
                const Point2 eu = sampler.get2D();
                if (!Sw.sample(pi.wo, euc, eu, TransportMode::Radiance, &es) || !es.valid()) break;
                beta *= es.f * (AbsDot(es.wi, pi.shading.n) / es.pdf);
                specularBounce = false;
                prevScatterPdf = es.pdf;
                prevIt = pi;
                medium = pi.mediumAfter(es.wi, medium);
                ray = pi.spawnRay(es.wi);
            }
        }
        if (!survivesRoulette(&beta, etaScale, bounces, sampler)) break;
    }
    return L;
}

}  // namespace gradus
