// Factory functions of the integrators and their parameter tables, one pair
// per folder (see registry.cpp).
#pragma once
#include <memory>

#include "render/integrator.h"

namespace gradus {

std::unique_ptr<Integrator> CreatePathIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> PathParameters();
std::unique_ptr<Integrator> CreateBDPTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> BDPTParameters();
std::unique_ptr<Integrator> CreateMBDPTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> MBDPTParameters();
std::unique_ptr<Integrator> CreateGPTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> GPTParameters();
std::unique_ptr<Integrator> CreateGBDPTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> GBDPTParameters();
std::unique_ptr<Integrator> CreateVCMIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> VCMParameters();
std::unique_ptr<Integrator> CreateGVCMIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> GVCMParameters();
std::unique_ptr<Integrator> CreateMLTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> MLTParameters();
std::unique_ptr<Integrator> CreatePMLTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> PMLTParameters();
std::unique_ptr<Integrator> CreateGMLTIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> GMLTParameters();
std::unique_ptr<Integrator> CreateWhittedIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> WhittedParameters();
std::unique_ptr<Integrator> CreateDirectLightingIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> DirectLightingParameters();
std::unique_ptr<Integrator> CreateAmbientOcclusionIntegrator(const EntityDesc &desc);
std::vector<ParamInfo> AmbientOcclusionParameters();

}  // namespace gradus
