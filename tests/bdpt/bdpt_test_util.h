// Shared helpers of the BDPT tests: small scenes built in code and
// independent-run statistics for z-tests.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "render/render_loop.h"
#include "common/render_test_util.h"
#include "job/job.h"

namespace gradus::bdpt_test {

inline std::string Quad(const std::string &mat, const char *P, const char *N = nullptr) {
    std::string s = "AttributeBegin\n" + mat + "\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [" + P + "]";
    if (N) s += std::string(" \"normal N\" [") + N + "]";
    return s + "\nAttributeEnd\n";
}

// Box [-1,1] x [0,2] x [-1,1] open towards +z, camera at z = 3.5.
// `floorNormals` tilts the floor's shading normals (tests the adjoint correction).
inline std::string BoxScene(const std::string &integrator, const std::string &lights, const std::string &objects,
                            int res = 16, const std::string &camera = "Camera \"perspective\" \"float fov\" [40]",
                            bool floorNormals = false, const std::string &floorMat = "Material \"matte\" \"rgb Kd\" [0.7 0.7 0.7]",
                            const char *floorNormalValues = "0.35 1 0.2  0.35 1 0.2  -0.2 1 -0.3  -0.2 1 -0.3") {
    std::string s = "Integrator \"" + integrator + "\" \"integer maxdepth\" [4]\n";
    s += "Sampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n";
    s += "Film \"image\" \"integer xresolution\" [" + std::to_string(res) + "] \"integer yresolution\" [" +
         std::to_string(res) + "] \"string filename\" [\"unused.exr\"]\n";
    s += "LookAt 0 1 3.5  0 1 0  0 1 0\n" + camera + "\nWorldBegin\n";
    s += lights;
    s += Quad(floorMat, "-1 0 -1  -1 0 1  1 0 1  1 0 -1",
              floorNormals ? floorNormalValues : nullptr);
    s += Quad("Material \"matte\" \"rgb Kd\" [0.7 0.7 0.7]", "-1 2 -1  1 2 -1  1 2 1  -1 2 1");
    s += Quad("Material \"matte\" \"rgb Kd\" [0.7 0.7 0.7]", "-1 0 -1  1 0 -1  1 2 -1  -1 2 -1");
    s += Quad("Material \"matte\" \"rgb Kd\" [0.63 0.065 0.05]", "-1 0 -1  -1 2 -1  -1 2 1  -1 0 1");
    s += Quad("Material \"matte\" \"rgb Kd\" [0.14 0.45 0.09]", "1 0 -1  1 0 1  1 2 1  1 2 -1");
    s += objects;
    return s + "WorldEnd\n";
}

inline std::string CeilingLight(Float half = 0.3, Float L = 10) {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [%g %g %g]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
                  "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [%g 1.98 %g  %g 1.98 %g  %g 1.98 %g  %g 1.98 %g]\n"
                  "AttributeEnd\n",
                  L, L, L, -half, -half, half, -half, half, half, -half, half);
    return buf;
}

inline std::string Sphere(const std::string &mat, Float x, Float y, Float z, Float r) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "AttributeBegin\n%s\nTranslate %g %g %g\nShape \"sphere\" \"float radius\" [%g]\nAttributeEnd\n",
                  mat.c_str(), x, y, z, r);
    return buf;
}

// Renders `text` with the given integrator; returns the film image (with layers).
// Renders `text` with the given integrator (one thread); returns the film image (with layers).
inline Image Render(const std::string &text, const std::string &integrator, int spp, uint64_t seed,
                    const std::string &extraParams = "") {
    return test::RenderTestDesc(ParseString(text), spp, seed, 1, integrator).image;
}

using test::BlockMean;
using test::RunStats;
using test::Stats;
// Welch z statistic of two sets of independent runs.
inline double ZScore(const RunStats &a, const RunStats &b) {
    double se = std::sqrt(a.var / a.n + b.var / b.n);
    return se > 0 ? (a.mean - b.mean) / se : (a.mean == b.mean ? 0 : 1e9);
}

}  // namespace gradus::bdpt_test
