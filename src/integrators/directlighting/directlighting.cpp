#include "integrators/directlighting/directlighting.h"

#include <algorithm>

#include "integrators/factories.h"
#include "lights/light.h"
#include "samplers/sampling.h"
#include "scene/scene.h"

namespace gradus {

ParamTable<DirectLightingSettings> DirectLightingParams() {
    using S = DirectLightingSettings;
    ParamTable<S> t("direct lighting");
    t.integer("maxdepth", &S::maxDepth, kDefaultMaxDepth, "maximum recursion depth of specular reflection and transmission",
              AtLeast(0));
    t.enumeration("strategy", &S::strategy, "all", {"all", "one"},
                  "all: every light, with its \"samples\" count; one: one light chosen uniformly");
    t.pixelBounds(&S::pixelBounds);
    return t;
}

std::vector<ParamInfo> DirectLightingParameters() { return DirectLightingParams().describe(); }
std::unique_ptr<Integrator> CreateDirectLightingIntegrator(const EntityDesc &desc) {
    return std::make_unique<DirectLightingIntegrator>(desc);
}

DirectLightingIntegrator::DirectLightingIntegrator(const EntityDesc &desc)
    : DirectLightingIntegrator(DirectLightingParams().parse(desc), desc.loc) {}

DirectLightingIntegrator::DirectLightingIntegrator(const DirectLightingSettings &set, const FileLoc &loc)
    : WhittedIntegrator(set.maxDepth, loc), sampleAll_(set.strategy == "all") {}

Spectrum DirectLightingIntegrator::direct(const SurfaceInteraction &isect, const BSDF &bsdf, Sampler &sampler) const {
    const auto &lights = scene_->lights;
    if (!sampleAll_) {
        // One light, chosen uniformly (pbrt-v3's UniformSampleOneLight): divided by its probability 1/n.
        const int n = int(lights.size());
        const int i = std::min(int(sampler.get1D() * n), n - 1);
        return estimateDirect(isect, bsdf, *lights[i], sampler) * Float(n);
    }
    Spectrum L(0);
    for (const auto &light : lights) {
        Spectrum Ld(0);
        for (int k = 0; k < light->nSamples; ++k) Ld += estimateDirect(isect, bsdf, *light, sampler);
        L += Ld / Float(light->nSamples);
    }
    return L;
}

Spectrum DirectLightingIntegrator::estimateDirect(const SurfaceInteraction &isect, const BSDF &bsdf,
                                                  const Light &light, Sampler &sampler) const {
    const Scene &scene = *scene_;
    const Vec3 &wo = isect.wo;
    const Normal3 &ns = isect.shading.n;
    const Point2 uLight = sampler.get2D();
    const Float uc = sampler.get1D();
    const Point2 uScatter = sampler.get2D();
    Spectrum Ld(0);
    // Light sample, weighted against the BSDF sample (power heuristic, Veach 1997 Eq. 9.13).
    LightLiSample ls;
    if (light.sampleLi(isect, uLight, &ls) && ls.pdf > 0 && !ls.L.isBlack()) {
        const Spectrum f = bsdf.f(wo, ls.wi) * AbsDot(ls.wi, ns);
        if (!f.isBlack() && scene.unoccluded(isect, ls.pLight)) {
            if (IsDeltaLight(light.flags))
                Ld += f * ls.L / ls.pdf;
            else
                Ld += f * ls.L * (PowerHeuristic(1, ls.pdf, 1, bsdf.pdf(wo, ls.wi)) / ls.pdf);
        }
    }
    if (IsDeltaLight(light.flags)) return Ld;
    // BSDF sample (non-specular lobes only: the specular ones are the recursion's),
    // weighted against the light sample.
    BSDFSample bs;
    if (!bsdf.sample(wo, uc, uScatter, TransportMode::Radiance, &bs) || !bs.valid() || bs.isSpecular()) return Ld;
    const Float lightPdf = light.pdfLi(isect, bs.wi);
    if (!(lightPdf > 0)) return Ld;
    const Ray ray = isect.spawnRay(bs.wi);
    SurfaceInteraction hit;
    Spectrum Li(0);
    if (scene.intersect(ray, &hit)) {
        if (static_cast<const Light *>(hit.areaLight) == &light) Li = hit.Le(-bs.wi);
    } else {
        Li = light.Le(ray);  // infinite lights; zero for the others
    }
    if (!Li.isBlack())
        Ld += bs.f * Li * (AbsDot(bs.wi, ns) * PowerHeuristic(1, bs.pdf, 1, lightPdf) / bs.pdf);
    return Ld;
}

}  // namespace gradus
