// Chooses a light for next-event estimation.
//   "uniform": equal probabilities; "power": proportional to emitted power;
//   "spatial": per-voxel distributions over a grid spanning the scene (at most
//   64 voxels along the longest axis), built lazily the first time a voxel is
//   queried, proportional to each light's unoccluded contribution estimated at
//   32 points of the voxel, with a floor of 1e-3 of the average so that no
//   light that can contribute is ignored (pbrt-v3's strategy, which takes 128
//   points: at 8-16 spp the voxels' construction took 26-27% of a path render
//   of the Cornell box and veach-bidir, at 32 points 6-11%, at equal error).
// The position-free queries use the power distribution for "spatial".
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "lights/light.h"
#include "samplers/sampling.h"

namespace gradus {

class LightSampler {
  public:
    LightSampler();
    ~LightSampler();
    LightSampler(LightSampler &&) noexcept;
    LightSampler &operator=(LightSampler &&) noexcept;
    // Throws Error (at loc) for unknown strategies.
    LightSampler(const std::vector<std::shared_ptr<Light>> &lights, const std::string &strategy, const FileLoc &loc,
                 const Bounds3 &sceneBounds = Bounds3());
    // Position-free choice (uniform or power). Returns nullptr when there are no lights.
    const Light *sample(Float u, Float *pmf) const;
    Float pmf(const Light *light) const;
    // Choice for shading point p ("spatial" uses p's voxel).
    const Light *sample(const Point3 &p, Float u, Float *pmf) const;
    Float pmf(const Point3 &p, const Light *light) const;
    const std::string &strategy() const { return strategy_; }
    // Number of voxel distributions built so far (statistics).
    int64_t voxelsBuilt() const;

  private:
    struct Grid;
    const Float *lookup(const Point3 &p) const;  // the voxel's cumulative distribution
    std::vector<const Light *> lights_;
    Distribution1D distrib_;
    // Light -> index in lights_ (the last one for a light listed twice): an
    // open-addressing table, a power of two of slots at most half full,
    // probed linearly from a multiplicative hash of the pointer.
    int indexOf(const Light *light) const;
    std::vector<std::pair<const Light *, int>> slots_;
    int slotShift_ = 64;
    std::string strategy_;
    std::unique_ptr<Grid> grid_;
};

}  // namespace gradus
