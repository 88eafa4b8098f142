#include "integrators/path/path.h"

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"
#include "samplers/sampling.h"

namespace gradus {

ParamTable<PathSettings> PathParams() {
    using S = PathSettings;
    ParamTable<S> t("path tracing");
    t.maxDepth(&S::maxDepth);
    t.real("rrthreshold", &S::rrThreshold, 1,
           "Russian roulette when max(beta) < rrthreshold, after 3 bounces (pbrt-v3)");
    t.enumeration("lightsamplestrategy", &S::lightStrategy, "spatial", {"uniform", "power", "spatial"},
                  "light choice; spatial: per-voxel distributions (see light_sampler.h)");
    t.pixelBounds(&S::pixelBounds);
    return t;
}

std::vector<ParamInfo> PathParameters() { return PathParams().describe(); }

PathIntegrator::PathIntegrator(const EntityDesc &desc) : set_(PathParams().parse(desc)), loc_(desc.loc) {}

void PathIntegrator::preprocess(const Scene &scene, Film &) {
    lightSampler_ = LightSampler(scene.lights, set_.lightStrategy, loc_, scene.bounds);
    volumetric_ = scene.features.media || scene.features.subsurface;
}

void PathIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    Ray ray;
    Float w = scene_->camera->generateRay(cs, &ray);
    // A blocked sample (realistic camera: vignetted) still counts, with radiance 0,
    // as pbrt-v3's Film adds its filter weight: pixels average over all samples.
    if (w == 0) return rec.addRadiance(Spectrum(0));
    if (volumetric_) {
        // Media draw from their own stream, keyed by the render seed and the film position
        // (its own key, not MediaRNG's: the agreement tests' power was measured with it).
        RNG rng(Hash(sampler.seed(), FloatBits(cs.pFilm.x), FloatBits(cs.pFilm.y), FloatBits(cs.pLens.x)));
        rec.addRadiance(LiVolumetric(ray, sampler, arena, rng) * w);
        return;
    }
    rec.addRadiance(Li(ray, sampler, arena) * w);
}

// Russian roulette (pbrt-v3: after three bounces, on beta scaled by eta^2);
// false ends the path. Takes one sampler dimension at every bounce.
bool PathIntegrator::survivesRoulette(Spectrum *beta, Float etaScale, int bounces, Sampler &sampler) const {
    const Spectrum rrBeta = *beta * etaScale;
    const Float uRR = sampler.get1D();
    if (rrBeta.maxComponent() < set_.rrThreshold && bounces > 3) {
        const Float q = std::max<Float>(0.05, 1 - rrBeta.maxComponent());
        if (uRR < q) return false;
        *beta = *beta / (1 - q);
    }
    return !beta->isBlack();
}

// Next-event estimation and BSDF sampling combined with the power heuristic
// (Veach 1997, Eq. 9.13); emission found by BSDF sampling is weighted at the
// next vertex, so each bounce costs one closest-hit and one shadow ray.
Spectrum PathIntegrator::Li(const Ray &cameraRay, Sampler &sampler, Arena &arena) const {
    GRADUS_STAT_COUNTER("Path/Paths", nPaths);
    GRADUS_STAT_COUNTER("Path/Path vertices", nVertices);
    GRADUS_STAT_COUNTER("Path/Paths ended at the interface-crossing limit", nStuck);
    ++nPaths;
    const Scene &scene = *scene_;
    Spectrum L(0), beta(1);
    Ray ray = cameraRay;
    bool specularBounce = true;  // the camera ray counts as specular for emission
    Float prevBsdfPdf = 0;
    Interaction prevIt;
    Float etaScale = 1;
    int crossings = 0;  // consecutive interface crossings
    for (int bounces = 0;; ++bounces) {
        SurfaceInteraction isect;
        bool found = scene.intersect(ray, &isect);
        // Emission reached by the previous BSDF sample.
        if (found) {
            Spectrum Le = isect.Le(-ray.d);
            if (!Le.isBlack()) {
                if (specularBounce) {
                    L += beta * Le;
                } else {
                    Float lightPdf = lightSampler_.pmf(prevIt.p, isect.areaLight) * isect.areaLight->pdfLi(prevIt, ray.d);
                    L += beta * Le * PowerHeuristic(1, prevBsdfPdf, 1, lightPdf);
                }
            }
        } else {
            for (const Light *light : scene.infiniteLights) {
                Spectrum Le = light->Le(ray);
                if (Le.isBlack()) continue;
                if (specularBounce) {
                    L += beta * Le;
                } else {
                    Float lightPdf = lightSampler_.pmf(prevIt.p, light) * light->pdfLi(prevIt, ray.d);
                    L += beta * Le * PowerHeuristic(1, prevBsdfPdf, 1, lightPdf);
                }
            }
            DebugTrace("bounce %d: escaped; L (%.4g, %.4g, %.4g)", bounces, L.r, L.g, L.b);
            break;
        }
        if (DebugTracing())
            DebugTrace("bounce %d: hit (%.6g, %.6g, %.6g) n (%.3f, %.3f, %.3f) beta (%.4g, %.4g, %.4g) L so far "
                       "(%.4g, %.4g, %.4g)",
                       bounces, isect.p.x, isect.p.y, isect.p.z, isect.n.x, isect.n.y, isect.n.z, beta.r, beta.g,
                       beta.b, L.r, L.g, L.b);
        if (bounces >= set_.maxDepth) break;
        ++nVertices;

        if (!isect.material) {  // interface: continue straight through
            if (++crossings > kMaxInterfaceCrossings) {
                ++nStuck;
                break;
            }
            ray = isect.spawnRay(ray.d);
            --bounces;
            continue;
        }
        crossings = 0;
        BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
        if (!bsdf) break;
        const Vec3 wo = isect.wo;

        // Next-event estimation (skipped at purely specular vertices).
        if (bsdf.hasNonSpecular() && !scene.lights.empty()) {
            Float pmf;
            const Light *light = lightSampler_.sample(isect.p, sampler.get1D(), &pmf);
            Point2 uLight = sampler.get2D();
            LightLiSample ls;
            if (light && pmf > 0 && light->sampleLi(isect, uLight, &ls) && ls.pdf > 0) {
                Spectrum f = bsdf.f(wo, ls.wi) * AbsDot(ls.wi, isect.shading.n);
                if (!f.isBlack() && scene.unoccluded(isect, ls.pLight)) {
                    Float lightPdf = pmf * ls.pdf;
                    if (IsDeltaLight(light->flags)) {
                        L += beta * f * ls.L / lightPdf;
                    } else {
                        Float bsdfPdf = bsdf.pdf(wo, ls.wi);
                        L += beta * f * ls.L * (PowerHeuristic(1, lightPdf, 1, bsdfPdf) / lightPdf);
                    }
                }
            }
        } else if (bsdf.hasNonSpecular()) {
            sampler.get1D();
            sampler.get2D();
        }

        // BSDF sampling for the next direction.
        Float uc = sampler.get1D();
        Point2 u = sampler.get2D();
        BSDFSample bs;
        if (!bsdf.sample(wo, uc, u, TransportMode::Radiance, &bs) || !bs.valid()) break;
        beta *= bs.f * (AbsDot(bs.wi, isect.shading.n) / bs.pdf);
        specularBounce = bs.isSpecular();
        prevBsdfPdf = bs.pdf;
        prevIt = isect;
        if (bs.isTransmission()) etaScale *= Sqr(bs.eta);
        ray = isect.spawnRay(bs.wi);

        if (!survivesRoulette(&beta, etaScale, bounces, sampler)) break;
    }
    return L;
}

}  // namespace gradus
