#include "integrators/gradient/gradient_family.h"

namespace gradus {

void GradientFamily::initGradients(Film &film, bool useFilmFilter, bool lightTracing) {
    gfilm_.init(film, useFilmFilter, lightTracing);
    filmBounds_ = film.pixelBounds();
}

void GradientFamily::finishGradients(const Film &film, const RenderStats &stats, ReconstructionNorm norm,
                                     Float alpha, Image *out) {
    WriteGradientOutput(gfilm_.images(film, stats.spp), norm, alpha, out, &reconReport_);
}

}  // namespace gradus
