// GradientFilm light-tracing splats: values at the splat pixel (forward
// differences) and at the neighbour (backward differences, sign flipped),
// normalised by the samples per pixel like every film splat, second moments / N
// in the variance layers, pixels outside the film dropped, and added to the
// per-pixel part of the same images.
#include <gtest/gtest.h>

#include <algorithm>

#include "integrators/gradient/gradient_film.h"

namespace gradus {
namespace {

struct BoxFilter : Filter {
    BoxFilter() : Filter(Vec2(0.5, 0.5)) {}
    Float evaluate(Point2) const override { return 1; }
};

std::unique_ptr<Film> MakeFilm(int w, int h, bool variance = true) {
    const Float crop[4] = {0, 1, 0, 1};
    auto film = std::make_unique<Film>(Point2i{w, h}, crop, std::make_unique<BoxFilter>(), "unused.exr", 1);
    film->setVarianceLayers(variance);
    return film;
}

float At(const std::vector<float> &v, int w, int x, int y) { return v[(size_t(y) * w + x) * 3]; }

GradientSplat Splat(Point2i pixel, double primal, const double diff[kNumNeighbours],
                    const bool active[kNumNeighbours]) {
    GradientSplat s;
    s.pixel = pixel;
    s.value.primal = Spectrum(primal);
    for (int k = 0; k < kNumNeighbours; ++k) {
        s.value.diff[k] = Spectrum(diff[k]);
        s.value.active[k] = active[k];
    }
    return s;
}

TEST(GradientFilm, LightTracingSplatsAtPixelAndNeighbour) {
    const int w = 4, h = 3, spp = 4;
    const Float scale = 2;
    std::unique_ptr<Film> film = MakeFilm(w, h);
    GradientFilm gf;
    gf.init(*film, false, true);
    std::unique_ptr<FilmTile> tile = film->makeSplatTile();
    SampleRecorder rec(*tile, {0, 0}, Point2(0.5, 0.5));
    // Differences of +x, -x, +y, -y (kNeighbourOffsets).
    const double d[kNumNeighbours] = {1, 3, 0.5, 7};
    const bool on[kNumNeighbours] = {true, true, true, false};
    gf.splatLightTracing(rec, Splat({1, 1}, 2, d, on), scale);
    gf.splatLightTracing(rec, Splat({5, 1}, 100, d, on), scale);  // outside: dropped
    film->mergeTile(*tile);
    film->setSplatSamples(spp);
    GradientImages g = gf.images(*film, spp);
    ASSERT_EQ(g.width, w);
    // value * scale / spp; variance (value * scale)^2 / spp / N.
    EXPECT_FLOAT_EQ(At(g.primal, w, 1, 1), 2 * 2 / 4.0);
    EXPECT_FLOAT_EQ(At(g.primalVar, w, 1, 1), 16 / 4.0 / 4);
    EXPECT_FLOAT_EQ(At(g.dx, w, 1, 1), 1 * 2 / 4.0);     // +x: dx at the pixel
    EXPECT_FLOAT_EQ(At(g.dx, w, 0, 1), -3 * 2 / 4.0);    // -x: dx at p - (1, 0), I(p) - I(p-1)
    EXPECT_FLOAT_EQ(At(g.dxVar, w, 0, 1), 36 / 4.0 / 4);
    EXPECT_FLOAT_EQ(At(g.dy, w, 1, 1), 0.5 * 2 / 4.0);   // +y
    EXPECT_FLOAT_EQ(At(g.dy, w, 1, 0), 0);               // -y inactive
    double total = 0;
    for (float v : g.primal) total += v;
    EXPECT_FLOAT_EQ(float(total), 3 * 1) << "R, G, B of the one splat inside; the one outside is dropped";
}

TEST(GradientFilm, LightTracingSplatsAddToPixelSamples) {
    const int w = 3, h = 2, spp = 2;
    std::unique_ptr<Film> film = MakeFilm(w, h);
    GradientFilm gf;
    gf.init(*film, false, true);
    Bounds2i all{{0, 0}, {w, h}};
    std::unique_ptr<FilmTile> tile = film->makeTile(all);
    for (int s = 0; s < spp; ++s) {
        SampleRecorder rec(*tile, {1, 0}, Point2(1.5, 0.5));
        tile->addCount({1, 0}, 1);
        GradientSample cam;
        cam.primal = Spectrum(3);
        gf.record(rec, cam);
        const double d[kNumNeighbours] = {0, 0, 0, 0};
        const bool off[kNumNeighbours] = {false, false, false, false};
        gf.splatLightTracing(rec, Splat({1, 0}, 1, d, off), 1);
    }
    film->mergeTile(*tile);
    film->setSplatSamples(spp);
    GradientImages g = gf.images(*film, spp);
    // Camera samples: mean 3 (variance 0); splats: 2 / 2 = 1 (variance 2 / 2 / 2).
    EXPECT_FLOAT_EQ(At(g.primal, w, 1, 0), 4);
    EXPECT_FLOAT_EQ(At(g.primalVar, w, 1, 0), 0.5);
}

// Without variances (the default) the film holds no squares and the images
// have no variance arrays; the values are those of a film with variances.
TEST(GradientFilm, NoSquaresWithoutVariance) {
    const int w = 3, h = 2, spp = 2;
    GradientImages g[2];
    int layers[2];
    for (int v = 0; v < 2; ++v) {
        std::unique_ptr<Film> film = MakeFilm(w, h, v == 1);
        GradientFilm gf;
        gf.init(*film, false, true);
        layers[v] = film->numLayers();
        std::unique_ptr<FilmTile> tile = film->makeTile({{0, 0}, {w, h}});
        for (int s = 0; s < spp; ++s) {
            SampleRecorder rec(*tile, {1, 0}, Point2(1.5, 0.5));
            tile->addCount({1, 0}, 1);
            GradientSample cam;
            cam.primal = Spectrum(3 + s);
            cam.diff[0] = Spectrum(0.25 * s);
            cam.active[0] = true;
            gf.record(rec, cam);
            const double d[kNumNeighbours] = {1, 0.5, 0, 0};
            const bool on[kNumNeighbours] = {true, true, false, false};
            gf.splatLightTracing(rec, Splat({1, 0}, 1 + s, d, on), 1);
        }
        film->mergeTile(*tile);
        film->setSplatSamples(spp);
        g[v] = gf.images(*film, spp);
    }
    // Values of the primal and 4 differences, per-sample and splats, and the separated light.
    EXPECT_EQ(layers[0], 11);
    EXPECT_EQ(layers[1], 21);
    EXPECT_FALSE(g[0].hasVariance());
    EXPECT_TRUE(g[1].hasVariance());
    EXPECT_EQ(g[0].primal, g[1].primal);
    EXPECT_EQ(g[0].dx, g[1].dx);
    EXPECT_EQ(g[0].dy, g[1].dy);
    Image out;
    EXPECT_THROW(WriteGradientOutput(g[0], ReconstructionNorm::Weighted, 0.2, &out), Error);
    WriteGradientOutput(g[0], ReconstructionNorm::L1, 0.2, &out);
    const std::vector<std::string> names = out.layers();
    EXPECT_NE(std::find(names.begin(), names.end(), "primal"), names.end());
    EXPECT_EQ(std::find(names.begin(), names.end(), "primal_var"), names.end());
}

}  // namespace
}  // namespace gradus
