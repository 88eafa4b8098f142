// Film output range: accumulators are double; values beyond the float range
// of the outputs are clamped to +-FLT_MAX and counted, never written as Inf.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "render/film.h"

using namespace gradus;

TEST(Film, ValuesBeyondFloatRangeAreClampedAndCounted) {
    const Float crop[4] = {0, 1, 0, 1};
    Film film({4, 2}, crop, CreateFilter(EntityDesc()), "x.exr", 1);
    int layer = film.addLayer("extra");
    auto tile = film.makeTile(film.sampleBounds());
    tile->addSample(Point2(0.5, 0.5), Spectrum(1e40, -1e40, 2));
    tile->addCount({1, 0}, 1);
    tile->addLayer(layer, {1, 0}, Spectrum(3, 1e300, 0));
    film.mergeTile(*tile);
    Image img = film.toImage();
    const float big = std::numeric_limits<float>::max();
    EXPECT_EQ(img.at(0, 0, 0), big);
    EXPECT_EQ(img.at(0, 0, 1), -big);
    EXPECT_EQ(img.at(0, 0, 2), 2.0f);
    Image l = img.layerRGB("extra");
    EXPECT_EQ(l.at(1, 0, 0), 3.0f);
    EXPECT_EQ(l.at(1, 0, 1), big);
    EXPECT_EQ(film.clampedValues(), 3u);
    for (float v : img.data()) EXPECT_TRUE(std::isfinite(v));
}
