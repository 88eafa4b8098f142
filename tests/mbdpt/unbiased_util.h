// M-BDPT agrees with BDPT in expectation: every reorder option, m = 1, 2, 4,
// the other column samplers and the combinatorial mode, on the main image and
// on every per-(s, t) strategy image.
//
// Each configuration renders R = 24 independent runs (seeds) of a 16x16 box
// scene; BDPT renders R other runs. For each 8x8 quadrant (main image) or each
// strategy layer (whole-image mean) the run means give a Welch z statistic.
// Under the null hypothesis (both unbiased) a run mean is near normal and
// |z| > 5 has probability about 5e-5 (Student t, 23 dof); the main-image test
// tests make 15 x 4 = 60 comparisons, the strategy-layer tests 2 x 15: family-wise
// false-positive rate below 5e-3 for a random choice of seeds. The seeds are
// fixed, so the outcome is deterministic. Each comparison also checks its
// power: a 20% bias of a quadrant, or 30% of a (MIS-weighted) strategy image
// with a mean above 1e-3, would exceed the threshold.
// Default tier: distance reordering with m = 1, 2, 4 (test_unbiased_fast.cpp);
// slow tier: the other options (test_unbiased_slow.cpp).
#pragma once
#include <gtest/gtest.h>

#include <map>

#include "integrators/mbdpt/mbdpt.h"
#include "mbdpt_test_util.h"

namespace gradus::mbdpt_test {

constexpr int kRuns = 24, kSpp = 16, kDepth = 4;
constexpr double kZ = 5, kPowerBias = 1.2, kLayerPowerBias = 1.3;

inline std::string Integrator(const std::string &name, const std::string &params) {
    return "Integrator \"" + name + "\" \"integer maxdepth\" [" + std::to_string(kDepth) + "] " + params;
}

// Per-run values of the four quadrant means followed by the strategy-layer means.
inline std::vector<std::vector<double>> Runs(const std::string &name, const std::string &params, uint64_t seed0,
                                      const std::string &layerPrefix) {
    std::vector<std::vector<double>> v;
    for (int r = 0; r < kRuns; ++r) {
        Rendered out = Render(BoxScene(Integrator(name, params), 16, /*mirror=*/false), kSpp, seed0 + r);
        std::vector<double> row;
        for (int q = 0; q < 4; ++q) {
            int x0 = (q % 2) * 8, y0 = (q / 2) * 8;
            row.push_back(BlockMean(out.image, x0, y0, x0 + 8, y0 + 8));
        }
        if (!layerPrefix.empty())
            for (int d = 0; d <= kDepth; ++d)
                for (int t = 2; t <= d + 2; ++t)
                    row.push_back(BlockMean(out.image, 0, 0, 16, 16,
                                            layerPrefix + "_s" + std::to_string(d + 2 - t) + "_t" + std::to_string(t)));
        v.push_back(row);
    }
    return v;
}

inline RunStats Column(const std::vector<std::vector<double>> &runs, size_t i) {
    std::vector<double> c;
    for (const auto &r : runs) c.push_back(r[i]);
    return Stats(c);
}

inline const std::vector<std::vector<double>> &BDPTRuns() {
    static const auto runs = Runs("bdpt", "\"bool visualizeweights\" [true]", 5000, "bdpt");
    return runs;
}

inline void ExpectAgreement(const std::string &params, uint64_t seed0, bool layers = false) {
    const auto &ref = BDPTRuns();
    std::string p = params + (layers ? " \"bool visualizeweights\" [true]" : "");
    auto runs = Runs("mbdpt", p, seed0, layers ? "mbdpt" : "");
    size_t n = layers ? ref[0].size() : 4;
    for (size_t i = 0; i < n; ++i) {
        RunStats a = Column(runs, i), b = Column(ref, i);
        std::string what = i < 4 ? "quadrant " + std::to_string(i) : "strategy layer " + std::to_string(i - 4);
        EXPECT_LT(std::abs(ZScore(a, b)), kZ) << params << " " << what << ": mbdpt " << a.mean << " bdpt " << b.mean;
        const double bias = i < 4 ? kPowerBias : kLayerPowerBias;
        if (i < 4 || b.mean > 1e-3) {
            RunStats biased = a;
            biased.mean = b.mean * bias;
            biased.var *= bias * bias;
            EXPECT_GT(std::abs(ZScore(biased, b)), kZ) << params << " " << what << " too noisy to see a bias x" << bias;
        }
    }
}

}  // namespace gradus::mbdpt_test
