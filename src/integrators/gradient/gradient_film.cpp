#include "integrators/gradient/gradient_film.h"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>
#include <cstdio>

#include "core/error.h"

namespace gradus {

const Point2i kNeighbourOffsets[kNumNeighbours] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};

void GradientFilm::init(Film &film, bool useFilmFilter, bool lightTracing, bool samples) {
    GRADUS_CHECK(samples || lightTracing);
    bounds_ = film.pixelBounds();
    filter_ = useFilmFilter ? &film.filter() : nullptr;
    filterNorm_ = footprint_ = 1;
    if (filter_) {
        // Integral of the filter by the midpoint rule over its support.
        const int n = 256;
        Vec2 r = filter_->radius;
        double sum = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                sum += filter_->evaluate(Point2((2 * (i + 0.5) / n - 1) * r.x, (2 * (j + 0.5) / n - 1) * r.y));
        double integral = sum * (4 * r.x * r.y) / (double(n) * n);
        filterNorm_ = integral > 0 ? 1 / integral : 1;
        footprint_ = std::max<Float>(1, 4 * r.x * r.y);
    }
    static const char *names[NumLayers] = {"gd.primal", "gd.primal2", "gd.dxf", "gd.dxf2", "gd.dxb",
                                           "gd.dxb2",   "gd.dyf",     "gd.dyf2", "gd.dyb", "gd.dyb2"};
    samples_ = samples;
    variance_ = film.varianceLayers();
    // Sample layers hold no splat storage and splat layers no sample storage (24 B per pixel each);
    // the squares only with variances.
    auto wanted = [&](int i) { return variance_ || !IsSquare(i); };
    for (int i = 0; i < NumLayers; ++i)
        layer_[i] = samples && wanted(i) ? film.addLayer(names[i], LayerUse::Samples, false) : -1;
    sepLayer_ = samples ? film.addLayer("gd.separated", LayerUse::Samples, false) : -1;
    lightTracing_ = lightTracing;
    for (int i = 0; i < NumLayers; ++i)
        splatLayer_[i] = lightTracing && wanted(i)
                             ? film.addLayer(std::string("gd.lt.") + (names[i] + 3), LayerUse::Splats, false)
                             : -1;
}

namespace {
// The pixels a sample reaches through the filter (offsets from its pixel) and
// their normalised weights h(q - s) / integral, evaluated once per sample for
// all its layers (the primal and four differences: 5x fewer filter
// evaluations than per layer). Up to 9 x 9 pixels in place, wider on the heap.
class Footprint {
  public:
    Footprint(const Filter &f, Float norm, Point2 pFilm, Point2i pixel) {
        const Vec2 r = f.radius;
        Point2 pd(pFilm.x - 0.5, pFilm.y - 0.5);
        int x0 = int(std::ceil(pd.x - r.x)), x1 = int(std::floor(pd.x + r.x));
        int y0 = int(std::ceil(pd.y - r.y)), y1 = int(std::floor(pd.y + r.y));
        int cap = std::max(0, (x1 - x0 + 1) * (y1 - y0 + 1));
        if (cap > kLocal) {
            heapQ_.resize(cap);
            heapH_.resize(cap);
            q_ = heapQ_.data();
            h_ = heapH_.data();
        }
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                Float h = f.evaluate(Point2(x - pd.x, y - pd.y)) * norm;
                if (h == 0) continue;
                q_[n_] = Point2i{x - pixel.x, y - pixel.y};
                h_[n_++] = h;
            }
    }
    int size() const { return n_; }
    Point2i offset(int i) const { return q_[i]; }
    Float weight(int i) const { return h_[i]; }

  private:
    static constexpr int kLocal = 81;
    Point2i localQ_[kLocal];
    Float localH_[kLocal];
    Point2i *q_ = localQ_;
    Float *h_ = localH_;
    std::vector<Point2i> heapQ_;
    std::vector<Float> heapH_;
    int n_ = 0;
};
}  // namespace

void GradientFilm::record(SampleRecorder &rec, const GradientSample &s) const {
    GRADUS_CHECK(samples_);
    if (!s.primal.isFinite()) return;
    // Box: the sample's own pixel. Film filter: the pixels q whose centre lies
    // within the filter radius of the sample, with weight h(q - s).
    std::optional<Footprint> fp;
    if (filter_) fp.emplace(*filter_, filterNorm_, rec.pFilm(), rec.pixel());
    // v to `layer` and its square to layerSq (< 0: none).
    auto put2 = [&](int layer, int layerSq, const Spectrum &v, Point2i offset) {
        const bool squares = variance_ && layerSq >= 0;
        if (!fp) {
            rec.addLayer(layer, v, offset);
            if (squares) rec.addLayer(layerSq, v * v, offset);
            return;
        }
        if (v.isBlack()) return;  // adds nothing to either layer
        for (int i = 0; i < fp->size(); ++i) {
            Spectrum hv = v * fp->weight(i);
            Point2i at{fp->offset(i).x + offset.x, fp->offset(i).y + offset.y};
            rec.addLayer(layer, hv, at);
            if (squares) rec.addLayer(layerSq, hv * hv, at);
        }
    };
    auto put = [&](int layer, int layerSq, const Spectrum &v, Point2i offset) {
        put2(layer_[layer], layer_[layerSq], v, offset);
    };
    put(Primal, PrimalSq, s.primal, {0, 0});  // the full primal, separated light included
    if (!s.separated.isBlack() && s.separated.isFinite()) put2(sepLayer_, -1, s.separated, {0, 0});
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!s.active[k] || !s.diff[k].isFinite()) continue;
        Point2i off = kNeighbourOffsets[k];
        bool forward = off.x + off.y > 0;
        Spectrum v = forward ? s.diff[k] : s.diff[k] * -1.0;
        Point2i at = forward ? Point2i{0, 0} : off;
        put(kDiffLayers_[k][0], kDiffLayers_[k][1], v, at);
    }
}

void GradientFilm::recordSeparated(SampleRecorder &rec, Point2 pFilm, const Spectrum &v) const {
    GRADUS_CHECK(samples_);
    if (v.isBlack() || !v.isFinite()) return;
    const bool squares = variance_ && layer_[PrimalSq] >= 0;
    if (!filter_) {  // box: the sample's own pixel
        rec.addLayer(layer_[Primal], v);
        if (squares) rec.addLayer(layer_[PrimalSq], v * v);
        rec.addLayer(sepLayer_, v);
        return;
    }
    const Footprint fp(*filter_, filterNorm_, pFilm, rec.pixel());
    for (int i = 0; i < fp.size(); ++i) {
        const Spectrum hv = v * fp.weight(i);
        rec.addLayer(layer_[Primal], hv, fp.offset(i));
        if (squares) rec.addLayer(layer_[PrimalSq], hv * hv, fp.offset(i));
        rec.addLayer(sepLayer_, hv, fp.offset(i));
    }
}

void GradientFilm::splatLightTracing(SampleRecorder &rec, const GradientSplat &s, Float scale) const {
    GRADUS_CHECK(lightTracing_);
    const GradientSample &g = s.value;
    if (!g.primal.isFinite()) return;
    auto put = [&](Point2i px, int layer, const Spectrum &v) {
        if (!bounds_.inside(px) || splatLayer_[layer] < 0) return;  // < 0: a square without variances
        rec.splat(Point2(px.x + 0.5, px.y + 0.5), v, splatLayer_[layer]);
    };
    Spectrum v = g.primal * scale;
    put(s.pixel, Primal, v);
    put(s.pixel, PrimalSq, v * v);
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!g.active[k]) continue;
        Point2i off = kNeighbourOffsets[k];
        bool forward = off.x + off.y > 0;
        Spectrum d = g.diff[k] * (forward ? scale : -scale);
        Point2i at = forward ? s.pixel : Point2i{s.pixel.x + off.x, s.pixel.y + off.y};
        put(at, kDiffLayers_[k][0], d);
        put(at, kDiffLayers_[k][1], d * d);
    }
}

namespace {
// Sums of film values can exceed the float range (extreme emitters): clamped
// like the film's own outputs, never Inf (the reconstruction handles the range).
// Float sums stay float sums (same rounding as always), then are clamped.
float ToFloat(double v) {
    constexpr double big = std::numeric_limits<float>::max();
    return float(std::clamp(v, -big, big));
}
float SumF(float a, float b) { return ToFloat(double(a + b)); }
}  // namespace

GradientImages GradientFilm::images(const Film &film, double spp) const {
    GradientImages g;
    g.width = bounds_.width();
    g.height = bounds_.height();
    g.channels = 3;
    if (!samples_) {
        const size_t n = size_t(g.width) * g.height * 3;
        for (auto *v : {&g.primal, &g.dx, &g.dy}) v->assign(n, 0.f);
        if (variance_)
            for (auto *v : {&g.primalVar, &g.dxVar, &g.dyVar}) v->assign(n, 0.f);
        addSplats(film, spp, &g);
        return g;
    }
    size_t n = size_t(g.width) * g.height * 3;
    g.primal.resize(n);
    g.dx.resize(n);
    g.dy.resize(n);
    if (variance_) {
        g.primalVar.resize(n);
        g.dxVar.resize(n);
        g.dyVar.resize(n);
    }
    double invN = spp > 0 ? 1 / spp : 0;
    // The film's layer values (the floats of Film::layerImage) pixel by pixel:
    // no image per layer.
    g.separated.resize(n);
    float L[NumLayers][3], S[3];
    auto var = [&](int mean, int sq, int c) {
        double m = L[mean][c], m2 = L[sq][c];
        return std::max(0.0, (m2 - m * m / footprint_) * invN);
    };
    for (size_t p = 0; p < n / 3; ++p) {
        for (int k = 0; k < NumLayers; ++k)
            if (layer_[k] >= 0) film.layerValues(layer_[k], p, L[k]);
        film.layerValues(sepLayer_, p, S);
        for (int c = 0; c < 3; ++c) {
            const size_t i = 3 * p + c;
            g.primal[i] = L[Primal][c];
            g.separated[i] = S[c];
            g.dx[i] = SumF(L[DxF][c], L[DxB][c]);
            g.dy[i] = SumF(L[DyF][c], L[DyB][c]);
            if (!variance_) continue;
            g.primalVar[i] = ToFloat(var(Primal, PrimalSq, c));
            g.dxVar[i] = ToFloat(var(DxF, DxFSq, c) + var(DxB, DxBSq, c));
            g.dyVar[i] = ToFloat(var(DyF, DyFSq, c) + var(DyB, DyBSq, c));
        }
    }
    if (lightTracing_) addSplats(film, spp, &g);
    return g;
}

void GradientFilm::addSplats(const Film &film, double spp, GradientImages *g) const {
    // The film has normalised the splats by the samples per pixel; their
    // variance is approximated by the second moment / N.
    float L[NumLayers][3];
    double invN = spp > 0 ? 1 / spp : 0;
    for (size_t i = 0; i < g->primal.size(); ++i) {
        if (i % 3 == 0)
            for (int k = 0; k < NumLayers; ++k)
                if (splatLayer_[k] >= 0) film.layerValues(splatLayer_[k], i / 3, L[k]);
        auto at = [&](int layer) { return double(L[layer][i % 3]); };
        g->primal[i] = SumF(g->primal[i], ToFloat(at(Primal)));
        g->dx[i] = SumF(g->dx[i], ToFloat(at(DxF) + at(DxB)));
        g->dy[i] = SumF(g->dy[i], ToFloat(at(DyF) + at(DyB)));
        if (!variance_) continue;
        g->primalVar[i] = SumF(g->primalVar[i], ToFloat(at(PrimalSq) * invN));
        g->dxVar[i] = SumF(g->dxVar[i], ToFloat((at(DxFSq) + at(DxBSq)) * invN));
        g->dyVar[i] = SumF(g->dyVar[i], ToFloat((at(DyFSq) + at(DyBSq)) * invN));
    }
}

void WriteGradientOutput(const GradientImages &g, ReconstructionNorm norm, double alpha, Image *out,
                         std::string *report) {
    if (norm == ReconstructionNorm::Weighted && !g.hasVariance())
        throw Error("reconstruction \"weighted\" needs the variance layers (gradus --variance)");
    // The output's channels first; then each layer is set as soon as it is
    // computed and its intermediate freed (at most one solution and one
    // layer image beside the output).
    std::vector<const char *> layers = {"primal"};
    if (!g.separated.empty()) layers.push_back("separated");
    layers.insert(layers.end(), {"dx", "dy"});
    if (g.hasVariance()) layers.insert(layers.end(), {"primal_var", "dx_var", "dy_var"});
    layers.insert(layers.end(), {"reconstructed_l1", "reconstructed_l2", "reconstructed_hybrid"});
    if (norm == ReconstructionNorm::Weighted) layers.push_back("reconstructed_weighted");
    Image img = Image::RGB(g.width, g.height);
    img.metadata = std::move(out->metadata);
    *out = Image();  // the film's image: only its metadata is kept
    std::vector<std::string> names;  // every layer's channels in one reallocation
    for (const char *l : layers)
        for (const std::string &c : Image::LayerRGBNames(l)) names.push_back(c);
    img.addChannels(names);
    auto put = [&](const char *layer, const std::vector<float> &v) {
        Image im = Image::RGB(g.width, g.height);
        im.data() = v;
        img.setLayerRGB(layer, im);
    };
    put("primal", g.primal);
    if (!g.separated.empty()) put("separated", g.separated);
    put("dx", g.dx);
    put("dy", g.dy);
    if (g.hasVariance()) {
        put("primal_var", g.primalVar);
        put("dx_var", g.dxVar);
        put("dy_var", g.dyVar);
    }
    // A solution to its layer, and to the unprefixed R, G, B when it is the chosen one.
    // Every solution includes the separated light (Reconstruct adds it); the
    // hybrid's coarse scales come from the full primal: (R + S) + G * ((p + S) - (R + S))
    // is the hybrid of the solve R of p, plus S.
    auto solution = [&](const char *layer, const ReconstructionResult &r, bool chosen) {
        const Image im = ResultToImage(r);
        img.setLayerRGB(layer, im);
        if (chosen) img.setLayerRGB("", im);
    };
    // The last column of dx and the last row of dy are unused by the solver.
    ReconstructionOptions o1 = ReconstructionOptions::L1Default();
    o1.alpha = alpha;
    double l1Seconds, l2Seconds, weightedSeconds = 0;
    {
        ReconstructionResult r = Reconstruct(g, o1);
        l1Seconds = r.stats.seconds;
        solution("reconstructed_l1", r, norm != ReconstructionNorm::L2 && norm != ReconstructionNorm::Hybrid &&
                                            norm != ReconstructionNorm::Weighted);
        // Hybrid: the L1 solution with the primal's coarse scales (reconstruction.h).
        r.image = CombineScales(r.image, g.primal, r.width, r.height, r.channels,
                                ReconstructionOptions::Hybrid().lowpassSigma);
        solution("reconstructed_hybrid", r, norm == ReconstructionNorm::Hybrid);
    }
    {
        ReconstructionResult r = Reconstruct(g, ReconstructionOptions::L2Exact(alpha));
        l2Seconds = r.stats.seconds;
        solution("reconstructed_l2", r, norm == ReconstructionNorm::L2);
    }
    if (norm == ReconstructionNorm::Weighted) {
        ReconstructionResult r = Reconstruct(g, ReconstructionOptions::Weighted());
        weightedSeconds = r.stats.seconds;
        solution("reconstructed_weighted", r, true);
    }
    img.metadata["reconstruction"] = ReconstructionNormName(norm);
    img.metadata["reconstruction_alpha"] = std::to_string(alpha);
    if (report) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "Reconstruction: L1 %.3fs, L2 %.3fs%s (output: %s, alpha %g)\n", l1Seconds,
                      l2Seconds,
                      norm == ReconstructionNorm::Weighted ? (", weighted " + std::to_string(weightedSeconds) + "s").c_str()
                                                            : "",
                      ReconstructionNormName(norm), alpha);
        *report = buf;
    }
    *out = std::move(img);
}

}  // namespace gradus
