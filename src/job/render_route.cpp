#include "job/render_route.h"

#include <chrono>

#include "core/error.h"
#include "core/stats.h"

namespace gradus {

SceneDesc LoadSceneFile(const std::string &file, const GltfOptions &gltf, const EnvironmentOptions &env) {
    ResetInputFiles();
    const bool isGltf = IsGltfFile(file);
    GltfOptions g = gltf;
    if (env.given()) g.defaultEnvironment = false;
    SceneDesc desc = isGltf ? LoadGltfScene(file, g) : ParseFile(file);
    AddEnvironmentLight(env, isGltf, &desc);
    return desc;
}

namespace {
double SecondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

RenderJob LoadRenderJob(const std::string &file, const GltfOptions &gltf, const BuildOptions &bo, double *seconds) {
    const auto t0 = std::chrono::steady_clock::now();
    SceneDesc desc = LoadSceneFile(file, gltf, bo.environment);
    RenderJob job = BuildRenderJob(desc, bo);
    *seconds = SecondsSince(t0);
    return job;
}

bool LoadedScene::sharesWith(const BuildOptions &bo) const {
    const BuildOptions &a = build;
    if (a.quick != bo.quick || a.hasCrop != bo.hasCrop || !(a.resolution == bo.resolution)) return false;
    for (int i = 0; i < 4; ++i)
        if (a.hasCrop && a.crop[i] != bo.crop[i]) return false;
    const EnvironmentOptions &e = a.environment, &f = bo.environment;
    return e.map == f.map && e.scale == f.scale && e.rotateDegrees == f.rotateDegrees;
}

std::shared_ptr<LoadedScene> LoadScene(const std::string &file, const GltfOptions &gltf, const BuildOptions &bo,
                                       RenderJob *jobOut) {
    const auto t0 = std::chrono::steady_clock::now();
    auto s = std::make_shared<LoadedScene>();
    s->file = file;
    s->gltf = gltf;
    s->build = bo;
    s->desc = LoadSceneFile(file, gltf, bo.environment);
    s->inputs = InputFiles();
    RenderJob job = BuildRenderJob(s->desc, bo);
    s->scene = job.scene;
    s->seconds = SecondsSince(t0);
    if (jobOut) *jobOut = std::move(job);
    return s;
}

RenderJob BuildLoadedJob(LoadedScene &s, const BuildOptions &bo, double *seconds) {
    GRADUS_CHECK(s.sharesWith(bo));
    const auto t0 = std::chrono::steady_clock::now();
    RenderJob job = BuildRenderJob(s.desc, bo, s.scene, &s.inputs);
    *seconds = SecondsSince(t0);
    return job;
}

void ResolveSampleCount(const RenderJob &job, const BuildOptions &bo, RenderOptions *ro) {
    if (bo.sppOverride > 0) ro->spp = bo.sppOverride;
    if (ro->spp <= 0) ro->spp = job.sampler->samplesPerPixel();
    if (ro->timeLimit > 0 && bo.sppOverride <= 0) ro->spp = 0;  // time budget alone
}

RenderResult RenderLoadedJob(RenderJob &job, const RenderOptions &ro, const std::string &file,
                             const std::string &commandLine, double loadSeconds) {
    StatRegistry::get().reset();
    RenderResult res = RenderJobImage(job, ro);
    Metadata &m = res.image.metadata;
    m["scene"] = file;
    m["command_line"] = commandLine;
    m["scene_load_seconds"] = MetaValue::Double(loadSeconds);
    return res;
}

}  // namespace gradus
