// Helpers of the MLT tests: small scenes written in code, in-memory renders
// with the loop's options exposed, image luminance in the film's coefficients.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/render_test_util.h"
#include "image/image.h"
#include "integrators/mlt/mlt.h"
#include "parser/scene_desc.h"
#include "job/job.h"

namespace gradus::mlt_test {

using test::Quad;

// Closed box [-1,1] x [0,2] x [-1,1.2] seen from inside, a ceiling light
// (`light`: "" none, "open" facing down, "up" facing the ceiling, "sealed"
// inside a closed box of its own), a diffuse and a glossy sphere. `integratorLine` is the full directive.
inline std::string BoxScene(const std::string &integratorLine, int res = 12, const std::string &light = "open",
                            const std::string &sampler = "Sampler \"random\" \"integer pixelsamples\" [4]") {
    char film[200];
    std::snprintf(film, sizeof film,
                  "Film \"image\" \"integer xresolution\" [%d] \"integer yresolution\" [%d] "
                  "\"string filename\" [\"unused.exr\"]\n",
                  res, res);
    std::string s = integratorLine + "\n" + sampler + "\nPixelFilter \"box\"\n" + film;
    s += "LookAt 0 1 1.15  0 0.9 0  0 1 0\nCamera \"perspective\" \"float fov\" [70]\nWorldBegin\n";
    // Facing down, or ("up") facing the ceiling 2 cm above: the room is lit through that gap only.
    const char *lightQuad = light == "up" ? "-0.4 1.98 -0.4  -0.4 1.98 0.4  0.4 1.98 0.4  0.4 1.98 -0.4"
                                          : "-0.4 1.98 -0.4  0.4 1.98 -0.4  0.4 1.98 0.4  -0.4 1.98 0.4";
    if (!light.empty())
        s += "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [6 6 6]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [" +
             std::string(lightQuad) + "]\nAttributeEnd\n";
    if (light == "sealed")  // a closed black cube around the light
        s += "AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\nTranslate 0 1.9 0\n"
             "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  1 5 6 1 6 2  "
             "2 6 7 2 7 3  3 7 4 3 4 0] \"point P\" [-0.5 -0.05 -0.5  0.5 -0.05 -0.5  0.5 -0.05 0.5  -0.5 -0.05 0.5  "
             "-0.5 0.09 -0.5  0.5 0.09 -0.5  0.5 0.09 0.5  -0.5 0.09 0.5]\nAttributeEnd\n";
    s += test::ClosedBoxWallsAndSphere();
    s += "AttributeBegin\nMaterial \"plastic\" \"rgb Kd\" [0.2 0.3 0.5] \"rgb Ks\" [0.5 0.5 0.5] "
         "\"float roughness\" [0.08]\nTranslate -0.45 0.3 -0.4\nShape \"sphere\" \"float radius\" [0.3]\n"
         "AttributeEnd\n";
    s += "WorldEnd\n";
    return s;
}

// "Integrator "mlt" ..." with the given extra parameters.
inline std::string MLTLine(const std::string &params) { return "Integrator \"mlt\" " + params; }

struct Rendered {
    Image image;
    RenderStats stats;
    std::string statistics;
    std::unique_ptr<Integrator> integrator;
    const MLTIntegrator &mlt() const { return dynamic_cast<const MLTIntegrator &>(*integrator); }
};

// In-memory render; spp 0 = the job's own count (no --spp), timeLimit > 0 = --time.
inline Rendered Render(const std::string &text, int spp, uint64_t seed, int nthreads = 2, int sppPerPass = 1,
                       double timeLimit = 0) {
    BuildOptions bo;
    bo.sppOverride = spp;
    bo.seed = seed;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseString(text), bo);
    RenderOptions ro;
    ro.spp = spp > 0 ? spp : (timeLimit > 0 ? 0 : job.sampler->samplesPerPixel());
    ro.nthreads = nthreads;
    ro.quiet = true;
    ro.sppPerPass = sppPerPass;
    ro.timeLimit = timeLimit;
    RenderResult res = RenderJobImage(job, ro);
    Rendered r;
    r.image = std::move(res.image);
    r.stats = res.stats;
    r.statistics = job.integrator->statistics();
    r.integrator = std::move(job.integrator);
    return r;
}

// Luminance with the film's own coefficients (Spectrum::y).
inline double Lum(const Image &img, int x, int y) {
    return Spectrum(img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)).y();
}
inline double MeanLum(const Image &img, int x0, int y0, int x1, int y1) {
    double s = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) s += Lum(img, x, y);
    return s / (double(x1 - x0) * (y1 - y0));
}
inline double MeanLum(const Image &img) { return MeanLum(img, 0, 0, img.width(), img.height()); }

}  // namespace gradus::mlt_test
