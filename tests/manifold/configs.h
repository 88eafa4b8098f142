// Analytic chain configurations shared by the manifold tests and benchmarks.
#pragma once
#include <string>
#include <vector>

#include "analytic_scene.h"

namespace gradus::testing {

struct ChainConfig {
    std::string name;
    AnalyticScene scene;
    ManifoldChain base;
    ManifoldSurfacePoint target;  // a moved end vertex for walk tests
    Vec3 targetShift;             // target = moveOn(base end, targetShift)
};

// Rebuild a chain's frames (from dpdu) and offsets from its points and flags.
inline bool Rebuild(ManifoldChain *c) {
    std::vector<ManifoldSurfacePoint> pts;
    std::vector<char> refl, spec;
    for (int i = 0; i < c->size; ++i) {
        pts.push_back(c->v[i].sp);
        if (i > 0 && i < c->size - 1) {
            refl.push_back(c->v[i].reflect);
            spec.push_back(c->v[i].specular);
        }
    }
    bool r[kMaxManifoldVertices], s[kMaxManifoldVertices];
    for (size_t i = 0; i < refl.size(); ++i) { r[i] = refl[i]; s[i] = spec[i]; }
    return MakeChain(pts.data(), c->size, r, s, c);
}

// Trace an ideal specular chain from `start` towards `aim` through the listed
// primitives (last id = end surface) and rebuild it.
inline bool TraceSpecular(const AnalyticScene &scene, const ManifoldSurfacePoint &start,
                          const Point3 &aim, const std::vector<int> &ids,
                          const std::vector<bool> &reflect, ManifoldChain *out) {
    ManifoldChain tmpl;
    tmpl.size = int(ids.size()) + 1;
    if (tmpl.size > kMaxManifoldVertices) return false;
    SetupManifoldVertex(&tmpl.v[0], start);
    for (size_t i = 0; i < ids.size(); ++i) {
        ManifoldVertex &v = tmpl.v[i + 1];
        v.sp.primitiveId = ids[i];
        v.reflect = i < reflect.size() ? bool(reflect[i]) : true;
        v.specular = true;
        v.o = Vec2();
        v.frameRef = Vec3(0.36, 0.48, 0.8);
    }
    if (TraceChain(scene, start, Normalize(aim - start.p), tmpl, out) != ManifoldStatus::Success)
        return false;
    return Rebuild(out);
}

inline void SetTarget(ChainConfig *c, const Vec3 &shift) {
    c->targetShift = shift;
    c->target = c->scene.moveOn(c->base.back().sp, shift);
}

// Mirror plane z = 0 between a tilted start patch and an end patch (k = 1).
inline ChainConfig MirrorConfig(bool glossy = false) {
    ChainConfig c;
    c.name = glossy ? "glossy" : "mirror";
    int mirror = c.scene.addPlane({0, 0, 0}, {0, 0, 1});
    int startId = c.scene.addPlane({-2, 0, 3}, {1, 0, -1}, 1, 1, 0.5);
    int endId = c.scene.addPlane({2.5, 0.3, 2}, {-1, 0, -0.3}, 1, 1, 3);
    ManifoldSurfacePoint s = c.scene.pointOn(startId, {-2, 0, 3});
    if (!glossy) {
        TraceSpecular(c.scene, s, {0.1, 0.05, 0}, {mirror, endId}, {true}, &c.base);
    } else {
        // Near-specular plane, base vertex off the mirror configuration (o != 0).
        ManifoldSurfacePoint pts[3] = {s, c.scene.pointOn(mirror, {0.3, -0.1, 0}),
                                       c.scene.pointOn(endId, {2.2, 0.1, 3})};
        bool r[1] = {true}, sp[1] = {false};
        MakeChain(pts, 3, r, sp, &c.base);
    }
    SetTarget(&c, {0.2, 0.25, -0.1});
    return c;
}

// Glass slab (eta 1.5) between z = -1 and z = 0 above a floor (k = 2).
inline ChainConfig SlabConfig() {
    ChainConfig c;
    c.name = "slab";
    int top = c.scene.addPlane({0, 0, 0}, {0, 0, 1}, 1.5, 1);
    int bottom = c.scene.addPlane({0, 0, -1}, {0, 0, -1}, 1.5, 1);
    int floor = c.scene.addPlane({0, 0, -3}, {0, 0, 1});
    int startId = c.scene.addPlane({-1.5, 0, 2}, {0.5, 0, -1}, 1, 1, 0.5);
    ManifoldSurfacePoint s = c.scene.pointOn(startId, {-1.5, 0, 2});
    TraceSpecular(c.scene, s, {-0.5, 0.1, 0}, {top, bottom, floor}, {false, false}, &c.base);
    SetTarget(&c, {0.4, 0.3, 0});
    return c;
}

// Two stacked slabs (eta 1.5 and 1.33) above a floor (k = 4).
inline ChainConfig TwoSlabConfig() {
    ChainConfig c;
    c.name = "twoslabs";
    int a0 = c.scene.addPlane({0, 0, 0}, {0, 0, 1}, 1.5, 1);
    int a1 = c.scene.addPlane({0, 0, -1}, {0, 0, -1}, 1.5, 1);
    int b0 = c.scene.addPlane({0, 0, -2}, {0, 0, 1}, 1.33, 1);
    int b1 = c.scene.addPlane({0, 0, -3}, {0, 0, -1}, 1.33, 1);
    int floor = c.scene.addPlane({0, 0, -5}, {0, 0, 1});
    int startId = c.scene.addPlane({-1.5, 0, 2}, {0.5, 0, -1}, 1, 1, 0.5);
    ManifoldSurfacePoint s = c.scene.pointOn(startId, {-1.5, 0, 2});
    TraceSpecular(c.scene, s, {-0.7, 0.1, 0}, {a0, a1, b0, b1, floor},
                  {false, false, false, false}, &c.base);
    SetTarget(&c, {0.5, -0.3, 0});
    return c;
}

// Glass sphere (radius 1, eta 1.5): enter and leave (k = 2).
inline ChainConfig SphereConfig() {
    ChainConfig c;
    c.name = "sphere";
    int sphere = c.scene.addSphere({0, 0, 0}, 1, 1.5, 1);
    int startId = c.scene.addPlane({-4, 0.2, 0.1}, {1, 0, 0}, 1, 1, 0.5);
    int endId = c.scene.addPlane({4, 0, 0}, {-1, 0, 0});
    ManifoldSurfacePoint s = c.scene.pointOn(startId, {-4, 0.2, 0.1});
    TraceSpecular(c.scene, s, {0, 0.35, 0.2}, {sphere, sphere, endId}, {false, false}, &c.base);
    SetTarget(&c, {0, 0.08, -0.06});
    return c;
}

}  // namespace gradus::testing
