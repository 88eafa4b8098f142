#include "job/render_route.h"

#include <chrono>

#include "core/provenance.h"
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
