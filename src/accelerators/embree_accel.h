// Embree 3 behind one small interface: triangle meshes (native, with alpha
// cut-outs through intersection/occlusion filter functions), analytic
// shapes (user geometry, double-precision intersection) and object instances
// (Embree instances of a shared scene of triangle meshes).
//
// Every hittable geometry has a dense record id (from 0, in the order added):
// a world geometry one, an instance one per mesh of its object, consecutive.
// RayHit::geomId is that record id: (instance, geometry) in one number.
#pragma once
#include <memory>
#include <vector>

#include "core/geometry.h"
#include "shapes/analytic.h"
#include "shapes/curve.h"
#include "shapes/triangle.h"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace gradus {

struct RayHit {
    int geomId = -1, primId = -1;  // record id, triangle (or 0)
    Float t = 0;
    Float b1 = 0, b2 = 0;  // barycentrics for triangles; (u, v) for curves
};

class EmbreeAccel {
  public:
    EmbreeAccel();
    ~EmbreeAccel();
    EmbreeAccel(const EmbreeAccel &) = delete;
    EmbreeAccel &operator=(const EmbreeAccel &) = delete;

    // World geometry; returns its record id.
    int addMesh(std::shared_ptr<const TriangleMesh> mesh);
    int addAnalytic(std::shared_ptr<const AnalyticShape> shape);
    int addSphere(std::shared_ptr<const AnalyticShape> sphere) { return addAnalytic(std::move(sphere)); }
    // Curve geometry (user primitives, one per piece; RayHit::b1, b2 = the hit's u, v).
    int addCurve(std::shared_ptr<const CurveShape> curve);
    // An instanceable object: a scene of meshes (in the object's space, no
    // alpha cut-outs), built once however often it is instanced.
    int newObject();
    void addObjectMesh(int object, std::shared_ptr<const TriangleMesh> mesh);
    int objectMeshCount(int object) const;
    const std::shared_ptr<const TriangleMesh> &objectMesh(int object, int k) const {
        return objects_.at(size_t(object)).meshes.at(size_t(k));
    }
    // One instance of a (complete) object; returns the record id of its first
    // mesh, the others follow in addObjectMesh order.
    int addInstance(int object, const Transform &worldFromObject);
    int recordCount() const { return nextRecord_; }
    void commit();

    bool intersect(const Ray &r, RayHit *hit) const;
    bool occluded(const Ray &r) const;

  private:
    // Attaches a top-level geometry holding `records` records; returns the first record id.
    int attachTop(void *geometry, int records);
    RTCDeviceTy *device_ = nullptr;
    RTCSceneTy *scene_ = nullptr;
    int nextId_ = 0;      // top-level Embree geometry ids
    int nextRecord_ = 0;  // record ids
    std::vector<int> recordOfTop_;  // first record id of each top-level geometry
    struct Object {
        RTCSceneTy *scene = nullptr;
        std::vector<std::shared_ptr<const TriangleMesh>> meshes;
        bool committed = false;
    };
    std::vector<Object> objects_;
    std::vector<std::shared_ptr<const AnalyticShape>> analytic_;  // kept alive for user callbacks
    std::vector<std::shared_ptr<const TriangleMesh>> alphaMeshes_;  // kept alive for filter callbacks
    std::vector<std::shared_ptr<const CurveShape>> curves_;
};

}  // namespace gradus
