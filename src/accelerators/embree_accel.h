// Embree 3 behind one small interface: triangle meshes (native, with alpha
// cut-outs through intersection/occlusion filter functions) and analytic
// shapes (user geometry, double-precision intersection).
#pragma once
#include <memory>
#include <vector>

#include "core/geometry.h"
#include "shapes/analytic.h"
#include "shapes/triangle.h"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace gradus {

struct RayHit {
    int geomId = -1, primId = -1;
    Float t = 0;
    Float b1 = 0, b2 = 0;  // barycentrics for triangles
};

class EmbreeAccel {
  public:
    EmbreeAccel();
    ~EmbreeAccel();
    EmbreeAccel(const EmbreeAccel &) = delete;
    EmbreeAccel &operator=(const EmbreeAccel &) = delete;

    // Returns the geometry id (dense, from 0, in call order).
    int addMesh(std::shared_ptr<const TriangleMesh> mesh);
    int addAnalytic(std::shared_ptr<const AnalyticShape> shape);
    int addSphere(std::shared_ptr<const AnalyticShape> sphere) { return addAnalytic(std::move(sphere)); }
    void commit();

    bool intersect(const Ray &r, RayHit *hit) const;
    bool occluded(const Ray &r) const;

  private:
    RTCDeviceTy *device_ = nullptr;
    RTCSceneTy *scene_ = nullptr;
    int nextId_ = 0;
    std::vector<std::shared_ptr<const AnalyticShape>> analytic_;  // kept alive for user callbacks
    std::vector<std::shared_ptr<const TriangleMesh>> alphaMeshes_;  // kept alive for filter callbacks
};

}  // namespace gradus
