#include "integrators/gradient/gradient_family.h"

#include <chrono>

namespace gradus {

void GradientFamily::initGradients(Film &film, bool useFilmFilter, bool lightTracing) {
    gfilm_.init(film, useFilmFilter, lightTracing);
    filmBounds_ = film.pixelBounds();
}

double GradientFamily::reconstructionEstimate(ReconstructionNorm norm, Float alpha) const {
    if (reconEstimate_ >= 0) return reconEstimate_;
    constexpr int n = 64;
    GradientImages g;
    g.width = g.height = n;
    g.channels = 3;
    const size_t values = size_t(n) * n * 3;
    g.primal.resize(values);
    g.dx.resize(values);
    g.dy.resize(values);
    g.primalVar.assign(values, 0.01f);
    g.dxVar.assign(values, 0.01f);
    g.dyVar.assign(values, 0.01f);
    uint32_t h = 12345;  // deterministic noise: a realistic IRLS workload
    for (size_t i = 0; i < values; ++i) {
        h = h * 1664525u + 1013904223u;
        g.primal[i] = float(h >> 8) / float(1 << 24);
        g.dx[i] = 0.1f * (float(h & 0xffff) / 65536.f - 0.5f);
        g.dy[i] = -g.dx[i];
    }
    Image scratch;
    std::string report;
    const auto t0 = std::chrono::steady_clock::now();
    WriteGradientOutput(g, norm, alpha, &scratch, &report);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    reconEstimate_ = 1.5 * sec * double(filmBounds_.area()) / double(n * n);
    return reconEstimate_;
}

void GradientFamily::finishGradients(const Film &film, const RenderStats &stats, ReconstructionNorm norm,
                                     Float alpha, Image *out) {
    WriteGradientOutput(gfilm_.images(film, stats.spp), norm, alpha, out, &reconReport_);
}

}  // namespace gradus
