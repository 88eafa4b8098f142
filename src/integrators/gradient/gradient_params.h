// Parameters of the gradient family (gpt, gbdpt, gmlt): shift threshold,
// reconstruction and pixel filter of the gradient film.
#pragma once
#include <string>

#include "render/params.h"
#include "materials/bsdf.h"
#include "reconstruction/reconstruction.h"

namespace gradus {

// Every field is set by GradientParams (defaults there).
struct GradientSettings {
    Float shiftThreshold = kDefaultShiftThreshold;  // roughness below which a vertex is not reconnected ("specular")
    ReconstructionNorm norm;
    Float alpha;           // screened-Poisson primal weight
    bool filmFilter;       // pixelfilter "film" (else "box")
};

struct GradientParamOptions {
    std::string noFilmFilter;  // non-empty: pixelfilter "film" rejected with this reason (default box)
};

// shiftthreshold, reconstruction, alpha, pixelfilter.
ParamTable<GradientSettings> GradientParams(const GradientParamOptions &opts = {});

}  // namespace gradus
