// Factory functions of the integrators, one per folder (see registry.cpp).
#pragma once
#include <memory>

#include "integrators/integrator.h"

namespace gradus {

std::unique_ptr<Integrator> CreatePathIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateBDPTIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateMBDPTIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateGPTIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateGBDPTIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateVCMIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateGVCMIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateMLTIntegrator(const EntityDesc &desc);
std::unique_ptr<Integrator> CreateGMLTIntegrator(const EntityDesc &desc);

}  // namespace gradus
