// The bidirectional family (bdpt, mbdpt; gbdpt takes part of its settings):
// shared settings with their parameter table, and the shared runtime state of
// bdpt and mbdpt (light sampler, BidirContext, strategy layers, light-tracing
// splat scale).
#pragma once
#include <string>
#include <vector>

#include "integrators/common/bidir.h"
#include "render/params.h"
#include "lights/light_sampler.h"
#include "render/film.h"

namespace gradus {

// Every field is set by BidirParams (defaults there).
struct BidirSettings {
    int maxDepth;               // maximum path depth (edges - 1)
    std::string lightStrategy;  // uniform | power | spatial (= power: position-free)
    MISHeuristic heuristic;
    bool visStrategies, visWeights;
    int rrDepth;                  // BidirContext::rrDepth
    std::vector<int> pixelBounds;  // accepted for pbrt-v3 scenes; --cropwindow crops
};

// What a member takes from the family. bdpt and mbdpt: everything (the defaults).
struct BidirParamOptions {
    bool strategyLayers = true;  // misheuristic, visualizestrategies, visualizeweights
    int rrDepth = 3;             // default of rrdepth
    std::string noSpatial;       // non-empty: lightsamplestrategy "spatial" rejected with this reason
    std::string noRoulette;      // non-empty: rrdepth must be -1, with this reason
};

// maxdepth, lightsamplestrategy, [misheuristic, visualizestrategies,
// visualizeweights,] rrdepth, pixelbounds.
ParamTable<BidirSettings> BidirParams(const BidirParamOptions &opts = {});

// Film pixels / sampled pixels: the scale of light-tracing splats when one
// light subpath is traced per camera sample of the sampled pixels (the film
// normalises splats by the samples per pixel of the full image).
Float LightTracingSplatScale(const Film &film);

// Runtime state shared by bdpt and mbdpt.
class BidirFamily {
  public:
    const BidirContext &context() const { return ctx_; }
    // Film layer of strategy (s, t) (visualizestrategies / visualizeweights), or -1.
    int strategyLayer(int s, int t) const;
    // "<prefix>_s<S>_t<T>".
    static std::string StrategyLayerName(const std::string &prefix, int s, int t);

  protected:
    // Strategy layers are named after `prefix` and exist for t >= minT.
    BidirFamily(std::string prefix, int minT) : prefix_(std::move(prefix)), minT_(minT) {}
    // Light sampler, BidirContext, splat scale and (when visualising) the strategy layers.
    void preprocessBidir(const Scene &scene, Film &film, const BidirSettings &set, const FileLoc &loc);

    LightSampler lightSampler_;
    BidirContext ctx_;
    Float splatScale_ = 1;

  private:
    std::string prefix_;
    int minT_;
    int stride_ = 0;           // maxDepth + 3
    std::vector<int> layers_;  // indexed s * stride_ + t
};

}  // namespace gradus
