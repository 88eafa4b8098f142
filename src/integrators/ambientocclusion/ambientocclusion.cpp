#include "integrators/ambientocclusion/ambientocclusion.h"

#include "integrators/factories.h"
#include "samplers/sampling.h"
#include "scene/scene.h"

namespace gradus {

ParamTable<AOSettings> AOParams() {
    using S = AOSettings;
    ParamTable<S> t("ambient occlusion");
    t.boolean("cossample", &S::cosSample, true, "cosine-weighted directions (false: uniform over the hemisphere)");
    t.integer("nsamples", &S::nSamples, 64, "directions per camera sample", AtLeast(1));
    t.pixelBounds(&S::pixelBounds);
    return t;
}

std::vector<ParamInfo> AmbientOcclusionParameters() { return AOParams().describe(); }
std::unique_ptr<Integrator> CreateAmbientOcclusionIntegrator(const EntityDesc &desc) {
    return std::make_unique<AOIntegrator>(desc);
}

AOIntegrator::AOIntegrator(const EntityDesc &desc) : set_(AOParams().parse(desc)) {}

void AOIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &, SampleRecorder &rec) const {
    Ray ray;
    const Float w = scene_->camera->generateRay(cs, &ray);
    if (w == 0) return;
    rec.addRadiance(Spectrum(occlusion(ray, sampler) * w));
}

Float AOIntegrator::occlusion(const Ray &cameraRay, Sampler &sampler) const {
    Ray ray = cameraRay;
    SurfaceInteraction isect;
    // Surfaces without a material (medium interfaces) are passed through.
    if (scene_->intersectSurface(&ray, &isect) != Scene::SurfaceHit::Hit) return 0;
    const Frame frame(FaceForward(isect.n, -ray.d));
    Float sum = 0;
    for (int i = 0; i < set_.nSamples; ++i) {
        const Point2 u = sampler.get2D();
        const Vec3 local = set_.cosSample ? SampleCosineHemisphere(u) : SampleUniformHemisphere(u);
        const Float pdf = set_.cosSample ? CosineHemispherePdf(local.z) : UniformHemispherePdf();
        if (!(pdf > 0)) continue;
        const Vec3 wi = frame.toWorld(local);
        // Monte Carlo estimate of the integral of V(wi) cos over the hemisphere.
        if (!scene_->occluded(isect.spawnRay(wi))) sum += local.z / pdf;
    }
    return sum / Float(set_.nSamples);
}

}  // namespace gradus
