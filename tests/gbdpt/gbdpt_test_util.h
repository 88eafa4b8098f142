// Helpers for the G-BDPT tests: in-memory renders of scene text and a small
// scene with diffuse walls, an area light, a glass sphere and a mirror sphere.
#pragma once
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "common/render_test_util.h"
#include "job/job.h"
#include "integrators/common/bidir.h"
#include "integrators/gradient/camera_shift.h"
#include "integrators/gradient/lighttracing_shift.h"
#include "lights/light.h"

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

// ---- Shared by test_shift.cpp and test_media.cpp ----
// Camera sample and ray of trial `trial`: a pixel of the 24x18 test film's
// interior, the sampler positioned there (same random numbers as before).
inline CameraSample TrialSample(Sampler &sampler, const Camera &camera, int trial, Ray *ray) {
    Point2i px{1 + trial % 21, 1 + (trial / 21) % 15};
    sampler.startPixelSample(px, trial, 0);
    CameraSample cs{Point2(px.x + sampler.get1D(), px.y + sampler.get1D()), sampler.get2D()};
    camera.generateRay(cs, ray);
    return cs;
}

// Arena storage for a subpath of up to n vertices (constructed, n = 0).
inline ShiftSubpath ArenaSubpath(Arena &arena, int n) {
    ShiftSubpath p;
    p.v = new (arena.alloc(sizeof(PathVertex) * n, alignof(PathVertex))) PathVertex[n];
    p.b = new (arena.alloc(sizeof(BSDF) * n, alignof(BSDF))) BSDF[n];
    p.deltaSample = static_cast<uint8_t *>(arena.alloc(n));
    return p;
}

// The light subpath that makes strategy (s, n - s) of a camera path x[0..n-1]
// ending on an emitter: the reversed tail x[n-1] .. x[n-s], densities swapped.
inline ShiftSubpath ReversedTail(const BidirContext &bc, const ShiftSubpath &x, int s, Arena &arena) {
    ShiftSubpath L = ArenaSubpath(arena, s);
    L.n = s;
    const int n = x.n;
    for (int j = 0; j < s; ++j) {
        const PathVertex &c = x.v[n - 1 - j];
        PathVertex &v = L.v[j];
        v = c;
        v.pdfFwd = c.pdfRev;
        v.pdfRev = c.pdfFwd;
        v.wo = Normalize(x.v[n - j].p - c.p);  // towards the previous light-subpath vertex
        if (j == 0) v.wo = Normalize(x.v[n - 2].p - c.p);
        L.b[j] = x.b[n - 1 - j];
        L.deltaSample[j] = x.deltaSample[n - 1 - j];
    }
    // The emitter as a light vertex, as light subpaths start (a light vertex
    // keeps its flags: infinite, delta position).
    const PathVertex &e = x.v[n - 1];
    L.v[0].type = VertexType::Light;
    L.v[0].light = e.isInfiniteLight() ? bc.scene->infiniteLights[0] : EmitterOf(bc, e);
    L.v[0].flags = e.type == VertexType::Light ? e.flags : 0;
    L.v[0].pdfFwd = PdfLightOrigin(bc, x.v[n - 1], x.v[n - 2]);
    if (s >= 2) L.v[1].pdfFwd = PdfLightDirection(bc, x.v[n - 1], x.v[n - 2]);
    return L;
}

// Sums over the strategies (s, t) of x of the combined weights times (1 +
// rho) (*sum) and of x's BDPT weights (*sumx). False when a light-tracing
// shift failed (the sums are then partial).
inline bool SumStrategyWeights(const SubpathShiftContext &sc, const BidirContext &bc, const ShiftSubpath &x,
                        const CameraShift &sh, const CameraSample &cs, bool lightTracing, Arena &arena,
                        SubpathShiftStats *st, double *sum, double *sumx, int *withLT, UniformSource rng = {}) {
    const int n = x.n;
    const PathVertex &e = x.v[n - 1];
    const bool pointEnd = e.isDeltaLight() && !e.isInfiniteLight();
    bool ok = true;
    for (int t = n; t >= 1 && ok; --t) {
        int s = n - t;
        if (s == 0 && pointEnd) continue;  // a point is never hit
        if (t >= 2 && s >= 1 && !IsDiffuseVertex(sc, x.v[t - 1], &x.b[t - 1])) continue;
        if (s >= 1 && !IsDiffuseVertex(sc, x.v[t], &x.b[t])) continue;
        ShiftSubpath L, Ly;  // s = 0: no light vertices
        if (s >= 1) {
            L = ReversedTail(bc, x, s, arena);
            Ly = ReversedTail(bc, sh.y, s, arena);
        }
        if (t >= 2) {
            if (s >= 1 && !EdgeConnectible(bc, x.v[t - 1], x.v[t])) continue;
            Float wx = MISWeight(bc, L.view(), SubpathView{x.v, x.b, t}, s, t, nullptr);
            Float wy = MISWeight(bc, Ly.view(), SubpathView{sh.y.v, sh.y.b, t}, s, t, nullptr);
            Float rho = sh.rho[t - 1];
            *sum += CombinedWeight(wx, wy, rho) * (1 + rho);
            *sumx += wx;
        } else if (lightTracing) {
            PathVertex lens = x.v[0];
            Float wx = MISWeight(bc, L.view(), SubpathView{&lens, nullptr, 1}, s, 1, &lens);
            Spectrum fy;
            Float wy = 0, rho = 0;
            // The lens raster position of x_1 is the camera sample's.
            ok = ShiftLightTracingPath(sc, L, s, lens, cs.pFilm, Spectrum(1), {1, 0}, arena, &fy, &wy, &rho, st, rng);
            if (!ok) break;
            *sum += CombinedWeight(wx, wy, rho) * (1 + rho);
            *sumx += wx;
            ++*withLT;
        }
    }
    return ok;
}

}  // namespace gradus::gbdpttest
