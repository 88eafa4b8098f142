// Film: the main filtered RGB image plus named per-pixel layers (gradients,
// per-strategy images, ...), and light-tracing splats. Rendering goes through
// FilmTiles that are merged in a fixed order, so images do not depend on the
// thread count.
#pragma once
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/spectrum.h"
#include "filters/filter.h"
#include "image/image.h"

namespace gradus {

struct Bounds2i {
    Point2i pMin, pMax;  // pMax exclusive
    int width() const { return std::max(0, pMax.x - pMin.x); }
    int height() const { return std::max(0, pMax.y - pMin.y); }
    int64_t area() const { return int64_t(width()) * height(); }
    bool inside(Point2i p) const { return p.x >= pMin.x && p.x < pMax.x && p.y >= pMin.y && p.y < pMax.y; }
};

class FilmTile;

// Observes a film while it renders (render/display.h): merged() runs under the
// film's watch lock right after each merge, with the pixels it touched
// (clipped to the film's bounds; all of them when it carried splats). It
// must be quick: the merging thread holds the lock.
class FilmWatcher {
  public:
    virtual ~FilmWatcher() = default;
    virtual void merged(const Bounds2i &pixels, bool allPixels) = 0;
};

// What a layer accumulates: per-pixel sample sums (FilmTile::addLayer), splats
// (FilmTile::addSplat), or both. A layer holds storage only for its kinds
// (24 bytes per pixel each); the other kind is an error.
enum class LayerUse { Both, Samples, Splats };

class Film {
  public:
    Film(Point2i fullResolution, const Float cropWindow[4], std::unique_ptr<Filter> filter, std::string filename,
         Float scale);
    Point2i fullResolution() const { return fullRes_; }
    const Bounds2i &pixelBounds() const { return bounds_; }   // cropped output pixels
    Bounds2i sampleBounds() const;                             // pixels to sample (filter support)
    const Filter &filter() const { return *filter_; }
    const std::string &filename() const { return filename_; }
    Float scale() const { return scale_; }

    // Extra per-pixel layer: value = sum of contributions / samples of that pixel,
    // plus the layer's splats / total samples per pixel (like the main image).
    // written = false: an accumulator that the integrator turns into outputs of
    // its own (toImage leaves it out).
    int addLayer(const std::string &name, LayerUse use = LayerUse::Both, bool written = true);
    int numLayers() const { return int(layerNames_.size()); }
    const std::string &layerName(int i) const { return layerNames_[i]; }
    bool layerWritten(int i) const { return layerWritten_[i] != 0; }
    // Whether integrators keep per-pixel squared values for variance layers
    // (gradus --variance; gradient integrators: 240 bytes per pixel). Set before
    // Integrator::preprocess adds the layers.
    void setVarianceLayers(bool on) { variance_ = on; }
    bool varianceLayers() const { return variance_; }

    std::unique_ptr<FilmTile> makeTile(const Bounds2i &samplePixels) const;
    // A tile that holds only light-tracing splats (work items without a pixel).
    std::unique_ptr<FilmTile> makeSplatTile() const;
    void mergeTile(const FilmTile &tile);
    // Number of camera samples per pixel taken so far (for splat normalisation).
    void setSplatSamples(double sppTotal);

    // A watcher (nullptr: none) of the merges while it is set; merges then take
    // the watch lock, which readPixels takes as well (unwatched films lock nothing).
    void setWatcher(FilmWatcher *w);
    // Output values (as toImage writes them) of the pixels of b (inside
    // pixelBounds(), row-major), per pixel the main R, G, B and then R, G, B of
    // each layer listed; safe while other threads merge.
    void readPixels(const Bounds2i &b, const std::vector<int> &layers, float *out) const;
    double splatSamples() const { return splatSpp_; }
    // Factor on the splats of the main image (layer -1) or of a layer,
    // applied whenever the film is read (toImage, readPixels, layerValues):
    // an integrator whose splat normalisation is refined during the render
    // keeps unnormalised sums and sets the current factor (Metropolis: b).
    // 1 by default; not part of saveState (the integrator's state holds it).
    void setSplatScale(int layer, double s);
    double splatScale(int layer) const { return layer < 0 ? mainSplatScale_ : layerSplatScale_[size_t(layer)]; }
    // The splats of `layer` (a LayerUse::Splats layer, not written) are also
    // part of the main image, times the layer's splat scale.
    void addSplatsToMain(int layer);

    // Final images (cropped size).
    Image mainImage() const;
    Image layerImage(int layer) const;
    // The R, G, B of layerImage(layer) at pixel i of the cropped image (row-major), without the image.
    void layerValues(int layer, size_t i, float rgb[3]) const {
        const Spectrum v = layerPixel(layer, i);
        for (int c = 0; c < 3; ++c) rgb[c] = toOutput(v[c]);
    }
    // RGB main image and all layers ("name.R" ...) in one image.
    Image toImage() const;
    // Output values clamped to the float range by the image functions so far.
    uint64_t clampedValues() const { return clamped_; }

    // Checkpoints: every accumulator (main sums, weights, counts, splats, all
    // layers) as bytes: a header (pixel bounds, layer names) then doubles.
    std::string saveState() const;
    // Replaces the accumulators; throws Error when the bytes are not a film
    // state of this film's bounds and layers.
    void loadState(const std::string &state);
    // Elementwise sum of two states of the same film (partial renders of
    // disjoint passes); throws Error when their headers differ.
    static std::string AddStates(const std::string &a, const std::string &b);

  private:
    friend class FilmTile;
    size_t index(Point2i p) const {
        return size_t(p.y - bounds_.pMin.y) * bounds_.width() + size_t(p.x - bounds_.pMin.x);
    }
    Point2i fullRes_;
    Bounds2i bounds_;
    std::unique_ptr<Filter> filter_;
    std::string filename_;
    Float scale_;
    std::vector<Spectrum> sum_;
    std::vector<double> weight_;
    std::vector<Spectrum> splat_;
    std::vector<double> count_;
    std::vector<std::string> layerNames_;
    std::vector<char> layerWritten_;
    std::vector<std::vector<Spectrum>> layers_;
    std::vector<std::vector<Spectrum>> layerSplats_;
    double splatSpp_ = 0;
    double mainSplatScale_ = 1;
    std::vector<double> layerSplatScale_;
    std::vector<int> mainSplatLayers_;  // layers whose splats the main image adds (addSplatsToMain)
    bool variance_ = false;
    float toOutput(double v) const;
    Spectrum layerPixel(int layer, size_t i) const;
    static constexpr double kBaseBytesPerPixel = 2 * sizeof(Spectrum) + 2 * sizeof(double);
    static constexpr double kLayerBytesPerPixel = 2 * sizeof(Spectrum);  // an upper bound (LayerUse::Both)
    void checkMemory(const std::string &what, double bytesPerPixel) const;
    mutable std::atomic<uint64_t> clamped_{0};
    FilmWatcher *watcher_ = nullptr;
    mutable std::mutex watchMutex_;
    Spectrum mainPixel(size_t i) const;
};

class FilmTile {
  public:
    // splatsOnly: no pixel storage (addSample/addLayer/addCount drop their values).
    FilmTile(const Film &film, const Bounds2i &samplePixels, bool splatsOnly = false);
    // Filtered main-image sample at continuous raster position pFilm.
    void addSample(Point2 pFilm, const Spectrum &L, Float weight = 1);
    void addLayer(int layer, Point2i pixel, const Spectrum &v);
    void addCount(Point2i pixel, double n);
    // Light-tracing contribution at a raster position, to the main image
    // (layer -1) or to a layer; normalised by the total samples per pixel.
    void addSplat(Point2 pFilm, const Spectrum &v, int layer = -1) { splats_.push_back({pFilm, v, layer}); }

  private:
    friend class Film;
    bool inTile(Point2i p) const { return bounds_.inside(p); }
    size_t index(Point2i p) const {
        return size_t(p.y - bounds_.pMin.y) * bounds_.width() + size_t(p.x - bounds_.pMin.x);
    }
    const Film &film_;
    Bounds2i bounds_;  // pixels this tile may write (sample pixels grown by the filter radius + 1)
    std::vector<Spectrum> sum_;
    std::vector<double> weight_, count_;
    std::vector<std::vector<Spectrum>> layers_;
    struct Splat { Point2 p; Spectrum v; int layer; };
    std::vector<Splat> splats_;
};

}  // namespace gradus
