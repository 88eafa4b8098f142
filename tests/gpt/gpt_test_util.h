// Helpers for the G-PT tests: in-memory renders of scene text.
#pragma once
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "common/render_test_util.h"
#include "job/job.h"

namespace gradus::gpttest {

inline Image Render(const std::string &text, int spp, uint64_t seed, const std::string &integrator = "",
                    std::string *statistics = nullptr) {
    test::TestRender r =  // with variance layers (the tests compare gradients against them)
        test::RenderTestDesc(ParseString(text, "gpt_test.pbrt", "."), spp, seed, 0, integrator, true);
    if (statistics) *statistics = r.statistics;
    return std::move(r.image);
}

// Small scene exercising every shift: diffuse walls (reconnection), an
// environment light (environment shift), a near-specular metal sphere
// (half-vector reflection), a smooth glass sphere (replay of specular lobes),
// a near-specular rough glass sphere (half-vector refraction), an area light
// and a point light.
inline std::string ShiftScene(const std::string &integratorLine, int w = 20, int h = 16) {
    return test::TestSceneHeader("0 1 -3.2  0 0.7 0  0 1 0", 50, w, h, integratorLine) + R"(
WorldBegin
LightSource "infinite" "rgb L" [0.3 0.35 0.4]
LightSource "point" "point from" [0.9 1.7 -1.2] "rgb I" [0.6 0.6 0.6]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [5 5 5] "bool twosided" "true"
  Material "matte" "rgb Kd" [0 0 0]
  Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
    "point P" [-0.5 2 -0.5  0.5 2 -0.5  0.5 2 0.5  -0.5 2 0.5]
AttributeEnd
Material "matte" "rgb Kd" [0.6 0.55 0.5]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-2 0 -2  2 0 -2  2 0 1.5  -2 0 1.5]
Material "matte" "rgb Kd" [0.3 0.5 0.6]
Shape "trianglemesh" "integer indices" [0 1 2 0 2 3]
  "point P" [-2 0 1.5  2 0 1.5  2 2.5 1.5  -2 2.5 1.5]
AttributeBegin
  Material "metal" "float roughness" [0.0005] "bool remaproughness" "false"
  Translate -0.75 0.45 0.2
  Shape "sphere" "float radius" [0.45]
AttributeEnd
AttributeBegin
  Material "glass"
  Translate 0.6 0.35 -0.3
  Shape "sphere" "float radius" [0.35]
AttributeEnd
AttributeBegin
  Material "glass" "float uroughness" [0.0005] "float vroughness" [0.0005] "bool remaproughness" "false"
  Translate 0.05 0.25 -0.9
  Shape "sphere" "float radius" [0.25]
AttributeEnd
WorldEnd
)";
}

}  // namespace gradus::gpttest
