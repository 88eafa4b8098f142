// The one table of integrator names (registry.cpp): the only place that knows
// every integrator family; the job layer creates integrators through it.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "render/integrator.h"

namespace gradus {

using IntegratorFactory = std::function<std::unique_ptr<Integrator>(const EntityDesc &desc)>;

struct IntegratorInfo {
    std::string name;
    std::string description;
    IntegratorFactory create;
    // The integrator's parameter table (gradus --describe), without a scene.
    std::function<std::vector<ParamInfo>()> parameters;
};

// The one table of integrator names (src/integrators/registry.cpp).
const std::vector<IntegratorInfo> &IntegratorRegistry();
// Creates `desc.type` (throws a located Error listing valid names if unknown).
// The caller checks unused parameters afterwards.
std::unique_ptr<Integrator> CreateIntegrator(const EntityDesc &desc);

}  // namespace gradus
