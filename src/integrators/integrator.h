// Integrator base class and the registry of integrator names.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "render/driver.h"
#include "render/film.h"
#include "render/scene.h"

namespace gradus {

class Integrator {
  public:
    virtual ~Integrator() = default;
    virtual std::string name() const = 0;
    // Called once after the scene is built: build light distributions, add film layers.
    virtual void preprocess(const Scene &scene, Film &film) {}
    virtual RenderStats render(const Scene &scene, Film &film, const Sampler &sampler,
                               const RenderOptions &opts) = 0;
    // Adds integrator-specific results (e.g. reconstructed layers) to the output image.
    virtual void finish(const Film &film, Image *out) {}
    // Integrator-specific statistics for the end-of-render report.
    virtual std::string statistics() const { return ""; }
};

// An integrator that estimates independent camera samples through the shared driver.
class SampleIntegrator : public Integrator, public SampleEstimator {
  public:
    RenderStats render(const Scene &scene, Film &film, const Sampler &sampler, const RenderOptions &opts) override {
        scene_ = &scene;
        return RenderImage(film, sampler, *this, opts);
    }

  protected:
    const Scene *scene_ = nullptr;
};

using IntegratorFactory = std::function<std::unique_ptr<Integrator>(const EntityDesc &desc)>;

struct IntegratorInfo {
    std::string name;
    std::string description;
    IntegratorFactory create;
};

// The one table of integrator names (src/integrators/registry.cpp).
const std::vector<IntegratorInfo> &IntegratorRegistry();
// Creates `desc.type` (throws a located Error listing valid names if unknown).
// The caller checks unused parameters afterwards.
std::unique_ptr<Integrator> CreateIntegrator(const EntityDesc &desc);

}  // namespace gradus
