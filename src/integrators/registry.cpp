#include "core/error.h"
#include "integrators/integrator.h"
#include "integrators/path/path.h"

namespace gradus {

const std::vector<IntegratorInfo> &IntegratorRegistry() {
    static const std::vector<IntegratorInfo> table = {
        {"path", "unidirectional path tracing with next-event estimation and MIS",
         [](const EntityDesc &d) { return std::make_unique<PathIntegrator>(d); }},
    };
    return table;
}

std::unique_ptr<Integrator> CreateIntegrator(const EntityDesc &desc) {
    for (const auto &info : IntegratorRegistry())
        if (info.name == desc.type) return info.create(desc);
    std::string valid;
    for (const auto &info : IntegratorRegistry()) valid += (valid.empty() ? "" : ", ") + info.name;
    throw Error(desc.loc, "unknown integrator \"" + desc.type + "\" (available: " + valid + ")");
}

}  // namespace gradus
