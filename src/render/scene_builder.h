// Turns a parsed SceneDesc into a renderable Scene, Film, Sampler and
// Integrator, consuming every parameter (unused ones are located errors).
#pragma once
#include <memory>
#include <string>

#include "image/image.h"
#include "integrators/integrator.h"
#include "parser/scene_desc.h"
#include "render/film.h"
#include "render/scene.h"
#include "samplers/sampler.h"

namespace gradus {

struct BuildOptions {
    std::string integratorOverride;  // --integrator
    int sppOverride = 0;             // --spp
    uint64_t seed = 0;
    bool quick = false;              // --quick: 1/4 resolution, 1/8 spp
    bool hasCrop = false;            // --cropwindow
    Float crop[4] = {0, 1, 0, 1};
    std::string outfileOverride;     // --outfile
    bool quiet = false;
};

struct RenderJob {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Film> film;
    std::unique_ptr<Sampler> sampler;
    std::unique_ptr<Integrator> integrator;
    std::vector<std::string> warnings;
};

RenderJob BuildRenderJob(const SceneDesc &desc, const BuildOptions &opts);

// A finished render: the film image with all layers after Integrator::finish,
// with metadata (integrator, spp, seed, render_seconds, nonfinite_discarded).
struct RenderResult {
    Image image;
    RenderStats stats;
};
// Preprocess, the render loop, the film image and the integrator's finish:
// the one route from a built job to an image (gradus, tests, benchmarks).
RenderResult RenderJobImage(RenderJob &job, const RenderOptions &opts);

// Builds only the scene (geometry, materials, lights, camera) for the given film resolution.
std::unique_ptr<Scene> BuildScene(const SceneDesc &desc, Point2i resolution);

}  // namespace gradus
