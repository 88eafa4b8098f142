// Helpers for renderer tests: render a scene given as text, in memory.
#pragma once
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "render/scene_builder.h"

namespace gradus::test {

struct RenderResult {
    Image image;
    RenderStats stats;
};

inline RenderResult RenderDesc(const SceneDesc &desc, int spp, uint64_t seed, int nthreads,
                               const std::string &integrator) {
    BuildOptions bo;
    bo.sppOverride = spp;
    bo.seed = seed;
    bo.integratorOverride = integrator;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(desc, bo);
    RenderOptions ro;
    ro.spp = spp;
    ro.seed = seed;
    ro.nthreads = nthreads;
    ro.quiet = true;
    job.integrator->preprocess(*job.scene, *job.film);
    RenderResult r;
    r.stats = job.integrator->render(*job.scene, *job.film, *job.sampler, ro);
    r.image = job.film->toImage();
    job.integrator->finish(*job.film, &r.image);
    return r;
}

inline RenderResult RenderSceneText(const std::string &text, int spp, uint64_t seed = 0, int nthreads = 0,
                                    const std::string &integrator = "", const std::string &dir = ".") {
    return RenderDesc(ParseString(text, "test.pbrt", dir), spp, seed, nthreads, integrator);
}

inline RenderResult RenderSceneFile(const std::string &path, int spp, uint64_t seed = 0,
                                    const std::string &integrator = "") {
    return RenderDesc(ParseFile(path), spp, seed, 0, integrator);
}

// Mean and standard error of the mean of channel c over all pixels.
inline void PixelMeanAndStdErr(const Image &img, int c, double *mean, double *stderrOut) {
    double s = 0, s2 = 0;
    int n = img.width() * img.height();
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) {
            double v = img.at(x, y, c);
            s += v;
            s2 += v * v;
        }
    *mean = s / n;
    double var = std::max(0.0, s2 / n - *mean * *mean) * n / (n - 1);
    *stderrOut = std::sqrt(var / n);
}

}  // namespace gradus::test
