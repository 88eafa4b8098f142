// The route from a scene file to a rendered image that the gradus command line
// and the Python module share, so that equal options give equal images (and
// equal provenance): load, build, resolve the sample count, render, record.
#pragma once
#include <memory>
#include <string>

#include "core/provenance.h"
#include "parser/gltf.h"
#include "parser/scene_desc.h"
#include "render/render_loop.h"
#include "job/job.h"

namespace gradus {

// Reads a pbrt-v3 or glTF 2.0 scene (by the file's extension) after clearing
// the record of input files: a render's provenance starts with its scene.
// The environment options (env.image read by LoadEnvironmentMap) turn the
// glTF default environment off and add --envmap's light.
SceneDesc LoadSceneFile(const std::string &file, const GltfOptions &gltf, const EnvironmentOptions &env = {});

// LoadSceneFile and BuildRenderJob; *seconds = the time both took (the
// output's scene_load_seconds).
RenderJob LoadRenderJob(const std::string &file, const GltfOptions &gltf, const BuildOptions &bo, double *seconds);

// A scene loaded and built once for many renders (the Python module's Scene).
// Each render builds its film, sampler and integrator anew and shares the
// Scene, which no render modifies (integrators receive it const; lights are
// preprocessed by the builder; per-render state such as light samplers lives
// in the integrator), so its images equal those of a freshly loaded scene.
struct LoadedScene {
    std::string file;
    GltfOptions gltf;
    SceneDesc desc;
    std::shared_ptr<Scene> scene;
    BuildOptions build;        // the options it was built with (resolution, crop, quick, environment)
    InputFilesSummary inputs;  // the files its load read (provenance)
    double seconds = 0;        // load and build
    // Whether a render with options bo can share it (equal scene-level options).
    bool sharesWith(const BuildOptions &bo) const;
};

// Loads and builds the scene (with bo's integrator: its refusals are raised
// here); *job, when given, receives that first job.
std::shared_ptr<LoadedScene> LoadScene(const std::string &file, const GltfOptions &gltf, const BuildOptions &bo,
                                       RenderJob *job = nullptr);

// A job on a kept scene (bo's scene-level options must be the scene's:
// sharesWith); *seconds = the time the job's build took.
RenderJob BuildLoadedJob(LoadedScene &scene, const BuildOptions &bo, double *seconds);

// The samples per pixel of the render: bo.sppOverride (--spp), else the
// sampler's; with a time budget and no --spp none (the budget alone ends it).
void ResolveSampleCount(const RenderJob &job, const BuildOptions &bo, RenderOptions *ro);

// Resets the statistics counters, renders (RenderJobImage) and records the
// invocation: metadata scene, command_line and scene_load_seconds.
RenderResult RenderLoadedJob(RenderJob &job, const RenderOptions &ro, const std::string &file,
                             const std::string &commandLine, double loadSeconds);

}  // namespace gradus
