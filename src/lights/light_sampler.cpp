#include "lights/light_sampler.h"

#include "core/error.h"

namespace gradus {

LightSampler::LightSampler(const std::vector<std::shared_ptr<Light>> &lights, const std::string &strategy,
                           const FileLoc &loc)
    : strategy_(strategy) {
    if (strategy != "uniform" && strategy != "power" && strategy != "spatial")
        throw Error(loc, "unknown light sample strategy \"" + strategy + "\" (valid: uniform, power, spatial)");
    std::vector<Float> w;
    for (const auto &l : lights) {
        index_[l.get()] = int(lights_.size());
        lights_.push_back(l.get());
        w.push_back(strategy == "uniform" ? 1 : std::max<Float>(0, l->power().y()));
    }
    if (!w.empty()) distrib_ = Distribution1D(w.data(), int(w.size()));
}

const Light *LightSampler::sample(Float u, Float *pmf) const {
    if (lights_.empty()) { *pmf = 0; return nullptr; }
    int i = distrib_.sampleDiscrete(u, pmf);
    return lights_[i];
}

Float LightSampler::pmf(const Light *light) const {
    auto it = index_.find(light);
    if (it == index_.end()) return 0;
    return distrib_.discretePmf(it->second);
}

}  // namespace gradus
