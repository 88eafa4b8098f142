#include "image/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.h"

namespace gradus {

namespace {

std::string SizeStr(const Image &i) {
    return std::to_string(i.width()) + "x" + std::to_string(i.height());
}

// The RGB pair being compared, and which pixels take part.
struct Prepared {
    Image a, r;                 // RGB copies
    std::string layer, refLayer;
    std::vector<char> finite;   // per pixel: no NaN/Inf in a or r
    std::vector<char> used;     // per pixel: finite and not trimmed
    std::vector<double> pixelRel;  // per-pixel relMSE averaged over channels
    long long imgNaN = 0, imgInf = 0, refNaN = 0, refInf = 0;
    long long nonFinite = 0, discarded = 0;
};

Prepared Prepare(const Image &img, const Image &ref, const CompareOptions &opts) {
    if (img.width() != ref.width() || img.height() != ref.height())
        throw Error("image size mismatch: " + SizeStr(img) + " vs reference " + SizeStr(ref));
    if (!(opts.discardFraction >= 0 && opts.discardFraction < 1))
        throw Error("discard fraction must be in [0, 1), got " + std::to_string(opts.discardFraction));
    if (opts.discardCount < 0) throw Error("discard count must be >= 0");
    if (!(opts.relEpsilon > 0)) throw Error("relMSE epsilon must be > 0");
    Prepared p;
    p.layer = opts.layer ? *opts.layer : DefaultRGBLayer(img);
    bool refHas = false;
    for (const std::string &l : ref.layers()) refHas |= (l == p.layer);
    p.refLayer = opts.refLayer ? *opts.refLayer : refHas ? p.layer : DefaultRGBLayer(ref);
    p.a = img.layerRGB(p.layer);
    p.r = ref.layerRGB(p.refLayer);
    size_t npix = size_t(img.width()) * size_t(img.height());
    p.finite.assign(npix, 1);
    p.pixelRel.assign(npix, 0.0);
    for (size_t i = 0; i < npix; ++i) {
        for (int c = 0; c < 3; ++c) {
            float x = p.a.data()[i * 3 + c], r = p.r.data()[i * 3 + c];
            if (std::isnan(x)) ++p.imgNaN, p.finite[i] = 0;
            else if (std::isinf(x)) ++p.imgInf, p.finite[i] = 0;
            if (std::isnan(r)) ++p.refNaN, p.finite[i] = 0;
            else if (std::isinf(r)) ++p.refInf, p.finite[i] = 0;
        }
        if (!p.finite[i]) {
            ++p.nonFinite;
            continue;
        }
        double s = 0;
        for (int c = 0; c < 3; ++c) {
            double x = p.a.data()[i * 3 + c], r = p.r.data()[i * 3 + c];
            s += (x - r) * (x - r) / (r * r + opts.relEpsilon);
        }
        p.pixelRel[i] = s / 3;
    }
    p.used = p.finite;
    long long nFinite = (long long)npix - p.nonFinite;
    long long drop = (long long)std::floor(opts.discardFraction * double(nFinite)) + opts.discardCount;
    if (drop >= nFinite)
        throw Error("nothing left to compare: " + std::to_string(nFinite) +
                    " finite pixels, " + std::to_string(drop) + " to discard");
    if (drop > 0) {
        // Highest per-pixel relMSE first; ties broken by pixel index for determinism.
        std::vector<size_t> idx;
        idx.reserve(size_t(nFinite));
        for (size_t i = 0; i < npix; ++i)
            if (p.finite[i]) idx.push_back(i);
        auto worse = [&](size_t a, size_t b) {
            if (p.pixelRel[a] != p.pixelRel[b]) return p.pixelRel[a] > p.pixelRel[b];
            return a < b;
        };
        std::nth_element(idx.begin(), idx.begin() + (drop - 1), idx.end(), worse);
        for (long long k = 0; k < drop; ++k) p.used[idx[size_t(k)]] = 0;
        p.discarded = drop;
    }
    return p;
}

}  // namespace

ImageMetrics CompareImages(const Image &img, const Image &ref, const CompareOptions &opts) {
    Prepared p = Prepare(img, ref, opts);
    ImageMetrics m;
    m.width = img.width();
    m.height = img.height();
    m.layer = p.layer;
    m.refLayer = p.refLayer;
    m.pixels = (long long)img.width() * img.height();
    m.nonFinitePixels = p.nonFinite;
    m.imgNaN = p.imgNaN;
    m.imgInf = p.imgInf;
    m.refNaN = p.refNaN;
    m.refInf = p.refInf;
    m.discardedPixels = p.discarded;
    double se = 0, rel = 0, sa = 0, sr = 0;
    long long used = 0;
    for (size_t i = 0; i < p.used.size(); ++i) {
        if (!p.used[i]) continue;
        ++used;
        rel += p.pixelRel[i];
        for (int c = 0; c < 3; ++c) {
            double x = p.a.data()[i * 3 + c], r = p.r.data()[i * 3 + c];
            se += (x - r) * (x - r);
            sa += x;
            sr += r;
        }
    }
    m.usedPixels = used;
    double nvals = 3.0 * double(used);
    m.mse = se / nvals;
    m.rmse = std::sqrt(m.mse);
    m.psnr = m.mse > 0 ? 10 * std::log10(1.0 / m.mse) : std::numeric_limits<double>::infinity();
    m.relmse = rel / double(used);
    m.meanImg = sa / nvals;
    m.meanRef = sr / nvals;
    m.meanDiff = m.meanImg - m.meanRef;
    m.meanRelDiff = m.meanRef != 0 ? m.meanDiff / m.meanRef : 0;
    return m;
}

double MetricValue(const ImageMetrics &m, const std::string &metric) {
    if (metric == "relmse") return m.relmse;
    if (metric == "mse") return m.mse;
    if (metric == "rmse") return m.rmse;
    if (metric == "psnr") return m.psnr;
    throw Error("unknown metric \"" + metric + "\" (valid: relmse, mse, rmse, psnr)");
}

Image ErrorImage(const Image &img, const Image &ref, const CompareOptions &opts,
                 const std::string &metric) {
    bool relative = metric == "relmse";
    if (!relative && metric != "mse" && metric != "rmse" && metric != "psnr")
        MetricValue(ImageMetrics(), metric);  // throws the unknown-metric error
    Prepared p = Prepare(img, ref, opts);
    Image out(img.width(), img.height(), {"R", "G", "B", "relmse", "excluded"});
    out.metadata["error_metric"] = relative ? "(X-R)^2/(R^2+" + std::to_string(opts.relEpsilon) + ")"
                                            : "(X-R)^2";
    for (size_t i = 0; i < p.used.size(); ++i) {
        float *o = out.data().data() + i * 5;
        if (!p.used[i]) {
            o[4] = 1.f;
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            double x = p.a.data()[i * 3 + c], r = p.r.data()[i * 3 + c];
            double e = (x - r) * (x - r);
            o[c] = float(relative ? e / (r * r + opts.relEpsilon) : e);
        }
        o[3] = float(p.pixelRel[i]);
    }
    return out;
}

std::vector<ChannelStats> ComputeChannelStats(const Image &image) {
    int nc = image.numChannels();
    std::vector<ChannelStats> stats(static_cast<size_t>(nc));
    std::vector<double> sums(static_cast<size_t>(nc), 0.0);
    for (int c = 0; c < nc; ++c) {
        stats[c].name = image.channelNames()[c];
        stats[c].min = std::numeric_limits<double>::infinity();
        stats[c].max = -std::numeric_limits<double>::infinity();
    }
    size_t npix = size_t(image.width()) * size_t(image.height());
    const float *d = image.data().data();
    for (size_t i = 0; i < npix; ++i)
        for (int c = 0; c < nc; ++c) {
            float v = d[i * nc + c];
            ChannelStats &s = stats[c];
            if (std::isnan(v)) ++s.nan;
            else if (std::isinf(v)) ++s.inf;
            else {
                ++s.finite;
                sums[c] += v;
                s.min = std::min(s.min, double(v));
                s.max = std::max(s.max, double(v));
            }
        }
    for (int c = 0; c < nc; ++c) {
        if (stats[c].finite == 0) stats[c].min = stats[c].max = 0;
        else stats[c].mean = sums[c] / double(stats[c].finite);
    }
    return stats;
}

std::vector<double> SppWeights(const std::vector<Image> &images, bool *fromSpp) {
    std::vector<double> w;
    for (const Image &img : images) {
        auto it = img.metadata.find("spp");
        double v = 0;
        if (it != img.metadata.end()) {
            try {
                size_t used = 0;
                v = std::stod(it->second.str(), &used);
                if (used != it->second.str().size()) v = 0;
            } catch (const std::exception &) {
                v = 0;
            }
        }
        if (!(v > 0) || !std::isfinite(v)) {
            if (fromSpp) *fromSpp = false;
            return std::vector<double>(images.size(), 1.0);
        }
        w.push_back(v);
    }
    if (fromSpp) *fromSpp = true;
    return w;
}

Image MergeImages(const std::vector<Image> &images, const std::vector<double> &weights,
                  long long *skipped) {
    if (images.empty()) throw Error("merge: no input images");
    if (weights.size() != images.size())
        throw Error("merge: " + std::to_string(weights.size()) + " weights for " +
                    std::to_string(images.size()) + " images");
    for (double w : weights)
        if (!(w > 0) || !std::isfinite(w)) throw Error("merge: weights must be positive and finite");
    const Image &first = images[0];
    for (size_t k = 1; k < images.size(); ++k) {
        if (images[k].width() != first.width() || images[k].height() != first.height())
            throw Error("merge: image " + std::to_string(k + 1) + " is " + SizeStr(images[k]) +
                        ", image 1 is " + SizeStr(first));
        if (images[k].channelNames() != first.channelNames())
            throw Error("merge: image " + std::to_string(k + 1) +
                        " has different channels from image 1");
    }
    Image out(first.width(), first.height(), first.channelNames());
    out.metadata = first.metadata;
    long long bad = 0;
    size_t n = out.data().size();
    for (size_t i = 0; i < n; ++i) {
        double sum = 0, wsum = 0;
        for (size_t k = 0; k < images.size(); ++k) {
            float v = images[k].data()[i];
            if (!std::isfinite(v)) {
                ++bad;
                continue;
            }
            sum += weights[k] * v;
            wsum += weights[k];
        }
        out.data()[i] = wsum > 0 ? float(sum / wsum) : std::numeric_limits<float>::quiet_NaN();
    }
    bool fromSpp = false;
    std::vector<double> spp = SppWeights(images, &fromSpp);
    if (fromSpp) {
        double total = std::accumulate(spp.begin(), spp.end(), 0.0);
        out.metadata["spp"] = total == std::floor(total) && total < 1e15
                                  ? std::to_string((long long)total)
                                  : std::to_string(total);
    }
    out.metadata["merged_images"] = std::to_string(images.size());
    if (skipped) *skipped = bad;
    return out;
}

Image FalseColor(const Image &values, int channel, double maxValue) {
    if (channel < 0 || channel >= values.numChannels()) throw Error("falsecolor: bad channel");
    if (!(maxValue > 0) || !std::isfinite(maxValue))
        throw Error("falsecolor: maximum must be positive and finite");
    // Ramp control points in display (sRGB) values.
    static const float ramp[][3] = {{0.f, 0.f, 0.f},   {0.35f, 0.05f, 0.55f}, {0.85f, 0.1f, 0.25f},
                                    {1.f, 0.55f, 0.f}, {1.f, 0.95f, 0.1f},    {1.f, 1.f, 1.f}};
    const int nr = int(sizeof(ramp) / sizeof(ramp[0]));
    Image out = Image::RGB(values.width(), values.height());
    size_t npix = size_t(values.width()) * size_t(values.height());
    int nc = values.numChannels();
    for (size_t i = 0; i < npix; ++i) {
        float v = values.data()[i * nc + channel];
        float col[3];
        if (std::isnan(v)) {
            col[0] = 0.f, col[1] = 1.f, col[2] = 1.f;
        } else {
            double t = std::clamp(double(v) / maxValue, 0.0, 1.0) * (nr - 1);
            int k = std::min(int(t), nr - 2);
            float f = float(t - k);
            for (int c = 0; c < 3; ++c) col[c] = ramp[k][c] * (1 - f) + ramp[k + 1][c] * f;
        }
        for (int c = 0; c < 3; ++c) out.data()[i * 3 + c] = SRGBToLinear(col[c]);
    }
    return out;
}

}  // namespace gradus
