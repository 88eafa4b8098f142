// Helpers for the G-BDPT tests: in-memory renders of scene text and a small
// scene with diffuse walls, an area light, a glass sphere and a mirror sphere.
#pragma once
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "common/render_test_util.h"
#include "job/job.h"

namespace gradus::gbdpttest {

// With variance layers (the tests compare gradients against them).
inline RenderJob MakeJob(const std::string &text, int spp, uint64_t seed, const std::string &integrator = "") {
    return test::MakeTestJob(ParseString(text, "gbdpt_test.pbrt", "."), spp, seed, integrator, true);
}

inline Image Render(const std::string &text, int spp, uint64_t seed, const std::string &integrator = "",
                    std::string *statistics = nullptr) {
    test::TestRender r = test::RenderTestJob(MakeJob(text, spp, seed, integrator), spp, seed);
    if (statistics) *statistics = r.statistics;
    return std::move(r.image);
}

// Box scene (open towards the camera): matte walls, a small area light under
// the ceiling, a glass sphere (caustic: light -> glass -> floor seen by light
// tracing, and camera -> glass -> floor -> light) and a mirror sphere.
// roughGlass: the glass sphere is near-specular rough glass (roughness 0.0005,
// below the shift threshold: half-vector refraction in the first chain).
inline std::string BoxScene(const std::string &integratorLine, int w = 24, int h = 18, bool glossy = false,
                            bool roughGlass = false) {
    std::string mirror = glossy ? R"(Material "metal" "float roughness" [0.0005] "bool remaproughness" "false")"
                                : R"(Material "mirror")";
    std::string glass = roughGlass
                            ? R"(Material "glass" "float uroughness" [0.0005] "float vroughness" [0.0005] "bool remaproughness" "false")"
                            : R"(Material "glass")";
    return test::TestSceneHeader("0 1.1 -3.4  0 0.8 0  0 1 0", 45, w, h, integratorLine) + R"(
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [6 6 6]
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-0.4 1.95 -0.1  0.4 1.95 -0.1  0.4 1.95 0.6  -0.4 1.95 0.6]
AttributeEnd
Material "matte" "rgb Kd" [0.65 0.6 0.55]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-1.2 0 -1.5  1.2 0 -1.5  1.2 0 1.2  -1.2 0 1.2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-1.2 2 -1.5  -1.2 2 1.2  1.2 2 1.2  1.2 2 -1.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-1.2 0 1.2  1.2 0 1.2  1.2 2 1.2  -1.2 2 1.2]
Material "matte" "rgb Kd" [0.6 0.2 0.15]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-1.2 0 -1.5  -1.2 0 1.2  -1.2 2 1.2  -1.2 2 -1.5]
Material "matte" "rgb Kd" [0.15 0.5 0.2]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [1.2 0 -1.5  1.2 2 -1.5  1.2 2 1.2  1.2 0 1.2]
AttributeBegin
  )" + glass + R"(
  Translate 0.35 0.4 0.1
  Shape "sphere" "float radius" [0.4]
AttributeEnd
AttributeBegin
  )" + mirror + R"(
  Translate -0.5 0.35 0.5
  Shape "sphere" "float radius" [0.35]
AttributeEnd
WorldEnd
)";
}

// Open scene (no walls): a matte floor, a matte sphere, a glass sphere and a
// mirror sphere under a constant sky ("infinite"), with a point light (and,
// optionally, a sun: a distant light). Paths end on the environment
// (escaped camera subpaths, next-event estimation, light subpaths started at
// infinity) and at a point, so the environment shift and the reconnection to a
// point light are exercised by every strategy.
inline std::string EnvScene(const std::string &integratorLine, int w = 24, int h = 18, bool sun = false) {
    std::string distant = sun ? R"(LightSource "distant" "point from" [2 6 3] "point to" [0 0 0] "rgb L" [1.5 1.5 1.4])"
                              : "";
    return test::TestSceneHeader("0 1.4 -3.6  0 0.5 0  0 1 0", 45, w, h, integratorLine) + R"(
WorldBegin
LightSource "infinite" "rgb L" [0.5 0.55 0.7]
LightSource "point" "point from" [-0.6 1.6 -0.6] "rgb I" [1.2 1.1 1.0]
)" + distant + R"(
Material "matte" "rgb Kd" [0.6 0.6 0.55]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-3 0 -3  -3 0 3  3 0 3  3 0 -3]
AttributeBegin
  Material "matte" "rgb Kd" [0.6 0.25 0.15]
  Translate -0.55 0.3 0.2
  Shape "sphere" "float radius" [0.3]
AttributeEnd
AttributeBegin
  Material "glass"
  Translate 0.4 0.4 -0.1
  Shape "sphere" "float radius" [0.4]
AttributeEnd
AttributeBegin
  Material "mirror"
  Translate 0.1 0.25 0.8
  Shape "sphere" "float radius" [0.25]
AttributeEnd
WorldEnd
)";
}

}  // namespace gradus::gbdpttest
