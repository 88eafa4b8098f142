// The samplers: addressability (pure functions of seed, pixel, sample index and
// dimension), thread independence, uniformity and stratification quality.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <thread>
#include <vector>

#include "common/chi2_test.h"
#include "samplers/lowdiscrepancy.h"
#include "samplers/samplers.h"

using namespace gradus;

namespace {

struct Kind {
    const char *name;
    std::function<std::unique_ptr<Sampler>(uint64_t seed)> make;
};

const std::vector<Kind> &Kinds() {
    static const std::vector<Kind> kinds = {
        {"random", [](uint64_t s) { return std::make_unique<RandomSampler>(16, s); }},
        {"stratified", [](uint64_t s) { return std::make_unique<StratifiedSampler>(4, 4, true, s); }},
        {"halton", [](uint64_t s) { return std::make_unique<HaltonSampler>(16, s); }},
        {"sobol", [](uint64_t s) { return std::make_unique<SobolSampler>(16, s); }},
    };
    return kinds;
}

// A fixed mix of 1D and 2D requests: dims 0 | 1,2 | 3 | 4,5 | 6,7 | 8 -> 9 values.
std::vector<Float> ReadPattern(Sampler &s) {
    std::vector<Float> v;
    v.push_back(s.get1D());
    Point2 p = s.get2D();
    v.push_back(p.x), v.push_back(p.y);
    v.push_back(s.get1D());
    p = s.get2D();
    v.push_back(p.x), v.push_back(p.y);
    p = s.get2D();
    v.push_back(p.x), v.push_back(p.y);
    v.push_back(s.get1D());
    return v;
}

constexpr int kPixels = 6, kSpp = 16;
Point2i PixelOf(int k) { return {3 * k - 5, 1000 + 7 * k}; }

// Table of all values, in natural order.
std::vector<std::vector<Float>> Table(const Sampler &proto) {
    auto s = proto.clone();
    std::vector<std::vector<Float>> t;
    for (int p = 0; p < kPixels; ++p)
        for (int i = 0; i < kSpp; ++i) {
            s->startPixelSample(PixelOf(p), i);
            t.push_back(ReadPattern(*s));
        }
    return t;
}

class SamplerTest : public ::testing::TestWithParam<int> {
  protected:
    const Kind &kind() const { return Kinds()[GetParam()]; }
};

std::string KindName(const ::testing::TestParamInfo<int> &info) { return Kinds()[info.param].name; }

}  // namespace

TEST_P(SamplerTest, ValuesArePureFunctionsOfTheAddress) {
    auto s = kind().make(1234);
    EXPECT_EQ(s->name(), kind().name);
    EXPECT_EQ(s->samplesPerPixel(), 16);
    auto table = Table(*s);
    // Reversed order of (pixel, index), through a clone, re-reading each sample twice.
    auto c = s->clone();
    for (int p = kPixels - 1; p >= 0; --p)
        for (int i = kSpp - 1; i >= 0; --i) {
            c->startPixelSample(PixelOf(p), i);
            ReadPattern(*c);
            c->startPixelSample(PixelOf(p), i);
            EXPECT_EQ(ReadPattern(*c), table[p * kSpp + i]) << "pixel " << p << " sample " << i;
        }
    // Starting at a dimension gives the value that sequential reading gives there.
    for (int i = 0; i < kSpp; ++i) {
        const auto &row = table[2 * kSpp + i];
        c->startPixelSample(PixelOf(2), i, 3);
        EXPECT_EQ(c->get1D(), row[3]);
        c->startPixelSample(PixelOf(2), i, 6);
        Point2 q = c->get2D();
        EXPECT_EQ(q.x, row[6]);
        EXPECT_EQ(q.y, row[7]);
        EXPECT_EQ(c->get1D(), row[8]);
    }
    // All values in [0, 1); another seed or pixel changes them.
    for (auto &row : table)
        for (Float v : row) ASSERT_TRUE(v >= 0 && v < 1) << v;
    auto other = Table(*kind().make(1235));
    int same = 0, total = 0, samePixel = 0;
    for (size_t r = 0; r < table.size(); ++r)
        for (size_t k = 0; k < table[r].size(); ++k) {
            same += table[r][k] == other[r][k];
            if (r + kSpp < table.size()) samePixel += table[r][k] == table[r + kSpp][k];
            ++total;
        }
    EXPECT_LT(same, total / 50);
    EXPECT_LT(samePixel, total / 50);
}

TEST_P(SamplerTest, ThreadsAndOrderDoNotChangeValues) {
    auto s = kind().make(77);
    auto table = Table(*s);
    const int nThreads = 4;
    std::vector<std::vector<std::vector<Float>>> got(nThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < nThreads; ++t)
        threads.emplace_back([&, t] {
            auto c = s->clone();
            // Thread t takes every nThreads-th sample, walking backwards.
            for (int k = kPixels * kSpp - 1 - t; k >= 0; k -= nThreads) {
                c->startPixelSample(PixelOf(k / kSpp), k % kSpp);
                got[t].push_back(ReadPattern(*c));
            }
        });
    for (auto &th : threads) th.join();
    for (int t = 0; t < nThreads; ++t) {
        size_t j = 0;
        for (int k = kPixels * kSpp - 1 - t; k >= 0; k -= nThreads, ++j) EXPECT_EQ(got[t][j], table[k]);
    }
}

// z-tests of mean (1/2) and variance (1/12) of each dimension over 32x32
// pixels x 16 samples. Samplers that stratify make the sample mean *less*
// variable than independent samples, so the iid standard error is
// conservative. |z| < 4 per test: two-sided false-positive rate 6.3e-5,
// times 4 samplers x 9 dims x 2 moments = 72 tests -> < 0.5% in all.
TEST_P(SamplerTest, MeanAndVarianceOfEveryDimension) {
    auto s = kind().make(5);
    const int n = 32 * 32 * kSpp;
    std::vector<double> sum(9, 0), sum2(9, 0);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x)
            for (int i = 0; i < kSpp; ++i) {
                s->startPixelSample({x, y}, i);
                auto v = ReadPattern(*s);
                for (int d = 0; d < 9; ++d) {
                    sum[d] += v[d];
                    sum2[d] += (v[d] - 0.5) * (v[d] - 0.5);
                }
            }
    for (int d = 0; d < 9; ++d) {
        double zMean = (sum[d] / n - 0.5) / std::sqrt(1.0 / 12 / n);
        double zVar = (sum2[d] / n - 1.0 / 12) / std::sqrt(1.0 / 180 / n);
        EXPECT_LT(std::abs(zMean), 4) << "dim " << d;
        EXPECT_LT(std::abs(zVar), 4) << "dim " << d;
    }
}

// Joint uniformity of pairs of dimensions (within one 2D request, across
// requests, between 1D requests) over 64x64 pixels x 16 samples, chi-square on
// 10x10 bins. 4 samplers x 5 pairs share a 1% false-positive rate (Sidak);
// within-pixel stratification only lowers the statistic.
TEST_P(SamplerTest, PairsOfDimensionsAreJointlyUniform) {
    const std::pair<int, int> pairs[] = {{1, 2}, {4, 5}, {1, 4}, {2, 7}, {0, 8}};
    for (auto [a, b] : pairs) {
        auto s = kind().make(9);
        int64_t k = 0;
        chi2::Options o;
        o.xBins = o.yBins = 10;
        o.samples = 64 * 64 * kSpp;
        o.alpha = chi2::SidakAlpha(0.01, 4 * 5);
        o.subdivisions = 1;
        auto r = chi2::PlanarTest(
            [&](RNG &, Point2 *p) {
                int pix = int(k / kSpp), i = int(k % kSpp);
                ++k;
                s->startPixelSample({pix % 64, pix / 64}, i);
                auto v = ReadPattern(*s);
                *p = {v[a], v[b]};
                return true;
            },
            [](Point2) { return 1.0; }, o);
        EXPECT_TRUE(r.pass) << "dims " << a << "," << b << ": " << r.message;
    }
}

// Error of 16-sample estimates of a smooth integral over 256 pixels: the
// stratified and low-discrepancy samplers must beat independent sampling by a
// wide margin (expected ratios are ~0.1 or less; the threshold 0.5 is far
// from both the expected value and the MSE estimate's ~10% noise).
TEST(SamplerQuality, StratifiedSamplersReduceIntegrationError) {
    auto f = [](Point2 p) { return std::exp(-4 * (Sqr(p.x - 0.3) + Sqr(p.y - 0.6))) + p.x * p.y; };
    // Exact integral: int exp(-4 (x-.3)^2) dx over [0,1] times the same for y, plus 1/4.
    auto g = [](double c) { return std::sqrt(Pi) / 4 * (std::erf(2 * (1 - c)) + std::erf(2 * c)); };
    const double exact = g(0.3) * g(0.6) + 0.25;
    auto mse = [&](Sampler &s, int dimension) {
        double e2 = 0;
        for (int p = 0; p < 256; ++p) {
            double est = 0;
            for (int i = 0; i < 16; ++i) {
                s.startPixelSample({p, 3}, i, dimension);
                est += f(s.get2D());
            }
            e2 += Sqr(est / 16 - exact);
        }
        return e2 / 256;
    };
    RandomSampler random(16, 3);
    double base = mse(random, 0);
    for (int k = 1; k < int(Kinds().size()); ++k) {
        auto s = Kinds()[k].make(3);
        for (int dim : {0, 6}) EXPECT_LT(mse(*s, dim), 0.5 * base) << Kinds()[k].name << " dim " << dim;
    }
}

// Dimensions of different requests must be paired at random within a pixel:
// without the per-dimension index shuffle of the padded Sobol' sampler, the
// same index drives every pair and, e.g., the top bits of dims 1 and 4 are
// perfectly (anti-)correlated in each pixel. Estimating
// E[1(a < 1/2) 1(b < 1/2)] = 1/4 with 16 samples then has MSE 1/16, against
// 3/256 for independent samples and ~1/240 for a random pairing of strata.
// Threshold: 1.5x the independent sampler's MSE over 512 pixels (whose own
// relative noise is ~6%).
TEST(SamplerQuality, PaddedDimensionsAreDecorrelated) {
    auto mse = [](Sampler &s, int a, int b) {
        double e2 = 0;
        for (int p = 0; p < 512; ++p) {
            double est = 0;
            for (int i = 0; i < 16; ++i) {
                s.startPixelSample({p, 0}, i);
                auto v = ReadPattern(s);
                est += (v[a] < 0.5 && v[b] < 0.5) ? 1 : 0;
            }
            e2 += Sqr(est / 16 - 0.25);
        }
        return e2 / 512;
    };
    for (auto [a, b] : {std::pair<int, int>{1, 4}, {0, 3}, {2, 7}, {4, 6}}) {
        RandomSampler random(16, 8);
        double base = mse(random, a, b);
        EXPECT_NEAR(base, 3.0 / 256, 0.3 * 3.0 / 256);
        for (int k = 1; k < int(Kinds().size()); ++k) {
            auto s = Kinds()[k].make(8);
            EXPECT_LT(mse(*s, a, b), 1.5 * base) << Kinds()[k].name << " dims " << a << "," << b;
        }
    }
}

namespace {
// Number of points of `pts` in each cell of an nx x ny grid.
std::vector<int> Cells(const std::vector<Point2> &pts, int nx, int ny) {
    std::vector<int> c(nx * ny, 0);
    for (auto p : pts) ++c[int(p.y * ny) * nx + int(p.x * nx)];
    return c;
}
bool AllEqual(const std::vector<int> &c, int v) {
    return std::all_of(c.begin(), c.end(), [v](int x) { return x == v; });
}
std::vector<Point2> PixelPoints(Sampler &s, Point2i pixel, int dim, int first, int count) {
    std::vector<Point2> pts;
    for (int i = first; i < first + count; ++i) {
        s.startPixelSample(pixel, i, dim);
        pts.push_back(s.get2D());
    }
    return pts;
}
std::vector<Float> PixelValues(Sampler &s, Point2i pixel, int dim, int count) {
    std::vector<Float> v;
    for (int i = 0; i < count; ++i) {
        s.startPixelSample(pixel, i, dim);
        v.push_back(s.get1D());
    }
    return v;
}
bool Stratified1D(const std::vector<Float> &v, int n) {
    std::vector<Point2> pts;
    for (Float x : v) pts.push_back({x, 0});
    return AllEqual(Cells(pts, n, 1), 1);
}
}  // namespace

TEST(SamplerQuality, StratifiedFillsEveryStratum) {
    for (bool jitter : {true, false}) {
        StratifiedSampler s(4, 3, jitter, 11);
        for (int px = 0; px < 20; ++px)
            for (int dim : {0, 2, 9}) {
                EXPECT_TRUE(AllEqual(Cells(PixelPoints(s, {px, 1}, dim, 0, 12), 4, 3), 1));
                EXPECT_TRUE(AllEqual(Cells(PixelPoints(s, {px, 1}, dim, 12, 12), 4, 3), 1));  // next block
                EXPECT_TRUE(Stratified1D(PixelValues(s, {px, 1}, dim, 12), 12));
            }
        if (!jitter) {  // un-jittered samples sit at stratum centres
            s.startPixelSample({0, 0}, 5);
            Float v = s.get1D();
            EXPECT_NEAR(v * 12 - std::floor(v * 12), 0.5, 1e-12);
        }
    }
}

// Every block of 2^m samples of a pixel is a (0,m,2)-net in every 2D request
// (all elementary intervals of area 2^-m hold one point) and stratified in 1D.
TEST(SamplerQuality, SobolPixelSamplesAreNets) {
    for (int spp : {1, 4, 16, 64}) {
        SobolSampler s(spp, 21);
        int m = 0;
        while ((1 << m) < spp) ++m;
        for (int px = 0; px < 8; ++px)
            for (int dim : {0, 2, 10}) {
                for (int block : {0, 1}) {
                    auto pts = PixelPoints(s, {px, -px}, dim, block * spp, spp);
                    for (int k = 0; k <= m; ++k)
                        EXPECT_TRUE(AllEqual(Cells(pts, 1 << k, 1 << (m - k)), 1))
                            << "spp " << spp << " pixel " << px << " dim " << dim << " k " << k;
                }
                EXPECT_TRUE(Stratified1D(PixelValues(s, {px, -px}, dim, spp), spp));
            }
    }
    EXPECT_EQ(RoundUpPow2(1), 1);
    EXPECT_EQ(RoundUpPow2(5), 8);
    EXPECT_EQ(RoundUpPow2(16), 16);
}

// Scrambled Halton keeps the radical-inverse strata: in bases 2 and 3 the
// first 16 points fill 1/16 strata, the first 9 the 1/9 strata, the first 6
// the 2x3 grid.
TEST(SamplerQuality, HaltonPixelSamplesAreStratified) {
    HaltonSampler s(16, 31);
    for (int px = 0; px < 10; ++px) {
        auto pts = PixelPoints(s, {px, 2}, 0, 0, 16);
        std::vector<Float> xs, ys;
        for (auto p : pts) xs.push_back(p.x);
        for (int i = 0; i < 9; ++i) ys.push_back(pts[i].y);
        EXPECT_TRUE(Stratified1D(xs, 16));
        EXPECT_TRUE(Stratified1D(ys, 9));
        EXPECT_TRUE(AllEqual(Cells(std::vector<Point2>(pts.begin(), pts.begin() + 6), 2, 3), 1));
        // Dimension 2 uses base 5: the first 5 samples fill the 1/5 strata.
        EXPECT_TRUE(Stratified1D(PixelValues(s, {px, 2}, 2, 5), 5));
    }
    // Dimensions past the prime table still work.
    s.startPixelSample({0, 0}, 3, PrimeTableSize + 5);
    Float v = s.get1D();
    EXPECT_TRUE(v >= 0 && v < 1);
}

// Unbiasedness of the scrambled samplers: over 4096 pixels (independent
// scrambles), the mean of 16-sample estimates of integrals over [0,1)^2 (a
// smooth function and a disk's indicator) matches the exact value within
// 4.5 standard errors (estimated from the pixels; false-positive rate ~7e-6
// per check, 3 samplers x 3 dimension pairs x 2 integrands), in the first
// dimensions (bases 2, 3 for halton) and in dimensions of one and two digits.
TEST(SamplerQuality, PixelEstimatesAreUnbiased) {
    auto g = [](double c) { return std::sqrt(Pi) / 4 * (std::erf(2 * (1 - c)) + std::erf(2 * c)); };
    struct Integrand {
        std::function<double(Point2)> f;
        double exact;
    };
    const Integrand fs[] = {
        {[](Point2 p) { return std::exp(-4 * (Sqr(p.x - 0.3) + Sqr(p.y - 0.6))) + p.x * p.y; },
         g(0.3) * g(0.6) + 0.25},
        {[](Point2 p) { return Sqr(p.x) + Sqr(p.y) < 0.5 ? 1.0 : 0.0; }, Pi / 8},
    };
    for (int k = 1; k < int(Kinds().size()); ++k)
        for (int dim : {0, 8, 300}) {
            auto s = Kinds()[k].make(17);
            for (const Integrand &in : fs) {
                const int P = 4096;
                double sum = 0, sum2 = 0;
                for (int p = 0; p < P; ++p) {
                    double est = 0;
                    for (int i = 0; i < 16; ++i) {
                        s->startPixelSample({p % 64, p / 64}, i, dim);
                        est += in.f(s->get2D());
                    }
                    est /= 16;
                    sum += est;
                    sum2 += est * est;
                }
                double mean = sum / P, var = (sum2 / P - mean * mean) * P / (P - 1);
                double z = (mean - in.exact) / std::sqrt(var / P);
                EXPECT_LT(std::abs(z), 4.5) << Kinds()[k].name << " dim " << dim << " mean " << mean << " exact "
                                            << in.exact;
            }
        }
}

INSTANTIATE_TEST_SUITE_P(All, SamplerTest, ::testing::Range(0, 4), KindName);
