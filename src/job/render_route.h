// The route from a scene file to a rendered image that the gradus command line
// and the Python module share, so that equal options give equal images (and
// equal provenance): load, build, resolve the sample count, render, record.
#pragma once
#include <string>

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

// The samples per pixel of the render: bo.sppOverride (--spp), else the
// sampler's; with a time budget and no --spp none (the budget alone ends it).
void ResolveSampleCount(const RenderJob &job, const BuildOptions &bo, RenderOptions *ro);

// Resets the statistics counters, renders (RenderJobImage) and records the
// invocation: metadata scene, command_line and scene_load_seconds.
RenderResult RenderLoadedJob(RenderJob &job, const RenderOptions &ro, const std::string &file,
                             const std::string &commandLine, double loadSeconds);

}  // namespace gradus
