// The primary sample space chain alone (integrators/mlt/primary_sample.h):
// reject/accept bookkeeping, the lazy catch-up of small steps, and that the
// Metropolis kernel leaves a target on [0,1)^n invariant when the coordinates
// read depend on the state (the case the lazy vector and the streams exist for).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "integrators/mlt/primary_sample.h"
#include "common/chi2_test.h"

namespace gradus::mlt {
namespace {

// Reads n coordinates of stream s.
std::vector<Float> Read(PrimarySampler &u, int s, int n) {
    u.startStream(s);
    std::vector<Float> v;
    for (int i = 0; i < n; ++i) v.push_back(u.get1D());
    return v;
}

TEST(PrimarySampler, RejectRestoresAndAcceptKeeps) {
    RNG rng(7);
    PrimarySampler u(0.05, 0.3);
    u.restart(&rng);
    const std::vector<Float> x = Read(u, kCameraStream, 5), l = Read(u, kLightStream, 3);
    // The state reads the same values again.
    EXPECT_EQ(Read(u, kCameraStream, 5), x);
    for (int k = 0; k < 50; ++k) {
        u.propose();
        std::vector<Float> y = Read(u, kCameraStream, 5);
        EXPECT_NE(y, x) << k;
        for (Float v : y) EXPECT_TRUE(v >= 0 && v < 1);
        u.reject();
        EXPECT_EQ(Read(u, kCameraStream, 5), x) << k;  // the state, not the proposal
    }
    EXPECT_EQ(Read(u, kLightStream, 3), l);
    u.propose();
    std::vector<Float> y = Read(u, kCameraStream, 5);
    u.accept();
    EXPECT_EQ(Read(u, kCameraStream, 5), y);
}

// Streams interleave: reading one stream further does not shift another.
TEST(PrimarySampler, StreamsAreIndependentOfEachOther) {
    RNG a(3), b(3);
    PrimarySampler u(0.01, 0.3), v(0.01, 0.3);
    u.restart(&a);
    v.restart(&b);
    std::vector<Float> c1 = Read(u, kCameraStream, 2);
    Read(u, kLightStream, 9);
    std::vector<Float> c2 = Read(u, kCameraStream, 4);
    EXPECT_EQ(std::vector<Float>(c2.begin(), c2.begin() + 2), c1);
    Read(v, kCameraStream, 4);  // same reads, different order: same camera values where both read them
    EXPECT_EQ(Read(v, kCameraStream, 2), c1);
}

// A coordinate left unread for n accepted small steps moves by sigma sqrt(n + 1)
// when read in the next proposal (n steps caught up + the proposal's own).
// Offsets of 4000 independent trials: variance within 10% of sigma^2 (n + 1)
// (the sample variance of 4000 normals is within 10% with probability
// 1 - 2e-5); after an accepted large step the coordinate is fresh instead
// (|offset| > 0.1 for about 80% of the trials, not ~0).
TEST(PrimarySampler, LazySmallStepsCatchUpAndLargeStepsRefresh) {
    const Float sigma = 1e-3;
    for (int n : {0, 9, 99}) {
        double s2 = 0;
        const int trials = 4000;
        for (int k = 0; k < trials; ++k) {
            RNG rng(uint64_t(1000 + k));
            PrimarySampler u(sigma, 0);
            u.restart(&rng);
            const Float x0 = Read(u, kLightStream, 1)[0];
            for (int i = 0; i < n; ++i) {
                u.propose();
                Read(u, kCameraStream, 1);  // the chain moves without reading the light stream
                u.accept();
            }
            u.propose();
            double d = Read(u, kLightStream, 1)[0] - x0;
            d -= std::round(d);  // wrapped offset
            s2 += d * d;
        }
        const double expected = sigma * sigma * (n + 1);
        EXPECT_NEAR(s2 / trials / expected, 1, 0.1) << "n = " << n;
    }
    int far = 0;
    const int trials = 2000;
    for (int k = 0; k < trials; ++k) {
        RNG rng(uint64_t(9000 + k));
        PrimarySampler u(sigma, 1);  // every proposal a large step
        u.restart(&rng);
        const Float x0 = Read(u, kLightStream, 1)[0];
        u.propose();
        Read(u, kCameraStream, 1);
        u.accept();
        double d = Read(u, kLightStream, 1)[0] - x0;  // the state's value, outside a proposal
        d -= std::round(d);
        far += std::abs(d) > 0.1;
    }
    EXPECT_NEAR(far / double(trials), 0.8, 0.05);
}

// Toy target on primary sample space: the connection-stream coordinate a picks
// which other coordinates are read, as a strategy choice does.
//   a < 1/2: f = 4a * 2v, v = light-stream coordinate 1 (coordinate 0 read and unused)
//   a >= 1/2: f = 1/2 + v, v = camera-stream coordinate 0
// Both halves hold mass 1/2. Returns f and the bin (4 x 4 over a and v).
Float Toy(PrimarySampler &u, int *bin) {
    u.startStream(kConnectionStream);
    const Float a = u.get1D();
    Float v, f;
    if (a < 0.5) {
        u.startStream(kLightStream);
        u.get1D();
        v = u.get1D();
        f = 4 * a * 2 * v;
    } else {
        u.startStream(kCameraStream);
        v = u.get1D();
        f = 0.5 + v;
    }
    *bin = std::min(3, int(a * 4)) * 4 + std::min(3, int(v * 4));
    return f;
}

// Probability of each bin under the toy target; `lowerHalf` scales the mass of a < 1/2.
std::vector<double> ToyBins(double lowerHalf = 1) {
    std::vector<double> p(16);
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double a0 = i / 4.0, a1 = (i + 1) / 4.0, v0 = j / 4.0, v1 = (j + 1) / 4.0;
            if (i < 2)
                p[size_t(i * 4 + j)] = lowerHalf * 2 * (a1 * a1 - a0 * a0) * (v1 * v1 - v0 * v0);
            else
                p[size_t(i * 4 + j)] = (2 - lowerHalf) * 0.25 * (0.5 * (v1 - v0) + 0.5 * (v1 * v1 - v0 * v0));
        }
    return p;
}

// Invariance: chains started from exact samples of the toy target (rejection
// sampling) and run for 40 Metropolis steps must still be distributed as the
// target. The final states of 20000 independent chains against the 16 bin
// probabilities: chi-square, 15 degrees of freedom, alpha = 1e-3 per
// configuration (3 configurations: false-positive rate <= 3e-3). Power check:
// the same counts against a target with 10% more mass on a < 1/2 are rejected.
TEST(PrimarySampler, MetropolisKernelKeepsTheTarget) {
    struct Config {
        Float sigma, pLarge;
    };
    for (const Config &cfg : {Config{0.05, 0.3}, Config{0.01, 0.1}, Config{0.2, 0}}) {
        SCOPED_TRACE(testing::Message() << "sigma " << cfg.sigma << ", large " << cfg.pLarge);
        std::vector<double> counts(16, 0);
        const int chains = 20000;
        for (int c = 0; c < chains; ++c) {
            RNG rng(uint64_t(c) * 7919 + 13);
            PrimarySampler u(cfg.sigma, cfg.pLarge);
            int bin = 0;
            Float f = 0;
            do {  // exact start: f <= 4
                u.restart(&rng);
                f = Toy(u, &bin);
            } while (!(rng.uniform() * 4 < f));
            for (int k = 0; k < 40; ++k) {
                u.propose();
                int nb = 0;
                const Float fy = Toy(u, &nb);
                const Float a = fy > 0 ? std::min<Float>(1, fy / f) : 0;
                if (rng.uniform() < a) {
                    u.accept();
                    f = fy;
                    bin = nb;
                } else {
                    u.reject();
                }
            }
            counts[size_t(bin)] += 1;
        }
        auto stat = [&](const std::vector<double> &p) {
            double x2 = 0;
            for (int i = 0; i < 16; ++i) {
                double e = p[size_t(i)] * chains;
                x2 += (counts[size_t(i)] - e) * (counts[size_t(i)] - e) / e;
            }
            return chi2::PValue(x2, 15);
        };
        EXPECT_GT(stat(ToyBins()), 1e-3);
        EXPECT_LT(stat(ToyBins(1.1)), 1e-3) << "power check";
    }
}

}  // namespace
}  // namespace gradus::mlt
