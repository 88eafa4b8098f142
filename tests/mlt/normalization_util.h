// The running normalisation of the Metropolis driver (metropolis/metropolis.h,
// 4.): with b refined during the render, the image mean of mlt, pmlt and gmlt
// at 16 mutations per pixel is that of the scene, not that of the bootstrap's b.
//
// Statistic (the criterion). K = 8 renders (seeds s0 + k) give the
// ratios r_k = image mean luminance / true mean; the render passes when
// |mean_k r_k - 1| <= 1% and every |r_k - 1| <= 3%. Power: a planted wrong b,
// the same ratios times 1.02 or 1 / 1.02 (the image mean is proportional to
// b), must fail that statistic. The false-positive rate follows from the
// spread of the r_k, which the scene parameters below keep small (the
// measured per-render sd is printed; a gaussian of that sd gives the rates
// that ExpectConverges states and bounds).
#pragma once
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "mlt_test_util.h"

namespace gradus::mlt_test {

struct Spread {
    double mean = 0, sd = 0, maxDev = 0;  // of the ratios
};

inline Spread SpreadOf(const std::vector<double> &r, double scale = 1) {
    Spread s;
    for (double v : r) s.mean += v * scale;
    s.mean /= double(r.size());
    for (double v : r) {
        s.sd += (v * scale - s.mean) * (v * scale - s.mean);
        s.maxDev = std::max(s.maxDev, std::abs(v * scale - 1));
    }
    s.sd = std::sqrt(s.sd / double(r.size() - 1));
    return s;
}

inline bool Passes(const Spread &s) { return std::abs(s.mean - 1) <= 0.01 && s.maxDev <= 0.03; }

// Two-sided gaussian tail P(|Z| > z).
inline double Tail(double z) { return std::erfc(z / std::sqrt(2.0)); }

// Image-mean ratios of K renders of `scene` against `truth`.
inline std::vector<double> Ratios(const std::string &scene, double truth, int spp, uint64_t seed0, int K = 8) {
    std::vector<double> r;
    for (int k = 0; k < K; ++k) r.push_back(MeanLum(Render(scene, spp, seed0 + uint64_t(k)).image) / truth);
    return r;
}

inline void ExpectConverges(const std::string &what, const std::vector<double> &r) {
    const Spread s = SpreadOf(r);
    std::ostringstream o;
    o << what << ": ratios";
    for (double v : r) o << " " << v;
    // Rates of a gaussian of the measured sd: the mean check (sd / sqrt(K))
    // and the K per-render checks; and the miss rate of a 2% wrong b.
    const double seMean = s.sd / std::sqrt(double(r.size()));
    const double fpMean = Tail(0.01 / seMean), fpEach = double(r.size()) * Tail(0.03 / s.sd);
    const double miss = 0.5 * (Tail((0.02 - 0.01) / seMean) - Tail((0.02 + 0.01) / seMean));
    o << "; mean " << s.mean << ", sd " << s.sd << ", max |r - 1| " << s.maxDev << "; false-positive rate ~ "
      << fpMean + fpEach << ", miss rate of a 2% wrong b ~ " << miss;
    std::cout << "[ normalisation ] " << o.str() << "\n";
    EXPECT_TRUE(Passes(s)) << o.str();
    // The spread must keep both rates small for the test to mean anything.
    EXPECT_LT(fpMean + fpEach, 1e-3) << o.str();
    EXPECT_LT(miss, 1e-3) << o.str();
    for (double scale : {1.02, 1 / 1.02})
        EXPECT_FALSE(Passes(SpreadOf(r, scale))) << "power check: b off by " << scale << " passes; " << o.str();
}

}  // namespace gradus::mlt_test
