// The job layer: a parsed SceneDesc and the command line's options become a
// renderable job (Scene, Film, Sampler, Integrator), consuming every parameter
// (unused ones are located errors); RenderJobImage runs it to an image with
// its checkpoints and provenance.
#pragma once
#include <memory>
#include <string>

#include "core/provenance.h"
#include "image/image.h"
#include "job/environment.h"
#include "render/integrator.h"
#include "parser/scene_desc.h"
#include "render/film.h"
#include "scene/scene_builder.h"
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
    bool checkOutput = true;         // check that the output path is writable (off when no file is written)
    Point2i resolution{0, 0};        // --resolution (0: the Film's)
    bool quiet = false;
    // --variance: gradient integrators keep squared values and write primal_var,
    // dx_var, dy_var (also on with "reconstruction" "weighted", which reads them).
    bool variance = false;
    // --param NAME=VALUE: integrator parameters from the command line (replace the scene's).
    std::vector<std::string> paramOverrides;
    // --envmap, --envmap-scale, --envmap-rotate (job/environment.h): applied
    // to the SceneDesc when the scene file is loaded (render_route.h); recorded
    // here in the provenance.
    EnvironmentOptions environment;
};

struct RenderJob {
    std::shared_ptr<Scene> scene;  // shared by the jobs of a kept scene (render_route.h)
    std::unique_ptr<Film> film;
    std::unique_ptr<Sampler> sampler;
    std::unique_ptr<Integrator> integrator;
    // Notes for the user (always printed by gradus): e.g. scene parameters
    // that an --integrator override does not use.
    std::vector<std::string> warnings;
    // Provenance recorded in the output: resolved parameters of camera,
    // sampler, film, filter and integrator, resolution, crop, quick flag,
    // input files and their hash (RenderJobImage adds the render's figures).
    Metadata provenance;
    // What --envmap adds to the render's identity (checkpoints): "" without it.
    std::string environmentIdentity;
};

// With `scene`, that Scene (built by an earlier BuildRenderJob of the same
// desc with the same resolution, crop, quick and environment options) is
// shared instead of building one, and `inputs` (the files its load read) is
// recorded as the provenance of input files.
RenderJob BuildRenderJob(const SceneDesc &desc, const BuildOptions &opts, std::shared_ptr<Scene> scene = nullptr,
                         const InputFilesSummary *inputs = nullptr);

// A finished render: the film image with all layers after Integrator::finish,
// with the job's provenance and the render's figures as typed metadata
// (integrator, spp, seed, threads, render_seconds = everything after scene
// loading: preprocess + passes + finish, seconds_* per phase, cpu_seconds,
// stop_reason, nonfinite_discarded, output_values_clamped, peak_rss_mb).
struct RenderResult {
    Image image;
    RenderStats stats;
};
// Preprocess, the render loop, the film image and the integrator's finish:
// the one route from a built job to an image (gradus, tests, benchmarks).
// opts.timeLimit bounds all of it: the loop gets what preprocessing left,
// minus the integrator's estimate of its finish (e.g. reconstruction).
// Checkpoints (opts.checkpointFile, resumeFile, passBegin/passEnd): see
// job/checkpoint.h; a checkpoint of another render is refused.
RenderResult RenderJobImage(RenderJob &job, const RenderOptions &opts);
// The text that identifies a render for its checkpoints.
std::string RenderIdentity(const RenderJob &job, const RenderOptions &opts);

// --param NAME=VALUE overrides for the integrator entity (typed by its
// parameter table; located errors name the command line).
void ApplyParamOverrides(const std::vector<std::string> &overrides, EntityDesc *integrator);

}  // namespace gradus
