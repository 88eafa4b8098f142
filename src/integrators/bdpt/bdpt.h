// Bidirectional path tracing (Veach 1997, ch. 10; pbrt-v3 "bdpt") on the
// shared path-vertex core in integrators/common/.
//
// Parameters (pbrt-v3 names and defaults):
//   integer maxdepth 5                    maximum path depth (edges - 1)
//   string lightsamplestrategy "power"    uniform | power | spatial (= power)
//   bool visualizestrategies false        layers "bdpt_s<S>_t<T>": unweighted contribution of each strategy
//   bool visualizeweights false           layers "bdpt_s<S>_t<T>": MIS-weighted contribution of each strategy
//   string misheuristic "balance"         balance (pbrt-v3) | power (exponent 2)
//   integer pixelbounds [x0 x1 y0 y1]     accepted (use --cropwindow instead)
//   integer rrdepth 3                     Russian roulette on subpaths after this many bounces
//                                         (-1: off, as pbrt-v3; see BidirContext::rrDepth)
// Light-tracing (t = 1) strategy layers are filled through per-layer film splats.
// With both visualize flags set, visualizeweights wins.
#pragma once
#include <vector>

#include "integrators/common/bidir.h"
#include "integrators/integrator.h"
#include "lights/light_sampler.h"

namespace gradus {

class BDPTIntegrator : public PixelSampleIntegrator {
  public:
    explicit BDPTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "bdpt"; }
    void preprocess(const Scene &scene, Film &film) override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    int maxDepth() const { return maxDepth_; }
    const BidirContext &context() const { return ctx_; }
    // Layer index of strategy (s, t), or -1.
    int strategyLayer(int s, int t) const;
    static std::string LayerName(int s, int t);

  private:
    int maxDepth_;
    int rrDepth_ = 3;
    std::string strategy_;
    bool visStrategies_, visWeights_;
    MISHeuristic heuristic_;
    FileLoc loc_;
    LightSampler lightSampler_;
    BidirContext ctx_;
    std::vector<int> layers_;  // indexed s * (maxDepth + 3) + t
    Float splatScale_ = 1;     // full-image pixels / sampled pixels (one light path per camera sample)
};

}  // namespace gradus
