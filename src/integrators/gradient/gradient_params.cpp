#include "integrators/gradient/gradient_params.h"

namespace gradus {

ParamTable<GradientSettings> GradientParams(const GradientParamOptions &o) {
    using S = GradientSettings;
    using N = ReconstructionNorm;
    ParamTable<S> t("gradient family");
    t.real("shiftthreshold", &S::shiftThreshold, kDefaultShiftThreshold,
           "roughness below which a vertex is not reconnected (\"specular\")", AtLeast(0));
    t.enumeration<N>("reconstruction", &S::norm, "hybrid",
                     {{"hybrid", N::Hybrid}, {"l1", N::L1}, {"l2", N::L2}, {"weighted", N::Weighted},
                      {"L1", N::L1, "", true}, {"L2", N::L2, "", true}},
                     "screened-Poisson reconstruction in the unprefixed R,G,B (all are written as layers): "
                     "hybrid = L1 below 8 px, the primal's (unbiased) energy above; l1 is robust to "
                     "outliers but biased low at short render times; l2 unbiased but noisier");
    t.real("alpha", &S::alpha, 0.2, "screened-Poisson primal weight", AtLeast(0));
    bool film = o.noFilmFilter.empty();
    t.enumeration<bool>("pixelfilter", &S::filmFilter, film ? "film" : "box",
                        {{"film", true, o.noFilmFilter}, {"box", false}},
                        film ? "film: the scene's PixelFilter (the same image as path); "
                               "box: a sample counts in its own pixel (as the papers)"
                             : "box: a sample counts in its own pixel (as the papers)");
    return t;
}

}  // namespace gradus
