// Film output range: accumulators are double; values beyond the float range
// of the outputs are clamped to +-FLT_MAX and counted, never written as Inf.
// Layer storage by LayerUse.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "core/error.h"
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

// Layers hold only the kinds they declare (LayerUse): values reach the image
// as with LayerUse::Both, the state round-trips (the unused kind as a zero
// array, the same format), a state with values of an unused kind is refused,
// and writing the undeclared kind is an internal error, never a silent drop.
TEST(Film, LayerUseKeepsOnlyTheDeclaredStorage) {
    const Float crop[4] = {0, 1, 0, 1};
    auto make = [&](LayerUse a, LayerUse b) {
        auto f = std::make_unique<Film>(Point2i{4, 2}, crop, CreateFilter(EntityDesc()), "x.exr", 1);
        f->addLayer("s", a);
        f->addLayer("p", b);
        return f;
    };
    auto fill = [](Film &f, bool samples, bool splats) {
        auto tile = f.makeTile(f.sampleBounds());
        tile->addCount({1, 0}, 2);
        if (samples) tile->addLayer(0, {1, 0}, Spectrum(4, 2, 0));
        if (splats) tile->addSplat(Point2(2.5, 1.5), Spectrum(0, 6, 3), 1);
        f.mergeTile(*tile);
        f.setSplatSamples(3);
    };
    auto kinds = make(LayerUse::Samples, LayerUse::Splats), both = make(LayerUse::Both, LayerUse::Both);
    fill(*kinds, true, true);
    fill(*both, true, true);
    const Image a = kinds->toImage(), b = both->toImage();
    EXPECT_TRUE(a.data() == b.data());
    EXPECT_EQ(a.layerRGB("s").at(1, 0, 0), 2.0f);
    EXPECT_EQ(a.layerRGB("p").at(2, 1, 1), 2.0f);
    // Same state bytes (unused kinds are zero arrays either way), and they load back.
    const std::string state = kinds->saveState();
    EXPECT_EQ(state, both->saveState());
    auto again = make(LayerUse::Samples, LayerUse::Splats);
    again->loadState(state);
    again->setSplatSamples(3);
    EXPECT_TRUE(again->toImage().data() == a.data());
    // Splat values in layer "s" do not fit a render that declares it sample-only.
    auto other = make(LayerUse::Both, LayerUse::Both);
    auto tile = other->makeTile(other->sampleBounds());
    tile->addSplat(Point2(0.5, 0.5), Spectrum(1), 0);
    other->mergeTile(*tile);
    EXPECT_THROW(kinds->loadState(other->saveState()), Error);
    EXPECT_DEATH(fill(*make(LayerUse::Splats, LayerUse::Splats), true, false), "internal check failed");
    EXPECT_DEATH(fill(*make(LayerUse::Samples, LayerUse::Samples), false, true), "internal check failed");
}
