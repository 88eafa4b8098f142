// Image comparison metrics (MSE, RMSE, PSNR, relMSE, mean differences) with
// NaN/Inf exclusion and outlier trimming, plus per-image statistics, spp-weighted
// merging and false-colour error maps. Used by imgtool, the tests and the bench.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "image/image.h"

namespace gradus {

struct CompareOptions {
    // Layer of the test image to compare (nullopt: DefaultRGBLayer). The reference
    // uses the same layer when it has it, else its own default layer.
    std::optional<std::string> layer;
    // Layer of the reference (nullopt: as described above).
    std::optional<std::string> refLayer;
    // Ignore the highest-error fraction of the finite pixels, ranked by per-pixel
    // relMSE averaged over channels; in [0, 1).
    double discardFraction = 0;
    // Ignore this many more of the highest-error pixels (added to the fraction's count).
    long long discardCount = 0;
    // relMSE denominator offset: (X-R)^2 / (R^2 + relEpsilon). 0.001 as in the papers.
    double relEpsilon = 0.001;
};

struct ImageMetrics {
    int width = 0, height = 0;
    std::string layer, refLayer;  // layers actually compared
    long long pixels = 0;           // width * height
    long long nonFinitePixels = 0;  // excluded because a channel of img or ref is NaN/Inf
    long long imgNaN = 0, imgInf = 0, refNaN = 0, refInf = 0;  // channel values
    long long discardedPixels = 0;  // trimmed outliers
    long long usedPixels = 0;       // pixels the figures below are computed over
    double mse = 0;     // mean over used pixels and R,G,B of (X-R)^2
    double rmse = 0;    // sqrt(mse)
    double psnr = 0;    // 10 log10(1 / mse), peak 1.0; +inf when mse == 0
    double relmse = 0;  // mean of (X-R)^2 / (R^2 + relEpsilon)
    double meanImg = 0, meanRef = 0;  // means over used pixels and channels
    double meanDiff = 0;     // meanImg - meanRef
    double meanRelDiff = 0;  // (meanImg - meanRef) / meanRef (0 if meanRef == 0)
};

// Compares the RGB of `img` against the reference `ref`. Throws gradus::Error on
// a size mismatch, bad options, or when no pixel is left to compare.
ImageMetrics CompareImages(const Image &img, const Image &ref, const CompareOptions &opts = {});

// Value of a metric by name: "relmse", "mse", "rmse" or "psnr" (else gradus::Error).
double MetricValue(const ImageMetrics &m, const std::string &metric);

// Per-pixel error image with channels R,G,B (per-channel error: (X-R)^2/(R^2+eps)
// for metric "relmse", (X-R)^2 otherwise), "relmse" (the per-pixel relMSE averaged
// over channels) and "excluded" (1 where a pixel was NaN/Inf or trimmed, its errors 0).
Image ErrorImage(const Image &img, const Image &ref, const CompareOptions &opts = {},
                 const std::string &metric = "relmse");

struct ChannelStats {
    std::string name;
    long long finite = 0, nan = 0, inf = 0;
    double min = 0, max = 0, mean = 0;  // over finite values (0 when none)
};
std::vector<ChannelStats> ComputeChannelStats(const Image &image);

// Weights from each image's "spp" metadata when every image has a valid one,
// else all 1. *fromSpp (optional) tells which was used.
std::vector<double> SppWeights(const std::vector<Image> &images, bool *fromSpp = nullptr);

// Weighted average of images with identical size and channel names. A NaN/Inf value
// is left out of its pixel's average (the other weights renormalised); their count
// goes to *skipped. Metadata comes from the first image; "spp" becomes the sum when
// all inputs carry one. Throws gradus::Error on mismatches or non-positive weights.
Image MergeImages(const std::vector<Image> &images, const std::vector<double> &weights,
                  long long *skipped = nullptr);

// Maps a single-channel value v (channel `channel` of `values`) to a colour ramp
// (black, purple, red, orange, yellow, white) over [0, maxValue]; NaN -> cyan.
// Returns a linear RGB image (so WriteImage(png) reproduces the ramp's sRGB colours).
Image FalseColor(const Image &values, int channel, double maxValue);

}  // namespace gradus
