#include "integrators/gradient/gradient_film.h"

#include <chrono>
#include <cstdio>

namespace gradus {

const Point2i kNeighbourOffsets[kNumNeighbours] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};

void GradientFilm::init(Film &film) {
    static const char *names[NumLayers] = {"gd.primal", "gd.primal2", "gd.dxf", "gd.dxf2", "gd.dxb",
                                           "gd.dxb2",   "gd.dyf",     "gd.dyf2", "gd.dyb", "gd.dyb2"};
    for (int i = 0; i < NumLayers; ++i) layer_[i] = film.addLayer(names[i]);
}

void GradientFilm::record(SampleRecorder &rec, const GradientSample &s) const {
    if (!s.primal.isFinite()) return;
    rec.addLayer(layer_[Primal], s.primal);
    rec.addLayer(layer_[PrimalSq], s.primal * s.primal);
    // +x: dx at p; -x: dx at p-(1,0) with the sign flipped (I(p) - I(p-1)). Same for y.
    const int lay[kNumNeighbours][2] = {{DxF, DxFSq}, {DxB, DxBSq}, {DyF, DyFSq}, {DyB, DyBSq}};
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!s.active[k] || !s.diff[k].isFinite()) continue;
        Point2i off = kNeighbourOffsets[k];
        bool forward = off.x + off.y > 0;
        Spectrum v = forward ? s.diff[k] : s.diff[k] * -1.0;
        Point2i at = forward ? Point2i{0, 0} : off;
        rec.addLayer(layer_[lay[k][0]], v, at);
        rec.addLayer(layer_[lay[k][1]], v * v, at);
    }
}

GradientImages GradientFilm::images(const Film &film, double spp) const {
    Image L[NumLayers];
    for (int i = 0; i < NumLayers; ++i) L[i] = film.layerImage(layer_[i]);
    GradientImages g;
    g.width = L[0].width();
    g.height = L[0].height();
    g.channels = 3;
    size_t n = size_t(g.width) * g.height * 3;
    g.primal.resize(n);
    g.dx.resize(n);
    g.dy.resize(n);
    g.primalVar.resize(n);
    g.dxVar.resize(n);
    g.dyVar.resize(n);
    double invN = spp > 0 ? 1 / spp : 0;
    auto var = [&](int mean, int sq, size_t i) {
        double m = L[mean].data()[i], m2 = L[sq].data()[i];
        return std::max(0.0, (m2 - m * m) * invN);
    };
    for (size_t i = 0; i < n; ++i) {
        g.primal[i] = L[Primal].data()[i];
        g.dx[i] = L[DxF].data()[i] + L[DxB].data()[i];
        g.dy[i] = L[DyF].data()[i] + L[DyB].data()[i];
        g.primalVar[i] = float(var(Primal, PrimalSq, i));
        g.dxVar[i] = float(var(DxF, DxFSq, i) + var(DxB, DxBSq, i));
        g.dyVar[i] = float(var(DyF, DyFSq, i) + var(DyB, DyBSq, i));
    }
    return g;
}

void GradientFilm::finish(const Film &film, double spp, ReconstructionNorm norm, double alpha, Image *out,
                          std::string *report) const {
    GradientImages g = images(film, spp);
    auto toImage = [&](const std::vector<float> &v) {
        Image im = Image::RGB(g.width, g.height);
        im.data() = v;
        return im;
    };
    Image img = Image::RGB(g.width, g.height);
    img.metadata = out->metadata;
    img.setLayerRGB("primal", toImage(g.primal));
    img.setLayerRGB("dx", toImage(g.dx));
    img.setLayerRGB("dy", toImage(g.dy));
    img.setLayerRGB("primal_var", toImage(g.primalVar));
    img.setLayerRGB("dx_var", toImage(g.dxVar));
    img.setLayerRGB("dy_var", toImage(g.dyVar));
    // The last column of dx and the last row of dy are unused by the solver.
    ReconstructionOptions o1 = ReconstructionOptions::L1Default();
    o1.alpha = alpha;
    ReconstructionResult r1 = Reconstruct(g, o1);
    ReconstructionResult r2 = Reconstruct(g, ReconstructionOptions::L2Exact(alpha));
    Image i1 = ResultToImage(r1), i2 = ResultToImage(r2);
    img.setLayerRGB("reconstructed_l1", i1);
    img.setLayerRGB("reconstructed_l2", i2);
    const Image *chosen = &i1;
    Image iw;
    ReconstructionStats sw;
    if (norm == ReconstructionNorm::L2) chosen = &i2;
    if (norm == ReconstructionNorm::Weighted) {
        ReconstructionResult rw = Reconstruct(g, ReconstructionOptions::Weighted());
        sw = rw.stats;
        iw = ResultToImage(rw);
        img.setLayerRGB("reconstructed_weighted", iw);
        chosen = &iw;
    }
    img.setLayerRGB("", *chosen);
    img.metadata["reconstruction"] = ReconstructionNormName(norm);
    img.metadata["reconstruction_alpha"] = std::to_string(alpha);
    if (report) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "Reconstruction: L1 %.3fs, L2 %.3fs%s (output: %s, alpha %g)\n",
                      r1.stats.seconds, r2.stats.seconds,
                      norm == ReconstructionNorm::Weighted ? (", weighted " + std::to_string(sw.seconds) + "s").c_str()
                                                            : "",
                      ReconstructionNormName(norm), alpha);
        *report = buf;
    }
    *out = std::move(img);
}

}  // namespace gradus
