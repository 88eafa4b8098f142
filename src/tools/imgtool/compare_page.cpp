#include "compare_page.h"

#include <Imath/half.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "compare_assets.h"
#include "core/error.h"

namespace gradus {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string Base64(const std::vector<unsigned char> &in) {
    static const char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((in.size() + 2) / 3 * 4);
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t v = uint32_t(in[i]) << 16;
        size_t n = std::min<size_t>(3, in.size() - i);
        if (n > 1) v |= uint32_t(in[i + 1]) << 8;
        if (n > 2) v |= uint32_t(in[i + 2]);
        for (size_t k = 0; k < 4; ++k)
            out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=';
    }
    return out;
}

// RGB as half floats in planes R, G, B, all low bytes first and then all high
// bytes (the high bytes, sign and exponent, deflate well), zlib-compressed.
// Finite values beyond the half range are clamped to +-65504.
std::vector<unsigned char> PackHalfRGB(const Image &rgb) {
    size_t npix = size_t(rgb.width()) * size_t(rgb.height()), n = npix * 3;
    std::vector<unsigned char> raw(2 * n);
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < npix; ++i) {
            float v = rgb.data()[i * 3 + c];
            if (std::isfinite(v)) v = std::clamp(v, -65504.f, 65504.f);  // the largest half
            uint16_t bits = Imath::half(v).bits();
            size_t k = size_t(c) * npix + i;
            raw[k] = (unsigned char)(bits & 0xff);
            raw[n + k] = (unsigned char)(bits >> 8);
        }
    uLongf size = compressBound(uLong(raw.size()));
    std::vector<unsigned char> packed(size);
    if (compress2(packed.data(), &size, raw.data(), uLong(raw.size()), 6) != Z_OK)
        throw Error("compare: zlib compression failed");
    packed.resize(size);
    return packed;
}

std::string Stem(const std::string &path) { return fs::path(path).stem().string(); }

// Layer `layer` ("" = default) of an image as RGB, with errors naming the file.
Image LayerOf(const Image &img, const std::string &path, std::string *layer) {
    try {
        if (layer->empty()) *layer = DefaultRGBLayer(img);
        return img.layerRGB(*layer);
    } catch (const Error &e) {
        throw Error(path + ": " + e.what());
    }
}

json MetadataJson(const Image &img) {
    json meta = json::object();
    for (const auto &[key, v] : img.metadata) {
        if (v.type() == MetaValue::Type::Int) meta[key] = (long long)v.number();
        else if (v.type() == MetaValue::Type::Double) meta[key] = Number(v.number());
        else meta[key] = v.str();
    }
    return meta;
}

void WriteText(const fs::path &file, const std::string &text) {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(text.data(), std::streamsize(text.size()));
    out.close();
    if (!out) throw Error("compare: cannot write " + file.string());
}

}  // namespace

double ErrorQuantile(const Image &err, double q) {
    int ch = err.channelIndex("relmse"), ex = err.channelIndex("excluded"), nc = err.numChannels();
    std::vector<float> v;
    size_t npix = size_t(err.width()) * size_t(err.height());
    for (size_t i = 0; i < npix; ++i)
        if (err.data()[i * nc + ex] == 0.f) v.push_back(err.data()[i * nc + ch]);
    if (v.empty()) return 0;
    size_t k = std::min(v.size() - 1, size_t(q * double(v.size())));
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
    return v[k];
}

ComparePageSummary WriteComparePage(const std::string &dir, const std::vector<ComparePageInput> &inputs,
                                    const ComparePageOptions &opts) {
    if (inputs.size() < 2) throw Error("compare: a reference and at least one image are needed");
    if (inputs.size() > 64) throw Error("compare: at most 63 images besides the reference");
    // Everything is read and checked before the folder is touched.
    std::vector<Image> images;
    std::vector<std::string> layers;
    for (const ComparePageInput &in : inputs) {
        images.push_back(ReadImage(in.path));
        layers.push_back(in.layer);
    }
    const Image &ref = images[0];
    for (size_t k = 1; k < images.size(); ++k)
        if (images[k].width() != ref.width() || images[k].height() != ref.height())
            throw Error("compare: image size mismatch: " + inputs[k].path + " is " +
                        std::to_string(images[k].width()) + "x" + std::to_string(images[k].height()) +
                        ", the reference " + inputs[0].path + " " + std::to_string(ref.width()) + "x" +
                        std::to_string(ref.height()));
    std::vector<Image> rgb;
    for (size_t k = 0; k < images.size(); ++k) rgb.push_back(LayerOf(images[k], inputs[k].path, &layers[k]));

    ComparePageSummary summary;
    CompareOptions mo;  // the RGB copies are compared as shown: no layers
    mo.discardFraction = opts.metrics.discardFraction;
    mo.discardCount = opts.metrics.discardCount;
    mo.relEpsilon = opts.metrics.relEpsilon;
    json jimages = json::array();
    std::vector<double> logQ;
    for (size_t k = 0; k < images.size(); ++k) {
        json ji;
        ji["label"] = inputs[k].label.empty() ? Stem(inputs[k].path) : inputs[k].label;
        ji["file"] = fs::path(inputs[k].path).filename().string();
        ji["layer"] = layers[k];
        ji["reference"] = k == 0;
        ji["data"] = "img-" + std::to_string(k) + ".js";
        ji["metadata"] = MetadataJson(images[k]);
        ImageMetrics m = CompareImages(rgb[k], rgb[0], mo);
        json jm = {{"mean", Number(m.meanImg)}, {"nonfinite_pixels", m.nonFinitePixels}};
        if (k > 0) {
            jm.update({{"relmse", Number(m.relmse)}, {"mse", Number(m.mse)}, {"rmse", Number(m.rmse)},
                       {"psnr", Number(m.psnr)}, {"mean_rel_diff", Number(m.meanRelDiff)},
                       {"used_pixels", m.usedPixels}, {"discarded_pixels", m.discardedPixels}});
            summary.metrics.push_back(m);
            if (!(opts.errorMax > 0)) {
                double q = ErrorQuantile(ErrorImage(rgb[k], rgb[0], mo), 0.99);
                if (q > 0) logQ.push_back(std::log(q));
            }
        }
        ji["metrics"] = jm;
        jimages.push_back(ji);
    }
    // Default ramp top: the geometric mean of the images' 99th percentiles of
    // per-pixel relMSE (as bench/run's error maps), so no image saturates alone.
    summary.errorMax = opts.errorMax;
    if (!(summary.errorMax > 0)) {
        double s = 0;
        for (double l : logQ) s += l;
        summary.errorMax = logQ.empty() ? 1.0 : std::exp(s / double(logQ.size()));
    }
    json data;
    data["format"] = 1;
    std::string title = opts.title;
    if (title.empty()) {
        title = "Gradus comparison: ";
        for (size_t k = 1; k < jimages.size(); ++k)
            title += jimages[k]["label"].get<std::string>() + (k + 1 < jimages.size() ? ", " : " against ");
        title += jimages[0]["label"].get<std::string>();
    }
    data["title"] = title;
    data["width"] = ref.width();
    data["height"] = ref.height();
    data["exposure"] = opts.exposure;
    data["error_max"] = summary.errorMax;
    data["epsilon"] = mo.relEpsilon;
    data["discard_fraction"] = mo.discardFraction;
    data["discard_count"] = mo.discardCount;
    data["encoding"] = "half RGB planes, low bytes then high bytes, zlib, base64";
    data["images"] = jimages;

    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) throw Error("compare: cannot create the folder " + dir);
    auto write = [&](const std::string &name, const std::string &text) {
        WriteText(fs::path(dir) / name, text);
        summary.files.push_back(name);
        summary.bytes += text.size();
    };
    for (int a = 0; a < kNumCompareAssets; ++a) write(kCompareAssets[a].name, kCompareAssets[a].text);
    write("data.js", "window.GRADUS_COMPARE = " + data.dump() + ";\n");
    for (size_t k = 0; k < rgb.size(); ++k)
        write("img-" + std::to_string(k) + ".js",
              "(window.GRADUS_IMAGES = window.GRADUS_IMAGES || {})[" + std::to_string(k) + "] = \"" +
                  Base64(PackHalfRGB(rgb[k])) + "\";\n");
    return summary;
}

}  // namespace gradus
