// Pixel filters (box, triangle, gaussian, mitchell, sinc) against their closed
// forms, written here from the definitions (pbrt-v3's parameters: xwidth and
// ywidth are radii); their integrals by a Gauss-Legendre quadrature against
// closed forms; the Mitchell-Netravali family against the cubic B-spline and
// Catmull-Rom and its partition of unity; and the film's use of a filter
// (pixel centres at +0.5, the support inclusive of the radius, x and y apart).
// The filters are evaluated, never sampled (the film splats each sample onto
// the pixels in reach), so there is no sampling routine to test.
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "filters/filter.h"
#include "parser/scene_desc.h"
#include "render/film.h"
#include "samplers/rng.h"

namespace gradus {
namespace {

std::unique_ptr<Filter> MakeFilter(const std::string &directive) {
    SceneDesc d = ParseString(directive + "\nWorldBegin\nWorldEnd\n", "test.pbrt");
    return CreateFilter(d.filter);
}

// 1D closed forms.
double Tri(double x, double r) { return std::max(0.0, r - std::abs(x)); }
double Gauss(double x, double r, double a) { return std::max(0.0, std::exp(-a * x * x) - std::exp(-a * r * r)); }
// Mitchell & Netravali (1988), k on [-2, 2].
double MitchellK(double x, double B, double C) {
    x = std::abs(x);
    if (x < 1) return ((12 - 9 * B - 6 * C) * x * x * x + (-18 + 12 * B + 6 * C) * x * x + (6 - 2 * B)) / 6;
    if (x < 2)
        return ((-B - 6 * C) * x * x * x + (6 * B + 30 * C) * x * x + (-12 * B - 48 * C) * x + (8 * B + 24 * C)) / 6;
    return 0;
}
double Sinc(double x) { return x == 0 ? 1 : std::sin(M_PI * x) / (M_PI * x); }
double Lanczos(double x, double r, double tau) { return std::abs(x) > r ? 0 : Sinc(x) * Sinc(x / tau); }

struct Case {
    std::string directive;
    double rx, ry;
    std::function<double(double, double)> f;  // closed form inside the radius
    double integral;                          // closed form, or NaN
};

std::vector<Case> Cases() {
    const double nan = std::nan("");
    auto gaussIntegral = [](double r, double a) {
        return std::sqrt(M_PI / a) * std::erf(std::sqrt(a) * r) - 2 * r * std::exp(-a * r * r);
    };
    std::vector<Case> c;
    c.push_back({"PixelFilter \"box\"", 0.5, 0.5, [](double, double) { return 1.0; }, 1});
    c.push_back({"PixelFilter \"box\" \"float xwidth\" [1.5] \"float ywidth\" [0.75]", 1.5, 0.75,
                 [](double, double) { return 1.0; }, 4 * 1.5 * 0.75});
    c.push_back({"PixelFilter \"triangle\"", 2, 2, [](double x, double y) { return Tri(x, 2) * Tri(y, 2); }, 16});
    c.push_back({"PixelFilter \"triangle\" \"float xwidth\" [1.25] \"float ywidth\" [3]", 1.25, 3,
                 [](double x, double y) { return Tri(x, 1.25) * Tri(y, 3); }, 1.25 * 1.25 * 9});
    c.push_back({"PixelFilter \"gaussian\"", 2, 2, [](double x, double y) { return Gauss(x, 2, 2) * Gauss(y, 2, 2); },
                 gaussIntegral(2, 2) * gaussIntegral(2, 2)});
    c.push_back({"PixelFilter \"gaussian\" \"float xwidth\" [2.5] \"float ywidth\" [1.2] \"float alpha\" [0.7]", 2.5, 1.2,
                 [](double x, double y) { return Gauss(x, 2.5, 0.7) * Gauss(y, 1.2, 0.7); },
                 gaussIntegral(2.5, 0.7) * gaussIntegral(1.2, 0.7)});
    // Mitchell: k(2 x / r), whose integral is r / 2 per axis for every B, C.
    c.push_back({"PixelFilter \"mitchell\"", 2, 2,
                 [](double x, double y) { return MitchellK(x, 1. / 3, 1. / 3) * MitchellK(y, 1. / 3, 1. / 3); }, 1});
    c.push_back({"PixelFilter \"mitchell\" \"float xwidth\" [1.6] \"float ywidth\" [2.4] \"float B\" [0.1] \"float C\" [0.7]",
                 1.6, 2.4, [](double x, double y) { return MitchellK(2 * x / 1.6, 0.1, 0.7) * MitchellK(2 * y / 2.4, 0.1, 0.7); },
                 1.6 * 2.4 / 4});
    c.push_back({"PixelFilter \"sinc\"", 4, 4, [](double x, double y) { return Lanczos(x, 4, 3) * Lanczos(y, 4, 3); }, nan});
    c.push_back({"PixelFilter \"sinc\" \"float xwidth\" [2.5] \"float ywidth\" [3.5] \"float tau\" [2]", 2.5, 3.5,
                 [](double x, double y) { return Lanczos(x, 2.5, 2) * Lanczos(y, 3.5, 2); }, nan});
    return c;
}

TEST(Filters, ValuesAreTheClosedForms) {
    for (const Case &c : Cases()) {
        SCOPED_TRACE(c.directive);
        auto f = MakeFilter(c.directive);
        EXPECT_EQ(f->radius.x, c.rx);
        EXPECT_EQ(f->radius.y, c.ry);
        RNG rng(21);
        for (int k = 0; k < 2000; ++k) {
            const double x = (2 * rng.uniform() - 1) * c.rx, y = (2 * rng.uniform() - 1) * c.ry;
            EXPECT_NEAR(f->evaluate(Point2(x, y)), c.f(x, y), 1e-12) << x << " " << y;
        }
        // The centre, the axes and the corners of the support.
        for (double sx : {-1.0, -0.5, 0.0, 0.5, 1.0})
            for (double sy : {-1.0, 0.0, 1.0})
                EXPECT_NEAR(f->evaluate(Point2(sx * c.rx, sy * c.ry)), c.f(sx * c.rx, sy * c.ry), 1e-12)
                    << sx << " " << sy;
    }
}

// Gauss-Legendre (5 points) on `parts` equal sub-intervals per axis: the
// filters' kinks (0, +-r/2 for Mitchell) fall on sub-interval ends, so the
// rule is exact to ~1e-13 on these piecewise-smooth integrands.
double Integrate2D(const Filter &f, int parts = 64) {
    const double xg[5] = {0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640, 0.9061798459386640};
    const double wg[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665, 0.2369268850561891,
                          0.2369268850561891};
    std::vector<double> xs, wx, ys, wy;
    auto nodes = [&](double r, std::vector<double> &p, std::vector<double> &w) {
        const double h = 2 * r / parts;
        for (int i = 0; i < parts; ++i)
            for (int g = 0; g < 5; ++g) {
                p.push_back(-r + (i + 0.5) * h + 0.5 * h * xg[g]);
                w.push_back(0.5 * h * wg[g]);
            }
    };
    nodes(f.radius.x, xs, wx);
    nodes(f.radius.y, ys, wy);
    double sum = 0;
    for (size_t j = 0; j < ys.size(); ++j)
        for (size_t i = 0; i < xs.size(); ++i) sum += wx[i] * wy[j] * f.evaluate(Point2(xs[i], ys[j]));
    return sum;
}

TEST(Filters, IntegralsAreTheClosedForms) {
    for (const Case &c : Cases()) {
        if (std::isnan(c.integral)) continue;
        SCOPED_TRACE(c.directive);
        auto f = MakeFilter(c.directive);
        EXPECT_NEAR(Integrate2D(*f) / c.integral, 1, 1e-10);
    }
}

// Mitchell-Netravali: (B, C) = (1, 0) is the cubic B-spline, (0, 1/2) is
// Catmull-Rom (interpolating: 1 at 0, 0 at +-1); every (B, C) sums to k(0)
// over shifts by r/2 (the family's partition of unity, times k(0) for y = 0).
TEST(Filters, MitchellFamily) {
    auto bspline = [](double x) {
        x = std::abs(x);
        return x < 1 ? (4 - 6 * x * x + 3 * x * x * x) / 6 : x < 2 ? std::pow(2 - x, 3) / 6 : 0;
    };
    auto catmullRom = [](double x) {
        x = std::abs(x);
        return x < 1 ? (3 * x * x * x - 5 * x * x + 2) / 2 : x < 2 ? (-x * x * x + 5 * x * x - 8 * x + 4) / 2 : 0;
    };
    const double r = 1.8;
    auto fb = MakeFilter("PixelFilter \"mitchell\" \"float xwidth\" [1.8] \"float ywidth\" [1.8] \"float B\" [1] \"float C\" [0]");
    auto fc = MakeFilter("PixelFilter \"mitchell\" \"float xwidth\" [1.8] \"float ywidth\" [1.8] \"float B\" [0] \"float C\" [0.5]");
    RNG rng(22);
    for (int k = 0; k < 500; ++k) {
        const double x = (2 * rng.uniform() - 1) * r, y = (2 * rng.uniform() - 1) * r;
        EXPECT_NEAR(fb->evaluate(Point2(x, y)), bspline(2 * x / r) * bspline(2 * y / r), 1e-12);
        EXPECT_NEAR(fc->evaluate(Point2(x, y)), catmullRom(2 * x / r) * catmullRom(2 * y / r), 1e-12);
    }
    EXPECT_NEAR(fc->evaluate(Point2(0, 0)), 1, 1e-12);
    EXPECT_NEAR(fc->evaluate(Point2(r / 2, 0)), 0, 1e-12);
    EXPECT_NEAR(fc->evaluate(Point2(0, -r / 2)), 0, 1e-12);
    for (double B : {0.3, 0.8}) {
        const double C = 1 - B;
        auto f = MakeFilter("PixelFilter \"mitchell\" \"float xwidth\" [1.8] \"float B\" [" + std::to_string(B) +
                            "] \"float C\" [" + std::to_string(C) + "]");
        const double k0 = (6 - 2 * B) / 6;  // f(x, 0) = k(2 x / r) k(0)
        for (int k = 0; k < 100; ++k) {
            const double x = rng.uniform() * r / 2;  // the shifts x - r, x - r/2, x, x + r/2 lie in [-r, r)
            double sum = 0;
            for (int j = -2; j <= 1; ++j) sum += f->evaluate(Point2(x + j * r / 2, 0));
            EXPECT_NEAR(sum, k0, 1e-12) << B << " x " << x;
        }
    }
}

// Windowed sinc: zero at the non-zero integers and at |x| > radius.
TEST(Filters, SincZerosAndWindow) {
    auto f = MakeFilter("PixelFilter \"sinc\" \"float xwidth\" [3.5] \"float ywidth\" [2.5] \"float tau\" [2.5]");
    EXPECT_NEAR(f->evaluate(Point2(0, 0)), 1, 1e-12);
    EXPECT_NEAR(f->evaluate(Point2(1e-7, -1e-7)), 1, 1e-12);
    for (int k : {-3, -2, -1, 1, 2, 3}) EXPECT_NEAR(f->evaluate(Point2(k, 0.3)), 0, 1e-15) << k;
    for (int k : {-2, -1, 1, 2}) EXPECT_NEAR(f->evaluate(Point2(0.7, k)), 0, 1e-15) << k;
    for (double x : {3.5001, 4.0, -5.0}) EXPECT_EQ(f->evaluate(Point2(x, 0)), 0);
    for (double y : {2.5001, -3.0}) EXPECT_EQ(f->evaluate(Point2(0, y)), 0);
}

TEST(Filters, RadiiOutsideTheRangeAreRefused) {
    for (const char *d : {"PixelFilter \"box\" \"float xwidth\" [0]", "PixelFilter \"gaussian\" \"float ywidth\" [-1]",
                          "PixelFilter \"triangle\" \"float xwidth\" [65]", "PixelFilter \"lanczos\""})
        EXPECT_THROW(MakeFilter(d), Error) << d;
}

// The film: a sample at p reaches the pixels whose centre c = (x + 0.5, y + 0.5)
// has |c - p| <= radius per axis, with weight f(c - p). Two samples, L = (1, 2,
// 4) at p1 and black at p2: a pixel holds L f1 / (f1 + f2) (zero where neither
// reaches). Anisotropic radii catch an x/y swap, the centres a half-pixel shift.
TEST(Filters, FilmWeightsSamplesByTheFilterAtPixelCentres) {
    struct FilmCase {
        std::string directive;
        double rx, ry;
        std::function<double(double, double)> f;
        Point2 p1, p2;
    };
    const FilmCase cases[] = {
        {"PixelFilter \"gaussian\" \"float xwidth\" [2.3] \"float ywidth\" [1.4] \"float alpha\" [0.9]", 2.3, 1.4,
         [](double x, double y) { return Gauss(x, 2.3, 0.9) * Gauss(y, 1.4, 0.9); }, Point2(6.3, 5.8), Point2(8.1, 6.6)},
        {"PixelFilter \"triangle\" \"float xwidth\" [1.2] \"float ywidth\" [2.6]", 1.2, 2.6,
         [](double x, double y) { return Tri(x, 1.2) * Tri(y, 2.6); }, Point2(5.05, 4.2), Point2(6.7, 7.9)},
        // Box of radius 0.5: p1 on the border of two pixels reaches both (the support is closed).
        {"PixelFilter \"box\"", 0.5, 0.5, [](double, double) { return 1.0; }, Point2(4.0, 3.25), Point2(9.5, 9.5)}};
    const Spectrum L(1, 2, 4);
    for (const FilmCase &c : cases) {
        SCOPED_TRACE(c.directive);
        const Float crop[4] = {0, 1, 0, 1};
        Film film(Point2i{16, 12}, crop, MakeFilter(c.directive), "unused.exr", 1);
        auto tile = film.makeTile(film.pixelBounds());
        tile->addSample(c.p1, L);
        tile->addSample(c.p2, Spectrum(0));
        film.mergeTile(*tile);
        const Image img = film.mainImage();
        int reached = 0;
        for (int y = 0; y < 12; ++y)
            for (int x = 0; x < 16; ++x) {
                auto w = [&](Point2 p) {
                    const double dx = x + 0.5 - p.x, dy = y + 0.5 - p.y;
                    return std::abs(dx) <= c.rx && std::abs(dy) <= c.ry ? c.f(dx, dy) : 0.0;
                };
                const double f1 = w(c.p1), f2 = w(c.p2), v = f1 + f2 > 0 ? f1 / (f1 + f2) : 0;
                reached += f1 > 0;
                for (int ch = 0; ch < 3; ++ch)
                    EXPECT_NEAR(img.at(x, y, ch), L[ch] * v, 1e-6 * L[ch]) << x << " " << y << " " << ch;
            }
        EXPECT_GE(reached, 2);
    }
}

}  // namespace
}  // namespace gradus
