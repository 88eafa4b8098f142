// gradus::Image <-> GradientImages conversions and the integrator helper.
#include <algorithm>

#include "core/error.h"
#include "image/image.h"
#include "reconstruction/reconstruction.h"

namespace gradus {

namespace {

bool HasLayer(const Image &img, const std::string &name) {
    std::vector<std::string> layers = img.layers();
    return std::find(layers.begin(), layers.end(), name) != layers.end();
}

std::vector<float> Interleaved3(const Image &rgb) {
    std::vector<float> out(size_t(rgb.width()) * rgb.height() * 3);
    for (int y = 0; y < rgb.height(); ++y)
        for (int x = 0; x < rgb.width(); ++x)
            for (int c = 0; c < 3; ++c) out[(size_t(y) * rgb.width() + x) * 3 + c] = rgb.at(x, y, c);
    return out;
}

std::vector<float> LayerData(const Image &img, const std::string &layer) {
    if (!HasLayer(img, layer)) {
        std::string have;
        for (const std::string &l : img.layers()) have += (have.empty() ? "" : ", ") + (l.empty() ? "<RGB>" : l);
        throw Error("reconstruction: the image has no layer '" + layer + "' (layers: " +
                    (have.empty() ? "none" : have) + ")");
    }
    return Interleaved3(img.layerRGB(layer));
}

}  // namespace

GradientImages GradientImagesFromImage(const Image &img) {
    GradientImages g;
    g.width = img.width();
    g.height = img.height();
    g.channels = 3;
    g.primal = LayerData(img, "primal");
    g.dx = LayerData(img, "dx");
    g.dy = LayerData(img, "dy");
    if (HasLayer(img, "separated")) g.separated = LayerData(img, "separated");
    const bool vp = HasLayer(img, "primal_var"), vx = HasLayer(img, "dx_var"),
               vy = HasLayer(img, "dy_var");
    if (vp && vx && vy) {
        g.primalVar = LayerData(img, "primal_var");
        g.dxVar = LayerData(img, "dx_var");
        g.dyVar = LayerData(img, "dy_var");
    }
    return g;
}

GradientImages GradientImagesFromImages(const Image &primal, const Image &dx, const Image &dy) {
    if (dx.width() != primal.width() || dx.height() != primal.height() ||
        dy.width() != primal.width() || dy.height() != primal.height())
        throw Error("reconstruction: primal (" + std::to_string(primal.width()) + "x" +
                    std::to_string(primal.height()) + "), dx (" + std::to_string(dx.width()) + "x" +
                    std::to_string(dx.height()) + ") and dy (" + std::to_string(dy.width()) + "x" +
                    std::to_string(dy.height()) + ") differ in size");
    GradientImages g;
    g.width = primal.width();
    g.height = primal.height();
    g.channels = 3;
    g.primal = Interleaved3(primal.layerRGB(""));
    g.dx = Interleaved3(dx.layerRGB(""));
    g.dy = Interleaved3(dy.layerRGB(""));
    return g;
}

Image ResultToImage(const ReconstructionResult &r) {
    Image img = Image::RGB(r.width, r.height);
    for (int y = 0; y < r.height; ++y)
        for (int x = 0; x < r.width; ++x)
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = r.at(x, y, std::min(c, r.channels - 1));
    return img;
}

Image ReconstructImage(const Image &img, const ReconstructionOptions &opt, ReconstructionStats *stats) {
    ReconstructionResult r = Reconstruct(GradientImagesFromImage(img), opt);
    if (stats) *stats = r.stats;
    return ResultToImage(r);
}

void AddReconstructionLayers(Image &film, double alpha) {
    GradientImages g = GradientImagesFromImage(film);
    ReconstructionOptions l1 = ReconstructionOptions::L1Default();
    l1.alpha = alpha;
    film.setLayerRGB("reconstructed_l1", ResultToImage(Reconstruct(g, l1)));
    film.setLayerRGB("reconstructed_l2",
                     ResultToImage(Reconstruct(g, ReconstructionOptions::L2Exact(alpha))));
}

}  // namespace gradus
