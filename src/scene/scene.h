// The renderable scene: Embree geometry with per-geometry records, lights,
// camera, and the SceneFeatures that integrators use to skip work.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "accelerators/embree_accel.h"
#include "cameras/camera.h"
#include "lights/light.h"
#include "materials/material.h"
#include "media/medium.h"

namespace gradus {

// What the scene contains (printed by --stats).
struct SceneFeatures {
    bool specularSurfaces = false;      // some material has a perfectly specular lobe (roughness 0)
    bool nearSpecularSurfaces = false;  // some material is glossy below kDefaultShiftThreshold...
    Float minRoughness = 1;             // lowest roughness over all materials
    bool deltaLights = false;
    bool infiniteLights = false;
    bool areaLights = false;
    bool textures = false;
    bool subdivisionSurfaces = false;
    bool media = false;       // some MakeNamedMedium is in use (camera, light or surface)
    bool subsurface = false;  // some material has a BSSRDF
    bool emittersDirectlyVisible = false;  // probed with camera rays at load
    int numLights = 0;
    int64_t numTriangles = 0;
    int numSpheres = 0;
    int numAnalytic = 0;  // analytic shapes other than spheres (disk, cylinder, ...)
    int numCurveSegments = 0;  // Shape "curve" segments (Embree curve primitives)
    int numInstances = 0;            // Embree instances (objects used more than once)
    int64_t numInstancedTriangles = 0;  // triangles of those instances, counted once per instance
    int64_t numStoredTriangles = 0;     // triangles held in memory (an instanced object's once)
    std::string describe() const;
};

// One per Embree geometry a ray can hit, instances included: the record id
// (SurfaceInteraction::geomId) names the pair (instance, geometry of its
// object); EmbreeAccel maps Embree's (instID, geomID) onto it.
struct GeometryRecord {
    std::shared_ptr<const TriangleMesh> mesh;  // or
    // Non-null for a mesh of an instanced object: the instance's transform
    // (owned by Scene::placements); the mesh is then in the object's space.
    const MeshPlacement *placement = nullptr;
    std::shared_ptr<const AnalyticShape> analytic;  // sphere, disk, cylinder, cone, paraboloid, hyperboloid
    // Same object as `analytic` (older name, kept while callers move to `analytic`).
    std::shared_ptr<const AnalyticShape> sphere;
    // Shape "curve" (primitive = segment); interaction() rebuilds a hit from its point.
    std::shared_ptr<const CurveShape> curve;
    const Material *material = nullptr;
    std::vector<const AreaLight *> areaLights;  // per primitive; empty if not emissive
    MediumInterface mediumInterface;            // the shape's (no media: both null)

    // World-space triangle data of a mesh record (placement applied).
    void meshInteraction(int tri, Float b1, Float b2, const Vec3 &wo, SurfaceInteraction *si) const {
        mesh->interaction(tri, b1, b2, wo, si, placement);
    }
    void triangleCorners(int tri, Point3 c[3]) const { mesh->corners(tri, placement, c); }
};

class Scene {
  public:
    Scene();
    ~Scene();
    // Closest hit; fills the full surface interaction (double precision).
    bool intersect(const Ray &r, SurfaceInteraction *si) const;
    // Closest hit on a surface with a material: interfaces (no material) are
    // crossed straight through by re-spawning *ray, at most
    // kMaxInterfaceCrossings times in a row. Stuck: the limit was reached.
    enum class SurfaceHit { Miss, Hit, Stuck };
    SurfaceHit intersectSurface(Ray *ray, SurfaceInteraction *si) const;
    // Any hit before r.tMax.
    bool occluded(const Ray &r) const;
    // Shadow-ray test between two interactions (offset at both ends).
    bool unoccluded(const Interaction &a, const Interaction &b) const { return !occluded(a.spawnRayTo(b)); }
    // Transmittance from a (in medium `ma`, the medium a ray leaving a towards b
    // starts in) to b: 0 when a surface with a material lies between, else the
    // product of the media's transmittances over the segments between the
    // interfaces crossed (pbrt-v3's VisibilityTester::Tr). Equals
    // unoccluded(a, b) ? 1 : 0 in a scene without media.
    Spectrum transmittance(const Interaction &a, const Medium *ma, const Interaction &b, UniformSource rng) const;

    EmbreeAccel accel;
    std::vector<GeometryRecord> geometry;   // indexed by record id (EmbreeAccel)
    std::vector<std::unique_ptr<MeshPlacement>> placements;  // one per object instance
    std::vector<std::shared_ptr<Light>> lights;
    std::vector<const Light *> infiniteLights;
    std::vector<std::shared_ptr<Material>> materials;  // owned
    std::unique_ptr<Camera> camera;
    std::vector<std::shared_ptr<Medium>> media;  // owned (MakeNamedMedium)
    const Medium *cameraMedium = nullptr;        // the medium the camera sits in
    Bounds3 bounds;
    SceneFeatures features;
    // Located notes for the user from building (parameters read but ignored).
    std::vector<std::string> notes;
};

}  // namespace gradus
