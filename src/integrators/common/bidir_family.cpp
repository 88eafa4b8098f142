#include "integrators/common/bidir_family.h"

#include "core/error.h"

namespace gradus {

ParamTable<BidirSettings> BidirParams(const BidirParamOptions &o) {
    using S = BidirSettings;
    ParamTable<S> t("bidirectional family");
    t.maxDepth(&S::maxDepth);
    t.enumeration<std::string>("lightsamplestrategy", &S::lightStrategy, "power",
                               {{"uniform", "uniform"}, {"power", "power"}, {"spatial", "spatial", o.noSpatial}},
                               o.noSpatial.empty() ? "light choice; spatial = power (position-free, as the MIS assumes)"
                                                   : "light choice (position-free, as the MIS assumes)");
    if (o.strategyLayers) {
        t.enumeration<MISHeuristic>("misheuristic", &S::heuristic, "balance",
                                    {{"balance", MISHeuristic::Balance}, {"power", MISHeuristic::Power}},
                                    "MIS heuristic of the strategies: balance (as pbrt-v3) or power (exponent 2)");
        t.boolean("visualizestrategies", &S::visStrategies, false,
                  "film layers <integrator>_s<S>_t<T>: unweighted contribution of each strategy");
        t.boolean("visualizeweights", &S::visWeights, false,
                  "the same layers MIS-weighted (wins over visualizestrategies)");
    }
    Range rr;
    if (!o.noRoulette.empty()) rr = Range{double(o.rrDepth), double(o.rrDepth), o.noRoulette};
    t.integer("rrdepth", &S::rrDepth, o.rrDepth, "Russian roulette on subpaths after this many bounces (-1: off)", rr);
    t.pixelBounds(&S::pixelBounds);
    return t;
}

Float LightTracingSplatScale(const Film &film) {
    Point2i full = film.fullResolution();
    int64_t sampled = film.sampleBounds().area();
    return sampled > 0 ? Float(int64_t(full.x) * full.y) / Float(sampled) : 1;
}

std::string BidirFamily::StrategyLayerName(const std::string &prefix, int s, int t) {
    return prefix + "_s" + std::to_string(s) + "_t" + std::to_string(t);
}

int BidirFamily::strategyLayer(int s, int t) const {
    if (layers_.empty() || s < 0 || t < 0 || s >= stride_ || t >= stride_) return -1;
    return layers_[size_t(s) * stride_ + t];
}

void BidirFamily::preprocessBidir(const Scene &scene, Film &film, const BidirSettings &set, const FileLoc &loc) {
    // Path vertices name media by a one-byte index (path_vertex.h).
    if (scene.features.media && scene.media.size() > 255)
        throw Error(loc, "the bidirectional integrators support at most 255 media (the scene has " +
                             std::to_string(scene.media.size()) + ")");
    lightSampler_ = LightSampler(scene.lights, set.lightStrategy, loc);
    ctx_.init(scene, lightSampler_, set.heuristic);
    ctx_.rrDepth = set.rrDepth;
    splatScale_ = LightTracingSplatScale(film);
    layers_.clear();
    stride_ = set.maxDepth + 3;
    if (!set.visStrategies && !set.visWeights) return;
    layers_.assign(size_t(stride_) * stride_, -1);
    for (int depth = 0; depth <= set.maxDepth; ++depth)
        for (int t = minT_; t <= depth + 2; ++t) {
            int s = depth + 2 - t;
            layers_[size_t(s) * stride_ + t] = film.addLayer(StrategyLayerName(prefix_, s, t));
        }
}

}  // namespace gradus
