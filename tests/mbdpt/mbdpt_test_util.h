// Helpers of the M-BDPT tests: a small box scene written in code, in-memory
// renders, block means and Welch z statistics of independent runs.
#pragma once
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "image/image.h"
#include "render/integrator.h"
#include "parser/scene_desc.h"
#include "common/render_test_util.h"
#include "job/job.h"

namespace gradus::mbdpt_test {

using test::Quad;

// Closed box [-1,1] x [0,2] x [-1,1.2] with a small ceiling light, a diffuse
// sphere, a glossy sphere and (optionally) a mirror sphere, camera inside the box.
// `integratorLine` is the full Integrator directive.
inline std::string BoxScene(const std::string &integratorLine, int res = 16, bool mirror = true) {
    char film[256];
    std::snprintf(film, sizeof film,
                  "Film \"image\" \"integer xresolution\" [%d] \"integer yresolution\" [%d] \"string filename\" [\"unused.exr\"]\n",
                  res, res);
    std::string s = integratorLine + "\nSampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n" + film;
    s += "LookAt 0 1 1.15  0 0.9 0  0 1 0\nCamera \"perspective\" \"float fov\" [70]\nWorldBegin\n";
    s += "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [12 12 12]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
         "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-0.25 1.98 -0.25  -0.25 1.98 0.25  0.25 1.98 0.25  0.25 1.98 -0.25]\n"
         "AttributeEnd\n";
    s += test::ClosedBoxWallsAndSphere();
    s += "AttributeBegin\nMaterial \"plastic\" \"rgb Kd\" [0.2 0.3 0.5] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.08]\n"
         "Translate -0.45 0.3 -0.4\nShape \"sphere\" \"float radius\" [0.3]\nAttributeEnd\n";
    if (mirror) s += "AttributeBegin\nMaterial \"mirror\"\nTranslate 0 0.2 0.2\nShape \"sphere\" \"float radius\" [0.2]\nAttributeEnd\n";
    s += "WorldEnd\n";
    return s;
}

using Rendered = test::TestRender;

inline Rendered Render(const std::string &text, int spp, uint64_t seed, int nthreads = 1) {
    return test::RenderTestDesc(ParseString(text), spp, seed, nthreads);
}

using test::BlockMean;
using test::RunStats;
using test::Stats;
// Welch z statistic of two sets of independent runs.
inline double ZScore(const RunStats &a, const RunStats &b) {
    double se = std::sqrt(a.var / a.n + b.var / b.n);
    return se > 0 ? (a.mean - b.mean) / se : (a.mean == b.mean ? 0 : 1e9);
}

}  // namespace gradus::mbdpt_test
