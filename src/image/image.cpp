#include "image/image.h"

#include <cstdio>
#include <cstdlib>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace gradus {

namespace {

// "primal.R" -> ("primal", "R"); "R" -> ("", "R"). Splits at the last dot.
void SplitChannel(const std::string &name, std::string *layer, std::string *base) {
    size_t dot = name.rfind('.');
    if (dot == std::string::npos) {
        *layer = "";
        *base = name;
    } else {
        *layer = name.substr(0, dot);
        *base = name.substr(dot + 1);
    }
}

std::string Join(const std::string &prefix, const std::string &base) {
    return prefix.empty() ? base : prefix + "." + base;
}

}  // namespace

Image::Image(int width, int height, std::vector<std::string> channels)
    : width_(width), height_(height), channels_(std::move(channels)) {
    if (width < 0 || height < 0)
        throw Error("Image: negative size " + std::to_string(width) + "x" + std::to_string(height));
    for (size_t i = 0; i < channels_.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (channels_[i] == channels_[j])
                throw Error("Image: duplicate channel name \"" + channels_[i] + "\"");
    data_.assign(size_t(width) * size_t(height) * channels_.size(), 0.f);
}

Image Image::RGB(int width, int height) { return Image(width, height, {"R", "G", "B"}); }

int Image::channelIndex(const std::string &name) const {
    for (size_t i = 0; i < channels_.size(); ++i)
        if (channels_[i] == name) return int(i);
    return -1;
}

int Image::addChannel(const std::string &name) {
    addChannels({name});
    return channelIndex(name);
}

void Image::addChannels(const std::vector<std::string> &names) {
    std::vector<std::string> add;
    for (const std::string &n : names)
        if (channelIndex(n) < 0 && std::find(add.begin(), add.end(), n) == add.end()) add.push_back(n);
    if (add.empty()) return;
    const size_t oldN = channels_.size(), newN = oldN + add.size();
    const size_t npix = size_t(width_) * size_t(height_);
    std::vector<float> grown(npix * newN, 0.f);
    for (size_t p = 0; p < npix; ++p)
        std::copy(data_.begin() + p * oldN, data_.begin() + (p + 1) * oldN, grown.begin() + p * newN);
    data_.swap(grown);
    channels_.insert(channels_.end(), add.begin(), add.end());
}

std::vector<std::string> Image::LayerRGBNames(const std::string &prefix) {
    return {Join(prefix, "R"), Join(prefix, "G"), Join(prefix, "B")};
}

std::vector<std::string> Image::layers() const {
    std::vector<std::string> out;
    for (const std::string &c : channels_) {
        std::string layer, base;
        SplitChannel(c, &layer, &base);
        if (std::find(out.begin(), out.end(), layer) == out.end()) out.push_back(layer);
    }
    return out;
}

Image Image::layerRGB(const std::string &prefix) const {
    int idx[3] = {channelIndex(Join(prefix, "R")), channelIndex(Join(prefix, "G")),
                  channelIndex(Join(prefix, "B"))};
    if (idx[0] < 0 || idx[1] < 0 || idx[2] < 0) {
        // Luminance-only layer, or a layer with a single channel: replicate it.
        int y = channelIndex(Join(prefix, "Y"));
        if (y < 0) {
            std::vector<int> members;
            for (size_t i = 0; i < channels_.size(); ++i) {
                std::string layer, base;
                SplitChannel(channels_[i], &layer, &base);
                if (layer == prefix) members.push_back(int(i));
            }
            if (members.size() == 1) y = members[0];
        }
        if (y < 0)
            throw Error("image has no RGB (or Y) channels in layer \"" + prefix + "\"");
        idx[0] = idx[1] = idx[2] = y;
    }
    Image out = RGB(width_, height_);
    out.metadata = metadata;
    out.originX = originX, out.originY = originY, out.displayWidth = displayWidth, out.displayHeight = displayHeight;
    size_t npix = size_t(width_) * size_t(height_), nc = channels_.size();
    for (size_t p = 0; p < npix; ++p)
        for (int c = 0; c < 3; ++c) out.data_[p * 3 + c] = data_[p * nc + idx[c]];
    return out;
}

void Image::setLayerRGB(const std::string &prefix, const Image &rgb) {
    if (rgb.width() != width_ || rgb.height() != height_)
        throw Error("setLayerRGB: size mismatch (" + std::to_string(rgb.width()) + "x" +
                    std::to_string(rgb.height()) + " into " + std::to_string(width_) + "x" +
                    std::to_string(height_) + ")");
    Image src = (rgb.channelIndex("R") >= 0 && rgb.channelIndex("G") >= 0 &&
                 rgb.channelIndex("B") >= 0 && rgb.numChannels() == 3)
                    ? rgb
                    : rgb.layerRGB("");
    int sc[3] = {src.channelIndex("R"), src.channelIndex("G"), src.channelIndex("B")};
    const std::vector<std::string> names = LayerRGBNames(prefix);
    addChannels(names);
    int dc[3];
    for (int c = 0; c < 3; ++c) dc[c] = channelIndex(names[size_t(c)]);
    size_t npix = size_t(width_) * size_t(height_), nc = channels_.size();
    for (size_t p = 0; p < npix; ++p)
        for (int c = 0; c < 3; ++c) data_[p * nc + dc[c]] = src.data_[p * 3 + sc[c]];
}

}  // namespace gradus

namespace gradus {

std::string DefaultRGBLayer(const Image &image) {
    auto has = [&](const std::string &l, const char *c) {
        return image.channelIndex(l.empty() ? std::string(c) : l + "." + c) >= 0;
    };
    auto hasRGB = [&](const std::string &l) { return has(l, "R") && has(l, "G") && has(l, "B"); };
    std::vector<std::string> layers = image.layers();
    bool haveUnprefixed = std::find(layers.begin(), layers.end(), "") != layers.end();
    if (haveUnprefixed && (hasRGB("") || has("", "Y"))) return "";
    if (hasRGB("primal")) return "primal";
    for (const std::string &l : layers)
        if (hasRGB(l)) return l;
    for (const std::string &l : layers)
        if (has(l, "Y")) return l;
    throw Error("image has no R,G,B (or Y) channels in any layer");
}

namespace {

int NextPowerOfTwo(int n) {
    int p = 1;
    while (p < n) p *= 2;
    return p;
}

// The resampling kernel at d source texels: the Lanczos window of two lobes,
// sinc(pi d) sinc(pi d / 2) on |d| <= 2.
double ResampleKernel(double d) {
    const double x = std::abs(d) / 2;
    if (x < 1e-5) return 1;
    if (x > 1) return 0;
    const double a = 3.14159265358979323846 * x;
    return (std::sin(2 * a) / (2 * a)) * (std::sin(a) / a);
}

// Taps of output texel i of m along an axis of n source texels: the four
// source texels nearest its centre (i + 1/2) n / m, indices wrapped, with
// normalised kernel weights.
struct Taps {
    int index[4];
    double weight[4];
};
std::vector<Taps> ResampleTaps(int n, int m) {
    std::vector<Taps> taps(static_cast<size_t>(m));
    for (int i = 0; i < m; ++i) {
        const double centre = (i + 0.5) * n / m;
        const int first = int(std::floor(centre - 1.5));
        double sum = 0;
        for (int k = 0; k < 4; ++k) {
            const int j = first + k;
            taps[size_t(i)].index[k] = ((j % n) + n) % n;
            sum += taps[size_t(i)].weight[k] = ResampleKernel(j + 0.5 - centre);
        }
        for (double &w : taps[size_t(i)].weight) w /= sum;
    }
    return taps;
}

}  // namespace

Image ResampleToPowerOfTwo(const Image &image) {
    const int w = image.width(), h = image.height();
    const int W = NextPowerOfTwo(w), H = NextPowerOfTwo(h);
    if ((W == w && H == h) || w == 0 || h == 0) return image;
    const size_t nc = size_t(image.numChannels());
    // Along x (rows of the source), then along y; the clamp follows the second pass.
    const std::vector<Taps> tx = ResampleTaps(w, W), ty = ResampleTaps(h, H);
    std::vector<double> wide(size_t(W) * h * nc, 0.0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < W; ++x)
            for (int k = 0; k < 4; ++k)
                for (size_t c = 0; c < nc; ++c)
                    wide[(size_t(y) * W + x) * nc + c] += tx[size_t(x)].weight[k] * image.at(tx[size_t(x)].index[k], y, int(c));
    Image out(W, H, image.channelNames());
    out.metadata = image.metadata;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (size_t c = 0; c < nc; ++c) {
                double v = 0;
                for (int k = 0; k < 4; ++k) v += ty[size_t(y)].weight[k] * wide[(size_t(ty[size_t(y)].index[k]) * W + x) * nc + c];
                out.at(x, y, int(c)) = float(std::max(0.0, v));
            }
    return out;
}

float SRGBToLinear(float v) {
    if (v <= 0.04045f) return v / 12.92f;
    return std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float LinearToSRGB(float v) {
    if (v <= 0.0031308f) return 12.92f * v;
    return 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

MetaValue MetaValue::Int(int64_t v) {
    MetaValue m(std::to_string(v));
    m.type_ = Type::Int;
    return m;
}

MetaValue MetaValue::Double(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    MetaValue m(buf);
    m.type_ = Type::Double;
    return m;
}

double MetaValue::number() const {
    char *end = nullptr;
    double v = std::strtod(text_.c_str(), &end);
    return end && *end == 0 && !text_.empty() ? v : 0;
}

}  // namespace gradus
