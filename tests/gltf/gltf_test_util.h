// Shared parts of the glTF tests: the generated files (GLTF_TEST_DATA, written
// by make_gltf.py, whose constants are repeated here), parameter access
// without marking parameters used, and the analytic light checks.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "lights/light.h"
#include "parser/gltf.h"
#include "parser/scene_desc.h"

namespace gradus::gltftest {

inline std::string Data(const std::string &name) { return std::string(GLTF_TEST_DATA) + "/" + name; }
inline SceneDesc Load(const std::string &name, const std::string &camera = "", bool defaultEnvironment = true) {
    GltfOptions o;
    o.camera = camera;
    o.defaultEnvironment = defaultEnvironment;
    return LoadGltfScene(Data(name), o);
}
inline std::string ReadText(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// The parameter `name` of `ps` (nullptr if absent), not marked used.
inline const Param *Find(const ParamSet &ps, const std::string &name) {
    for (const auto &p : ps.all())
        if (p.name == name) return &p;
    return nullptr;
}
inline std::vector<double> Numbers(const ParamSet &ps, const std::string &name) {
    const Param *p = Find(ps, name);
    return p ? p->numbers : std::vector<double>{};
}
inline std::string String(const ParamSet &ps, const std::string &name) {
    const Param *p = Find(ps, name);
    return p && !p->strings.empty() ? p->strings[0] : "";
}

// ---------------------------------------------------------------- lights.gltf
// make_gltf.py's constants.
constexpr double kColor[3] = {1.0, 0.5, 0.25};
constexpr double kPointI = 20, kSpotI = 50, kDirI = 3, kSpotInner = 0.3, kSpotOuter = 0.6, kDirAngle = 0.8;

inline Interaction RefAt(const Point3 &p) { return Interaction(p, Normal3(0, 0, 0), Vec3(0, 0, 0)); }

inline void ExpectSpectrum(const Spectrum &s, double scale, const std::string &what) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(s[c], kColor[c] * scale, 1e-9 * (1 + scale)) << what << " channel " << c;
}

// Checks the three lights of lights.gltf (in file order: point, spot, directional)
// against KHR_lights_punctual's definitions: a point light of intensity I gives
// I / d^2 at distance d; a spot light that times the falloff
// clamp((cos t - cos outer) / (cos inner - cos outer), 0, 1)^2; a directional
// light an irradiance of its intensity from the node's +Z side.
inline void CheckPunctualLights(const std::vector<const Light *> &lights) {
    ASSERT_EQ(lights.size(), 3u);
    const Light &point = *lights[0], &spot = *lights[1], &sun = *lights[2];
    EXPECT_TRUE(point.flags & LIGHT_DELTA_POSITION);
    EXPECT_TRUE(spot.flags & LIGHT_DELTA_POSITION);
    EXPECT_TRUE(sun.flags & LIGHT_DELTA_DIRECTION);
    // Point light at (0, 2, 0).
    for (const Point3 &p : {Point3(0.3, -1, 0.4), Point3(5, 2, 0), Point3(-0.1, 2.2, 0.05)}) {
        LightLiSample s;
        ASSERT_TRUE(point.sampleLi(RefAt(p), Point2(0.5, 0.5), &s));
        Vec3 d(0 - p.x, 2 - p.y, 0 - p.z);
        double d2 = d.x * d.x + d.y * d.y + d.z * d.z, len = std::sqrt(d2);
        ExpectSpectrum(s.L, kPointI / d2, "point light");
        EXPECT_NEAR(s.wi.x, d.x / len, 1e-12);
        EXPECT_NEAR(s.wi.y, d.y / len, 1e-12);
        EXPECT_NEAR(s.wi.z, d.z / len, 1e-12);
    }
    // Spot light at (0, 3, 0) along -Y: inside the inner cone, between the cones, outside.
    const double ci = std::cos(kSpotInner), co = std::cos(kSpotOuter);
    for (double theta : {0.0, 0.2, 0.35, 0.45, 0.55, 0.59, 0.65, 1.2}) {
        for (double phi : {0.0, 2.0}) {
            const double d = 1.7;
            Point3 p(d * std::sin(theta) * std::cos(phi), 3 - d * std::cos(theta), d * std::sin(theta) * std::sin(phi));
            double t = std::min(1.0, std::max(0.0, (std::cos(theta) - co) / (ci - co)));
            LightLiSample s;
            bool ok = spot.sampleLi(RefAt(p), Point2(0.5, 0.5), &s);
            if (t == 0) {
                EXPECT_TRUE(!ok || s.L.isBlack()) << "theta " << theta;
                continue;
            }
            ASSERT_TRUE(ok) << "theta " << theta;
            ExpectSpectrum(s.L, kSpotI * t * t / (d * d), "spot light at theta " + std::to_string(theta));
        }
    }
    // Directional light: the node's -Z turned by 0.8 rad about +X travels along
    // (0, sin 0.8, -cos 0.8); light arrives from the opposite direction.
    LightLiSample s;
    ASSERT_TRUE(sun.sampleLi(RefAt(Point3(0.2, -0.3, 0.1)), Point2(0.5, 0.5), &s));
    ExpectSpectrum(s.L, kDirI, "directional light");
    EXPECT_NEAR(s.wi.x, 0, 1e-12);
    EXPECT_NEAR(s.wi.y, -std::sin(kDirAngle), 1e-12);
    EXPECT_NEAR(s.wi.z, std::cos(kDirAngle), 1e-12);
}

}  // namespace gradus::gltftest
