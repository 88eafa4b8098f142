// Sampler factory.
//
// Names and parameters (pbrt-v3 defaults):
//   "random"      integer pixelsamples [4]
//   "stratified"  integer xsamples [2], ysamples [2], bool jitter [true],
//                 integer dimensions [5] (accepted, not needed: dimensions are unbounded)
//   "halton"      integer pixelsamples [16], bool samplepixelcenter [false]
//                 (true is not supported: the sampler does not know which
//                 dimensions are the film position)
//   "sobol"       integer pixelsamples [16], integer dimensions [4] (accepted, unused)
//                 sobol = padded scrambled (0,2)-sequence (see samplers.h).
// pbrt-v3 names mapped to the closest Gradus sampler:
//   "lowdiscrepancy", "02sequence" -> "sobol" (pbrt-v3's ZeroTwoSequenceSampler is
//                                     a padded scrambled (0,2)-sequence too)
//   "maxmindist"                   -> "stratified" with pixelsamples split into
//                                     the most square xsamples * ysamples grid
// As in pbrt-v3, the pixelsamples of sobol/lowdiscrepancy/02sequence are rounded
// up to a power of two (the (0,m,2)-net property needs it).
// sppOverride > 0 replaces pixelsamples; for stratified it is split into the
// most square xsamples * ysamples with that exact product.
#include "core/error.h"
#include "parser/paramset.h"
#include "samplers/samplers.h"

namespace gradus {

namespace {

// Most square factorisation n = xs * ys with xs <= ys.
void SquarestFactors(int n, int *xs, int *ys) {
    int x = 1;
    for (int d = 1; d * d <= n; ++d)
        if (n % d == 0) x = d;
    *xs = x;
    *ys = n / x;
}

int PositiveInt(const EntityDesc &desc, const std::string &name, int def) {
    int v = desc.params.getInt(name, def);
    if (v <= 0)
        throw Error(desc.params.locOf(name, desc.loc),
                    "sampler parameter \"" + name + "\" must be positive (got " + std::to_string(v) + ")");
    return v;
}

}  // namespace

std::unique_ptr<Sampler> CreateSampler(const EntityDesc &desc, uint64_t seed, int sppOverride) {
    const std::string &type = desc.type.empty() ? std::string("halton") : desc.type;
    std::unique_ptr<Sampler> sampler;
    if (type == "random") {
        int spp = PositiveInt(desc, "pixelsamples", 4);
        if (sppOverride > 0) spp = sppOverride;
        sampler = std::make_unique<RandomSampler>(spp, seed);
    } else if (type == "stratified" || type == "maxmindist") {
        int xs, ys;
        bool jitter = true;
        if (type == "stratified") {
            xs = PositiveInt(desc, "xsamples", 2);
            ys = PositiveInt(desc, "ysamples", 2);
            jitter = desc.params.getBool("jitter", true);
        } else {
            SquarestFactors(PositiveInt(desc, "pixelsamples", 16), &xs, &ys);
        }
        PositiveInt(desc, "dimensions", 4);
        if (sppOverride > 0) SquarestFactors(sppOverride, &xs, &ys);
        sampler = std::make_unique<StratifiedSampler>(xs, ys, jitter, seed);
    } else if (type == "halton") {
        int spp = PositiveInt(desc, "pixelsamples", 16);
        if (desc.params.getBool("samplepixelcenter", false))
            throw UnsupportedError(desc.params.locOf("samplepixelcenter", desc.loc),
                                   "\"bool samplepixelcenter\" true");
        if (sppOverride > 0) spp = sppOverride;
        sampler = std::make_unique<HaltonSampler>(spp, seed);
    } else if (type == "sobol" || type == "lowdiscrepancy" || type == "02sequence") {
        int spp = PositiveInt(desc, "pixelsamples", 16);
        PositiveInt(desc, "dimensions", 4);
        if (sppOverride > 0) spp = sppOverride;
        sampler = std::make_unique<SobolSampler>(RoundUpPow2(spp), seed);
    } else {
        throw Error(desc.loc, "unknown sampler \"" + type +
                                  "\" (valid: \"random\", \"stratified\", \"halton\", \"sobol\", and pbrt-v3's "
                                  "\"lowdiscrepancy\", \"02sequence\", \"maxmindist\")");
    }
    desc.params.checkUnused("Sampler \"" + type + "\"");
    return sampler;
}

}  // namespace gradus
