// Comparison metrics, statistics, merging and false colour against values worked
// out by hand on tiny images.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "image/metrics.h"

using namespace gradus;

namespace {

// An RGB image from a flat list of pixel values (row-major).
Image Make(int w, int h, std::vector<float> v) {
    Image img = Image::RGB(w, h);
    EXPECT_EQ(v.size(), img.data().size());
    img.data() = std::move(v);
    return img;
}

}  // namespace

// img: (1,2,3) (0.5,0.5,0.5); ref: (1,1,1) (0,1,0.5).
// Squared errors: 0,1,4 | 0.25,0.25,0  -> MSE = 5.5/6.
// relMSE terms: 0, 1/1.001, 4/1.001 | 0.25/0.001, 0.25/1.001, 0/0.251.
TEST(Metrics, HandComputedValues) {
    Image img = Make(2, 1, {1, 2, 3, 0.5f, 0.5f, 0.5f});
    Image ref = Make(2, 1, {1, 1, 1, 0, 1, 0.5f});
    ImageMetrics m = CompareImages(img, ref);
    EXPECT_EQ(m.usedPixels, 2);
    EXPECT_EQ(m.nonFinitePixels, 0);
    EXPECT_NEAR(m.mse, 0.9166666667, 1e-9);
    EXPECT_NEAR(m.rmse, 0.9574271078, 1e-9);
    EXPECT_NEAR(m.psnr, 0.3778856, 1e-6);  // 10 log10(12/11)
    EXPECT_NEAR(m.relmse, (5.0 / 1.001 + 250.0 + 0.25 / 1.001) / 6, 1e-9);
    EXPECT_NEAR(m.relmse, 42.54079254, 1e-7);
    EXPECT_NEAR(m.meanImg, 1.25, 1e-12);
    EXPECT_NEAR(m.meanRef, 0.75, 1e-12);
    EXPECT_NEAR(m.meanDiff, 0.5, 1e-12);
    EXPECT_NEAR(m.meanRelDiff, 2.0 / 3.0, 1e-12);
    EXPECT_DOUBLE_EQ(MetricValue(m, "relmse"), m.relmse);
    EXPECT_DOUBLE_EQ(MetricValue(m, "psnr"), m.psnr);
    EXPECT_THROW(MetricValue(m, "ssim"), Error);

    // A different epsilon changes only relMSE.
    CompareOptions o;
    o.relEpsilon = 0.01;
    ImageMetrics m2 = CompareImages(img, ref, o);
    EXPECT_NEAR(m2.relmse, (5.0 / 1.01 + 25.0 + 0.25 / 1.01) / 6, 1e-9);
    EXPECT_DOUBLE_EQ(m2.mse, m.mse);
}

TEST(Metrics, IdenticalImages) {
    Image a = Make(2, 1, {0.1f, 0.2f, 0.3f, 4, 5, 6});
    ImageMetrics m = CompareImages(a, a);
    EXPECT_EQ(m.mse, 0);
    EXPECT_EQ(m.relmse, 0);
    EXPECT_TRUE(std::isinf(m.psnr));
}

// Pixel 0 has a large absolute but small relative error; pixel 1 a small absolute
// error on a dark reference (large relMSE). Trimming ranks by relMSE.
TEST(Metrics, DiscardRanksByPerPixelRelMSE) {
    Image img = Make(4, 1, {12, 12, 12, 0.1f, 0.1f, 0.1f, 1, 1, 1, 2, 2, 2});
    Image ref = Make(4, 1, {10, 10, 10, 0, 0, 0, 1, 1, 1, 2, 2, 2});
    // Per-pixel relMSE: 4/100.001 = 0.04, 0.01/0.001 = 10, 0, 0.
    CompareOptions o;
    o.discardCount = 1;
    ImageMetrics m = CompareImages(img, ref, o);
    EXPECT_EQ(m.discardedPixels, 1);
    EXPECT_EQ(m.usedPixels, 3);
    EXPECT_NEAR(m.mse, 12.0 / 9, 1e-9);  // only pixel 0's errors remain
    EXPECT_NEAR(m.relmse, (4.0 / 100.001) / 3, 1e-9);

    CompareOptions f;
    f.discardFraction = 0.3;  // floor(0.3 * 4) = 1 pixel
    ImageMetrics mf = CompareImages(img, ref, f);
    EXPECT_EQ(mf.discardedPixels, 1);
    EXPECT_DOUBLE_EQ(mf.relmse, m.relmse);

    f.discardFraction = 0.5;  // 2 pixels: both with non-zero error
    ImageMetrics m2 = CompareImages(img, ref, f);
    EXPECT_EQ(m2.discardedPixels, 2);
    EXPECT_EQ(m2.mse, 0);

    f.discardCount = 1;  // fraction and count add up: 3 pixels
    EXPECT_EQ(CompareImages(img, ref, f).usedPixels, 1);

    CompareOptions all;
    all.discardCount = 4;
    EXPECT_THROW(CompareImages(img, ref, all), Error);
    CompareOptions bad;
    bad.discardFraction = 1.0;
    EXPECT_THROW(CompareImages(img, ref, bad), Error);
    bad.discardFraction = -0.1;
    EXPECT_THROW(CompareImages(img, ref, bad), Error);
}

TEST(Metrics, NonFiniteValuesAreCountedAndExcluded) {
    Image img = Make(3, 1, {NAN, 1, 1, 2, 2, 2, 1, 1, 1});
    Image ref = Make(3, 1, {1, 1, 1, 1, 1, INFINITY, 0, 0, 0});
    ImageMetrics m = CompareImages(img, ref);
    EXPECT_EQ(m.imgNaN, 1);
    EXPECT_EQ(m.imgInf, 0);
    EXPECT_EQ(m.refInf, 1);
    EXPECT_EQ(m.refNaN, 0);
    EXPECT_EQ(m.nonFinitePixels, 2);
    EXPECT_EQ(m.usedPixels, 1);
    EXPECT_NEAR(m.mse, 1.0, 1e-12);  // only pixel 2: (1-0)^2
    EXPECT_NEAR(m.relmse, 1000.0, 1e-9);
    EXPECT_TRUE(std::isfinite(m.meanImg));
}

TEST(Metrics, SizeMismatchAndLayers) {
    EXPECT_THROW(CompareImages(Image::RGB(2, 2), Image::RGB(2, 3)), Error);

    Image img(1, 1, {"R", "G", "B", "primal.R", "primal.G", "primal.B"});
    for (int c = 0; c < 3; ++c) img.at(0, 0, c) = 5.f, img.at(0, 0, c + 3) = 1.5f;
    Image ref = Make(1, 1, {1, 1, 1});
    CompareOptions o;
    EXPECT_NEAR(CompareImages(img, ref, o).mse, 16.0, 1e-12);
    o.layer = "primal";
    ImageMetrics m = CompareImages(img, ref, o);
    EXPECT_EQ(m.layer, "primal");
    EXPECT_EQ(m.refLayer, "");
    EXPECT_NEAR(m.mse, 0.25, 1e-12);
    o.layer = "dx";
    EXPECT_THROW(CompareImages(img, ref, o), Error);
}

TEST(Metrics, ErrorImage) {
    Image img = Make(2, 1, {1, 2, 3, NAN, 0.5f, 0.5f});
    Image ref = Make(2, 1, {1, 1, 1, 0, 1, 0.5f});
    Image e = ErrorImage(img, ref, {}, "relmse");
    ASSERT_EQ(e.numChannels(), 5);
    int rel = e.channelIndex("relmse"), ex = e.channelIndex("excluded");
    EXPECT_NEAR(e.at(0, 0, 1), 1 / 1.001, 1e-6);
    EXPECT_NEAR(e.at(0, 0, 2), 4 / 1.001, 1e-6);
    EXPECT_NEAR(e.at(0, 0, rel), 5 / 1.001 / 3, 1e-6);
    EXPECT_EQ(e.at(0, 0, ex), 0.f);
    EXPECT_EQ(e.at(1, 0, ex), 1.f);
    EXPECT_EQ(e.at(1, 0, 0), 0.f);
    Image s = ErrorImage(img, ref, {}, "mse");
    EXPECT_NEAR(s.at(0, 0, 2), 4.f, 1e-6);
    EXPECT_THROW(ErrorImage(img, ref, {}, "bogus"), Error);
}

TEST(Metrics, ChannelStats) {
    Image img(2, 2, {"R", "dx.R"});
    img.data() = {1, -1, 3, INFINITY, NAN, 0, 5, 2};
    auto s = ComputeChannelStats(img);
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(s[0].name, "R");
    EXPECT_EQ(s[0].nan, 1);
    EXPECT_EQ(s[0].finite, 3);
    EXPECT_DOUBLE_EQ(s[0].min, 1);
    EXPECT_DOUBLE_EQ(s[0].max, 5);
    EXPECT_DOUBLE_EQ(s[0].mean, 3);
    EXPECT_EQ(s[1].inf, 1);
    EXPECT_DOUBLE_EQ(s[1].min, -1);
    EXPECT_DOUBLE_EQ(s[1].mean, 1.0 / 3);
}

TEST(Merge, WeightsBySppMetadata) {
    Image a = Make(1, 1, {1, 2, 0}), b = Make(1, 1, {4, 2, 8});
    a.metadata["spp"] = "16";
    b.metadata["spp"] = "48";
    bool fromSpp = false;
    std::vector<double> w = SppWeights({a, b}, &fromSpp);
    EXPECT_TRUE(fromSpp);
    Image m = MergeImages({a, b}, w);
    EXPECT_NEAR(m.at(0, 0, 0), (16 * 1 + 48 * 4) / 64.0, 1e-6);  // 3.25
    EXPECT_NEAR(m.at(0, 0, 1), 2.0, 1e-6);
    EXPECT_NEAR(m.at(0, 0, 2), 6.0, 1e-6);
    EXPECT_EQ(m.metadata.at("spp"), "64");

    // One input without spp: equal weights.
    b.metadata.erase("spp");
    w = SppWeights({a, b}, &fromSpp);
    EXPECT_FALSE(fromSpp);
    Image e = MergeImages({a, b}, w);
    EXPECT_NEAR(e.at(0, 0, 0), 2.5, 1e-6);

    // Explicit weights, and a NaN left out of its pixel's average.
    b.data()[2] = NAN;
    long long skipped = 0;
    Image x = MergeImages({a, b}, {1, 3}, &skipped);
    EXPECT_NEAR(x.at(0, 0, 0), 3.25, 1e-6);
    EXPECT_EQ(x.at(0, 0, 2), 0.f);  // only a's 0 remains
    EXPECT_EQ(skipped, 1);

    EXPECT_THROW(MergeImages({a, b}, {1}), Error);
    EXPECT_THROW(MergeImages({a, b}, {1, -1}), Error);
    EXPECT_THROW(MergeImages({a, Image::RGB(2, 1)}, {1, 1}), Error);
    EXPECT_THROW(MergeImages({a, Image(1, 1, {"R", "G", "B", "A"})}, {1, 1}), Error);
    EXPECT_THROW(MergeImages({}, {}), Error);
}

TEST(FalseColor, RampEndsAndNaN) {
    Image v(3, 1, {"relmse"});
    v.data() = {0.f, 10.f, NAN};
    Image c = FalseColor(v, 0, 2.0);  // 10 is clamped to the top of the ramp
    for (int k = 0; k < 3; ++k) EXPECT_EQ(c.at(0, 0, k), 0.f);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(c.at(1, 0, k), 1.f, 1e-6);
    EXPECT_EQ(c.at(2, 0, 0), 0.f);
    EXPECT_NEAR(c.at(2, 0, 1), 1.f, 1e-6);
    EXPECT_THROW(FalseColor(v, 0, 0.0), Error);
    EXPECT_THROW(FalseColor(v, 1, 1.0), Error);
}
