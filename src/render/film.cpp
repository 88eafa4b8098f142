#include "render/film.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstring>

#include <unistd.h>

#include "core/error.h"

namespace gradus {

Film::Film(Point2i res, const Float crop[4], std::unique_ptr<Filter> filter, std::string filename, Float scale)
    : fullRes_(res), filter_(std::move(filter)), filename_(std::move(filename)), scale_(scale) {
    // pbrt-v3: cropped bounds = [ceil(res * crop.min), ceil(res * crop.max)).
    bounds_.pMin = {int(std::ceil(res.x * crop[0])), int(std::ceil(res.y * crop[2]))};
    bounds_.pMax = {int(std::ceil(res.x * crop[1])), int(std::ceil(res.y * crop[3]))};
    if (bounds_.area() <= 0) throw Error("film crop window selects no pixels");
    checkMemory("its accumulators", kBaseBytesPerPixel);
    size_t n = size_t(bounds_.area());
    sum_.assign(n, Spectrum(0));
    weight_.assign(n, 0);
    splat_.assign(n, Spectrum(0));
    count_.assign(n, 0);
}

void Film::checkMemory(const std::string &what, double bytesPerPixel) const {
    // A request that cannot succeed fails with a message instead of std::bad_alloc.
    static const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
    const double need = double(bounds_.area()) * bytesPerPixel;
    // Everything the film holds once this allocation is made (the constructor's
    // check comes before any storage exists).
    const double held = sum_.empty() ? 0 : double(bounds_.area()) * (kBaseBytesPerPixel + kLayerBytesPerPixel * numLayers());
    const double total = held + need;
    if (physical > 0 && total > physical) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "film of %dx%d pixels: %s need %.3g GiB (%.3g GiB in all), more than the %.3g GiB "
                      "of memory of this machine", bounds_.width(), bounds_.height(), what.c_str(), need / (1 << 30),
                      total / (1 << 30), physical / (1 << 30));
        throw Error(buf);
    }
}

Bounds2i Film::sampleBounds() const {
    Bounds2i b;
    b.pMin = {int(std::floor(bounds_.pMin.x + 0.5 - filter_->radius.x)),
              int(std::floor(bounds_.pMin.y + 0.5 - filter_->radius.y))};
    b.pMax = {int(std::ceil(bounds_.pMax.x - 0.5 + filter_->radius.x)),
              int(std::ceil(bounds_.pMax.y - 0.5 + filter_->radius.y))};
    return b;
}

int Film::addLayer(const std::string &name, LayerUse use, bool written) {
    for (int i = 0; i < numLayers(); ++i)
        if (layerNames_[i] == name) {
            GRADUS_CHECK(use == LayerUse::Both ? !layers_[i].empty() && !layerSplats_[i].empty()
                                               : !(use == LayerUse::Samples ? layers_[i] : layerSplats_[i]).empty());
            return i;
        }
    checkMemory("layer \"" + name + "\"", kLayerBytesPerPixel);
    layerNames_.push_back(name);
    layerWritten_.push_back(written);
    const size_t n = size_t(bounds_.area());
    layers_.emplace_back(use != LayerUse::Splats ? n : 0, Spectrum(0));
    layerSplats_.emplace_back(use != LayerUse::Samples ? n : 0, Spectrum(0));
    layerSplatScale_.push_back(1);
    return numLayers() - 1;
}

void Film::setSplatScale(int layer, double s) {
    std::unique_lock<std::mutex> lock(watchMutex_, std::defer_lock);
    if (watcher_) lock.lock();
    double &at = layer < 0 ? mainSplatScale_ : layerSplatScale_[size_t(layer)];
    if (at == s) return;
    at = s;
    if (watcher_) watcher_->merged(bounds_, true);  // every splat's weight changed
}

void Film::addSplatsToMain(int layer) {
    GRADUS_CHECK(layer >= 0 && layer < numLayers() && !layerSplats_[size_t(layer)].empty() &&
                 layers_[size_t(layer)].empty() && !layerWritten_[size_t(layer)]);
    if (std::find(mainSplatLayers_.begin(), mainSplatLayers_.end(), layer) == mainSplatLayers_.end())
        mainSplatLayers_.push_back(layer);
}

std::unique_ptr<FilmTile> Film::makeTile(const Bounds2i &samplePixels) const {
    return std::make_unique<FilmTile>(*this, samplePixels);
}

std::unique_ptr<FilmTile> Film::makeSplatTile() const { return std::make_unique<FilmTile>(*this, Bounds2i{}, true); }

FilmTile::FilmTile(const Film &film, const Bounds2i &sp, bool splatsOnly) : film_(film) {
    int rx = int(std::ceil(film.filter_->radius.x)) + 1, ry = int(std::ceil(film.filter_->radius.y)) + 1;
    if (!splatsOnly) {
        bounds_.pMin = {sp.pMin.x - rx, sp.pMin.y - ry};
        bounds_.pMax = {sp.pMax.x + rx, sp.pMax.y + ry};
    }
    size_t n = size_t(bounds_.area());
    sum_.assign(n, Spectrum(0));
    weight_.assign(n, 0);
    count_.assign(n, 0);
    layers_.resize(film.numLayers());
    for (int l = 0; l < film.numLayers(); ++l)
        if (!film.layers_[l].empty()) layers_[l].assign(n, Spectrum(0));  // splat-only layers: none
}

void FilmTile::addSample(Point2 pFilm, const Spectrum &L, Float w) {
    const Vec2 r = film_.filter_->radius;
    // Discrete pixels whose centre lies within the filter radius of pFilm.
    Point2 pd(pFilm.x - 0.5, pFilm.y - 0.5);
    int x0 = int(std::ceil(pd.x - r.x)), x1 = int(std::floor(pd.x + r.x));
    int y0 = int(std::ceil(pd.y - r.y)), y1 = int(std::floor(pd.y + r.y));
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            Point2i p{x, y};
            if (!film_.bounds_.inside(p) || !inTile(p)) continue;
            Float fw = film_.filter_->evaluate(Point2(x - pd.x, y - pd.y)) * w;
            if (fw == 0) continue;
            size_t i = index(p);
            sum_[i] += L * fw;
            weight_[i] += fw;
        }
}

void FilmTile::addLayer(int layer, Point2i p, const Spectrum &v) {
    if (!film_.bounds_.inside(p) || !inTile(p)) return;
    GRADUS_CHECK(!layers_[layer].empty());  // a LayerUse::Splats layer
    layers_[layer][index(p)] += v;
}

void FilmTile::addCount(Point2i p, double n) {
    if (!film_.bounds_.inside(p) || !inTile(p)) return;
    count_[index(p)] += n;
}

void Film::setWatcher(FilmWatcher *w) {
    std::lock_guard<std::mutex> lock(watchMutex_);
    watcher_ = w;
}

void Film::setSplatSamples(double sppTotal) {
    std::unique_lock<std::mutex> lock(watchMutex_, std::defer_lock);
    if (watcher_) lock.lock();
    splatSpp_ = sppTotal;
    if (watcher_) watcher_->merged(bounds_, true);  // every splat's weight changed
}

void Film::mergeTile(const FilmTile &t) {
    // Merges are serial (the render loop's ordered merge); the lock is for a watcher's readPixels.
    std::unique_lock<std::mutex> lock(watchMutex_, std::defer_lock);
    if (watcher_) lock.lock();
    for (int y = std::max(t.bounds_.pMin.y, bounds_.pMin.y); y < std::min(t.bounds_.pMax.y, bounds_.pMax.y); ++y)
        for (int x = std::max(t.bounds_.pMin.x, bounds_.pMin.x); x < std::min(t.bounds_.pMax.x, bounds_.pMax.x);
             ++x) {
            Point2i p{x, y};
            size_t i = index(p), j = t.index(p);
            sum_[i] += t.sum_[j];
            weight_[i] += t.weight_[j];
            count_[i] += t.count_[j];
            for (int l = 0; l < numLayers(); ++l)
                if (!t.layers_[l].empty()) layers_[l][i] += t.layers_[l][j];
        }
    for (const auto &s : t.splats_) {
        Point2i p{int(std::floor(s.p.x)), int(std::floor(s.p.y))};
        if (!bounds_.inside(p)) continue;
        if (s.layer < 0)
            splat_[index(p)] += s.v;
        else {
            GRADUS_CHECK(!layerSplats_[s.layer].empty());  // a LayerUse::Samples layer
            layerSplats_[s.layer][index(p)] += s.v;
        }
    }
    if (watcher_) {
        Bounds2i b;
        b.pMin = {std::max(t.bounds_.pMin.x, bounds_.pMin.x), std::max(t.bounds_.pMin.y, bounds_.pMin.y)};
        b.pMax = {std::min(t.bounds_.pMax.x, bounds_.pMax.x), std::min(t.bounds_.pMax.y, bounds_.pMax.y)};
        if (!t.splats_.empty()) watcher_->merged(bounds_, true);
        else if (b.area() > 0) watcher_->merged(b, false);
    }
}

void Film::readPixels(const Bounds2i &b, const std::vector<int> &layers, float *out) const {
    // As toOutput, without counting the clamped values (the render's figure).
    auto put = [&](const Spectrum &v) {
        constexpr double big = std::numeric_limits<float>::max();
        for (int c = 0; c < 3; ++c) *out++ = float(std::abs(v[c]) <= big ? v[c] : v[c] > 0 ? big : -big);
    };
    std::lock_guard<std::mutex> lock(watchMutex_);
    for (int y = b.pMin.y; y < b.pMax.y; ++y)
        for (int x = b.pMin.x; x < b.pMax.x; ++x) {
            const size_t i = index({x, y});
            put(mainPixel(i));
            for (int l : layers) put(layerPixel(l, i));
        }
}

float Film::toOutput(double v) const {
    // Accumulators are double; a value beyond the float range of the outputs is
    // clamped to +-FLT_MAX and counted (never written as Inf).
    constexpr double big = std::numeric_limits<float>::max();
    if (std::abs(v) <= big) return float(v);
    ++clamped_;
    return float(v > 0 ? big : -big);
}

Spectrum Film::mainPixel(size_t i) const {
    Spectrum v(0);
    if (weight_[i] != 0) v = sum_[i] / weight_[i];
    if (splatSpp_ > 0) {
        v += splat_[i] * mainSplatScale_ / splatSpp_;  // (scale 1: exactly splat / spp)
        for (int l : mainSplatLayers_) v += layerSplats_[size_t(l)][i] * layerSplatScale_[size_t(l)] / splatSpp_;
    }
    return v * scale_;
}

Image Film::mainImage() const {
    Image img = Image::RGB(bounds_.width(), bounds_.height());
    for (int y = 0; y < bounds_.height(); ++y)
        for (int x = 0; x < bounds_.width(); ++x) {
            const Spectrum v = mainPixel(size_t(y) * bounds_.width() + x);
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = toOutput(v[c]);
        }
    return img;
}

Spectrum Film::layerPixel(int layer, size_t i) const {
    Spectrum v = count_[i] > 0 && !layers_[layer].empty() ? layers_[layer][i] / count_[i] : Spectrum(0);
    if (splatSpp_ > 0 && !layerSplats_[layer].empty())
        v += layerSplats_[layer][i] * layerSplatScale_[size_t(layer)] / splatSpp_;
    return v * scale_;
}

Image Film::layerImage(int layer) const {
    Image img = Image::RGB(bounds_.width(), bounds_.height());
    for (int y = 0; y < bounds_.height(); ++y)
        for (int x = 0; x < bounds_.width(); ++x) {
            const Spectrum v = layerPixel(layer, size_t(y) * bounds_.width() + x);
            for (int c = 0; c < 3; ++c) img.at(x, y, c) = toOutput(v[c]);
        }
    return img;
}

Image Film::toImage() const {
    Image img = mainImage();
    std::vector<std::string> names;
    for (int l = 0; l < numLayers(); ++l)
        if (layerWritten_[l])
            for (const std::string &c : Image::LayerRGBNames(layerNames_[l])) names.push_back(c);
    img.addChannels(names);  // one reallocation for all layers
    for (int l = 0; l < numLayers(); ++l)
        if (layerWritten_[l]) img.setLayerRGB(layerNames_[l], layerImage(l));
    return img;
}

// ---------------------------------------------------------------- checkpoints
// State layout: "FILM", version, pixel bounds, layer names, then the arrays
// (main sums, weights, splats, counts, then per layer its values and its
// splats), each as a byte 0 (all zero, no data) or 1 followed by its doubles.
// Most layers of most integrators never receive splats: their zero arrays
// cost one byte.
namespace {

constexpr uint32_t kFilmStateMagic = 0x4d4c4946;  // "FILM"
constexpr uint32_t kFilmStateVersion = 2;
static_assert(sizeof(Spectrum) == 3 * sizeof(double), "film states store Spectrum as three doubles");

void PutU32(std::string *s, uint32_t v) { s->append(reinterpret_cast<const char *>(&v), 4); }

void PutArray(std::string *s, const void *p, size_t doubles) {
    const double *d = static_cast<const double *>(p);
    bool zero = true;
    for (size_t i = 0; i < doubles && zero; ++i) zero = d[i] == 0 && !std::signbit(d[i]);
    s->push_back(zero ? 0 : 1);
    if (!zero) s->append(static_cast<const char *>(p), doubles * sizeof(double));
}

struct ParsedState {
    Bounds2i bounds;
    std::vector<std::string> names;
    size_t headerBytes = 0;
    // Per array: offset of its doubles (or npos when all zero) and their count.
    std::vector<std::pair<size_t, size_t>> arrays;
};

ParsedState ParseFilmState(const std::string &s) {
    ParsedState ps;
    size_t at = 0;
    auto need = [&](size_t n) {
        if (s.size() - at < n) throw Error("film state: truncated");
    };
    auto u32 = [&] {
        need(4);
        uint32_t v;
        std::memcpy(&v, s.data() + at, 4);
        at += 4;
        return v;
    };
    if (s.size() < 8 || u32() != kFilmStateMagic) throw Error("film state: not a film state");
    if (u32() != kFilmStateVersion) throw Error("film state: unknown version");
    int32_t c[4];
    for (int32_t &v : c) v = int32_t(u32());
    Bounds2i &b = ps.bounds;
    b.pMin = {c[0], c[1]};
    b.pMax = {c[2], c[3]};
    if (b.width() <= 0 || b.height() <= 0 || b.area() > (int64_t(1) << 34)) throw Error("film state: bad bounds");
    uint32_t nl = u32();
    if (nl > 4096) throw Error("film state: bad layer count");
    for (uint32_t i = 0; i < nl; ++i) {
        uint32_t len = u32();
        need(len);
        ps.names.emplace_back(s.data() + at, len);
        at += len;
    }
    ps.headerBytes = at;
    const size_t n = size_t(b.area());
    std::vector<size_t> sizes = {3 * n, n, 3 * n, n};
    for (uint32_t i = 0; i < nl; ++i) sizes.insert(sizes.end(), {3 * n, 3 * n});
    for (size_t count : sizes) {
        need(1);
        const char kind = s[at++];
        if (kind == 0) {
            ps.arrays.push_back({std::string::npos, count});
        } else if (kind == 1) {
            need(count * sizeof(double));
            ps.arrays.push_back({at, count});
            at += count * sizeof(double);
        } else {
            throw Error("film state: bad array tag");
        }
    }
    if (at != s.size()) throw Error("film state: size does not match its header");
    return ps;
}

}  // namespace

std::string Film::saveState() const {
    std::string s;
    const size_t n = size_t(bounds_.area());
    PutU32(&s, kFilmStateMagic);
    PutU32(&s, kFilmStateVersion);
    for (int v : {bounds_.pMin.x, bounds_.pMin.y, bounds_.pMax.x, bounds_.pMax.y}) PutU32(&s, uint32_t(v));
    PutU32(&s, uint32_t(layerNames_.size()));
    for (const auto &name : layerNames_) {
        PutU32(&s, uint32_t(name.size()));
        s += name;
    }
    PutArray(&s, sum_.data(), 3 * n);
    PutArray(&s, weight_.data(), n);
    PutArray(&s, splat_.data(), 3 * n);
    PutArray(&s, count_.data(), n);
    // A layer's unused kind is written as an all-zero array (the format of every state).
    for (size_t l = 0; l < layers_.size(); ++l)
        for (const auto *a : {&layers_[l], &layerSplats_[l]}) {
            if (a->empty())
                s.push_back(0);
            else
                PutArray(&s, a->data(), 3 * n);
        }
    return s;
}

void Film::loadState(const std::string &state) {
    ParsedState ps = ParseFilmState(state);
    if (!(ps.bounds.pMin == bounds_.pMin) || !(ps.bounds.pMax == bounds_.pMax))
        throw Error("film state: its pixel bounds differ from this film's");
    if (ps.names != layerNames_) throw Error("film state: its layers differ from this render's");
    std::vector<void *> dst = {sum_.data(), weight_.data(), splat_.data(), count_.data()};
    for (size_t l = 0; l < layers_.size(); ++l)
        for (auto *a : {&layers_[l], &layerSplats_[l]}) dst.push_back(a->empty() ? nullptr : a->data());
    for (size_t k = 0; k < dst.size(); ++k) {
        const auto &a = ps.arrays[k];
        if (!dst[k]) {  // a kind this layer does not hold: the state must have nothing there
            if (a.first != std::string::npos)
                throw Error("film state: layer \"" + layerNames_[(k - 4) / 2] + "\" holds values this render does not use");
            continue;
        }
        if (a.first == std::string::npos) std::memset(dst[k], 0, a.second * sizeof(double));
        else std::memcpy(dst[k], state.data() + a.first, a.second * sizeof(double));
    }
}

std::string Film::AddStates(const std::string &a, const std::string &b) {
    ParsedState pa = ParseFilmState(a), pb = ParseFilmState(b);
    if (pa.headerBytes != pb.headerBytes || a.compare(0, pa.headerBytes, b, 0, pb.headerBytes) != 0)
        throw Error("film states of different films (bounds or layers differ)");
    std::string out = a.substr(0, pa.headerBytes);
    std::vector<double> sum;
    for (size_t k = 0; k < pa.arrays.size(); ++k) {
        const size_t n = pa.arrays[k].second;
        sum.assign(n, 0.0);
        for (const auto *src : {&pa.arrays[k], &pb.arrays[k]}) {
            if (src->first == std::string::npos) continue;
            const std::string &bytes = src == &pa.arrays[k] ? a : b;
            for (size_t i = 0; i < n; ++i) {
                double v;
                std::memcpy(&v, bytes.data() + src->first + i * sizeof(double), sizeof v);
                sum[i] += v;
            }
        }
        PutArray(&out, sum.data(), n);
    }
    return out;
}

}  // namespace gradus
