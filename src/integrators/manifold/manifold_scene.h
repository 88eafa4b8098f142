// ManifoldScene adapter over the renderer's Embree scene (manifold/manifold.h).
// Compiled into gradus_render (it needs the Scene); the gradus_manifold
// library (constraints, walk) stays scene-free.
//
// primitiveId is the Embree geometry id (one id per shape/mesh, not per
// triangle): a walk may slide a vertex across triangle edges of one mesh.
// Interior chain vertices need the shading normal and its derivatives
// (interpolated normals); the index of refraction is looked up per geometry
// (recorded by the integrator from the BSDF's refraction samples).
#pragma once
#include <atomic>
#include <memory>
#include <unordered_map>
#include <vector>

#include "integrators/manifold/manifold.h"
#include "core/interaction.h"
#include "scene/scene.h"

namespace gradus {

class EmbreeManifoldScene : public ManifoldScene {
  public:
    explicit EmbreeManifoldScene(const Scene &scene);
    bool intersect(const Ray &r, ManifoldSurfacePoint *hit) const override;
    bool visible(const Point3 &a, const Point3 &b) const override;
    Float extent(int primitiveId) const override;

    // Surface point of a renderer hit: shading normal, the derivatives of the unit
    // shading normal (SurfaceInteraction::shading.dnhatdu), geometric normal.
    ManifoldSurfacePoint fromInteraction(const SurfaceInteraction &si) const;
    // Index of refraction inside geometry `geomId` (1 = unknown/not refractive).
    Float eta(int geomId) const;
    void recordEta(int geomId, Float eta) const;
    Float epsilon() const { return eps_; }
    // Geometry id of an area light's shape (-1 if none).
    int geomOfLight(const Light *l) const;

  private:
    const Scene &scene_;
    Float eps_;
    std::unique_ptr<std::atomic<float>[]> eta_;
    std::vector<Float> extent_;  // per geometry: diagonal of its world bounds
    size_t nGeom_;
    std::unordered_map<const Light *, int> lightGeom_;
};

}  // namespace gradus
