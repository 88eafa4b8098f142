// Chooses a light for next-event estimation. "uniform" and "power" follow
// pbrt-v3; "spatial" (pbrt-v3's default) is currently the power distribution
// (documented limitation: no per-voxel distributions yet).
#pragma once
#include <string>
#include <unordered_map>
#include <vector>

#include "lights/light.h"
#include "samplers/sampling.h"

namespace gradus {

class LightSampler {
  public:
    LightSampler() = default;
    // Throws Error (at loc) for unknown strategies.
    LightSampler(const std::vector<std::shared_ptr<Light>> &lights, const std::string &strategy, const FileLoc &loc);
    // Returns nullptr when there are no lights.
    const Light *sample(Float u, Float *pmf) const;
    Float pmf(const Light *light) const;
    const std::string &strategy() const { return strategy_; }

  private:
    std::vector<const Light *> lights_;
    Distribution1D distrib_;
    std::unordered_map<const Light *, int> index_;
    std::string strategy_;
};

}  // namespace gradus
