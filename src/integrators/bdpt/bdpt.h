// Bidirectional path tracing (Veach 1997, ch. 10; pbrt-v3 "bdpt") on the
// shared path-vertex core in integrators/common/.
//
// Parameters (the bidirectional family's, integrators/common/bidir_family.h):
//   integer maxdepth 5                    maximum path depth (edges - 1)
//   string lightsamplestrategy "power"    uniform | power | spatial (= power)
//   string misheuristic "balance"         balance (pbrt-v3) | power (exponent 2)
//   bool visualizestrategies false        layers "bdpt_s<S>_t<T>": unweighted contribution of each strategy
//   bool visualizeweights false           layers "bdpt_s<S>_t<T>": MIS-weighted contribution of each strategy
//   integer rrdepth 3                     Russian roulette on subpaths after this many bounces
//                                         (-1: off, as pbrt-v3; see BidirContext::rrDepth)
//   integer pixelbounds []                accepted (use --cropwindow instead)
// Light-tracing (t = 1) strategy layers are filled through per-layer film splats.
// Participating media: medium vertices on both subpaths, transmittance in
// every connection (pbrt-v3's BDPT; common/bidir.h).
// With both visualize flags set, visualizeweights wins.
#pragma once
#include "integrators/common/bidir_family.h"
#include "render/integrator.h"

namespace gradus {

class BDPTIntegrator : public PixelSampleIntegrator, public BidirFamily {
  public:
    explicit BDPTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "bdpt"; }
    void preprocess(const Scene &scene, Film &film) override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    bool rendersMedia() const override { return true; }  // medium vertices (common/bidir.h)
    bool rendersCamerasWithoutImportance() const override { return true; }  // without t = 1 (bdpt.cpp)
    int maxDepth() const { return set_.maxDepth; }
    static std::string LayerName(int s, int t) { return StrategyLayerName("bdpt", s, t); }

  private:
    BidirSettings set_;
    FileLoc loc_;
};

}  // namespace gradus
