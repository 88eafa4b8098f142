#include "integrators/whitted/whitted.h"

#include <cmath>

#include "core/stats.h"
#include "integrators/factories.h"
#include "lights/light.h"
#include "scene/scene.h"

namespace gradus {

ParamTable<WhittedSettings> WhittedParams() {
    using S = WhittedSettings;
    ParamTable<S> t("whitted");
    t.integer("maxdepth", &S::maxDepth, kDefaultMaxDepth, "maximum recursion depth of specular reflection and transmission",
              AtLeast(0));
    t.pixelBounds(&S::pixelBounds);
    return t;
}

std::vector<ParamInfo> WhittedParameters() { return WhittedParams().describe(); }
std::unique_ptr<Integrator> CreateWhittedIntegrator(const EntityDesc &desc) {
    return std::make_unique<WhittedIntegrator>(desc);
}

WhittedIntegrator::WhittedIntegrator(const EntityDesc &desc)
    : WhittedIntegrator(WhittedParams().parse(desc).maxDepth, desc.loc) {}

void WhittedIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    Ray ray;
    const Float w = scene_->camera->generateRay(cs, &ray);
    if (w == 0) return;
    rec.addRadiance(Li(ray, sampler, arena, 0) * w);
}

Spectrum WhittedIntegrator::Li(const Ray &cameraRay, Sampler &sampler, Arena &arena, int depth) const {
    const Scene &scene = *scene_;
    Ray ray = cameraRay;
    SurfaceInteraction isect;
    // Interfaces (no material) are crossed without counting a depth (pbrt-v3).
    const Scene::SurfaceHit hit = scene.intersectSurface(&ray, &isect);
    Spectrum L(0);
    if (hit == Scene::SurfaceHit::Miss) {
        for (const Light *light : scene.infiniteLights) L += light->Le(ray);
        return L;
    }
    if (hit == Scene::SurfaceHit::Stuck) return L;
    const BSDF bsdf = isect.material->getBSDF(isect, arena, TransportMode::Radiance);
    L += isect.Le(isect.wo);
    if (!bsdf) return L;
    if (!scene.lights.empty()) L += direct(isect, bsdf, sampler);
    if (depth + 1 < maxDepth_) L += specular(isect, bsdf, sampler, arena, depth);
    return L;
}

Spectrum WhittedIntegrator::direct(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler) const {
    Spectrum L(0);
    for (const auto &light : scene_->lights) {
        LightLiSample ls;
        const Point2 u = sampler.get2D();
        if (!light->sampleLi(isect, u, &ls) || !(ls.pdf > 0) || ls.L.isBlack()) continue;
        const Spectrum f = bsdf.f(isect.wo, ls.wi) * AbsDot(ls.wi, isect.shading.n);
        if (!f.isBlack() && scene_->unoccluded(isect, ls.pLight)) L += f * ls.L / ls.pdf;
    }
    return L;
}

Spectrum WhittedIntegrator::specular(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler,
                                     Arena &arena, int depth) const {
    GRADUS_STAT_COUNTER("Whitted/Specular splits (both lobes traced)", nSplit);
    const unsigned specularLobes = bsdf.flags() & BSDF_SPECULAR;
    const Float uc = sampler.get1D();
    const Point2 u = sampler.get2D();
    if (!specularLobes) return Spectrum(0);
    const Vec3 &wo = isect.wo;
    auto trace = [&](const BSDFSample &s, Float weightPdf) {
        const Spectrum fcos = s.f * AbsDot(s.wi, isect.shading.n);
        return fcos * Li(isect.spawnRay(s.wi), sampler, arena, depth + 1) / weightPdf;
    };
    if (bsdf.isSpecular()) {
        // Split a two-lobe specular BSDF: uc at both ends of [0, 1) selects each
        // lobe; the lobes' probabilities sum to 1, so each counts f |cos|.
        BSDFSample a, b;
        const bool okA = bsdf.sample(wo, 0, u, TransportMode::Radiance, &a) && a.valid() && a.isSpecular();
        const bool okB = bsdf.sample(wo, std::nextafter(Float(1), Float(0)), u, TransportMode::Radiance, &b) && b.valid() &&
                         b.isSpecular();
        if (okA && okB && a.flags != b.flags && std::abs(a.pdf + b.pdf - 1) < 1e-4f) {
            ++nSplit;
            return trace(a, 1) + trace(b, 1);
        }
        if (okA && okB && a.flags == b.flags && a.pdf == 1) return trace(a, 1);  // one lobe (mirror, total reflection)
    }
    BSDFSample s;
    if (!bsdf.sample(wo, uc, u, TransportMode::Radiance, &s) || !s.valid() || !s.isSpecular()) return Spectrum(0);
    return trace(s, s.pdf);
}

}  // namespace gradus
