// Synthetic inputs for the reconstruction tests and benchmarks.
#pragma once
#include <algorithm>
#include <cmath>
#include <random>

#include "reconstruction/reconstruction.h"

namespace gradus {
namespace testutil {

// A smooth shaded background with a bright disc and a dark bar (hard edges).
inline std::vector<float> SceneImage(int W, int H, int C = 3) {
    std::vector<float> img(size_t(W) * H * C);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double u = (x + 0.5) / W, v = (y + 0.5) / H;
            double base = 0.3 + 0.2 * std::sin(3.0 * u) * std::cos(2.0 * v);
            double dxc = u - 0.6, dyc = v - 0.4;
            bool disc = dxc * dxc + dyc * dyc < 0.04;
            bool bar = u > 0.15 && u < 0.3 && v > 0.2;
            for (int c = 0; c < C; ++c) {
                double val = base * (1.0 + 0.3 * c);
                if (disc) val += 2.0 - 0.5 * c;
                if (bar) val *= 0.1;
                img[(size_t(y) * W + x) * C + c] = float(val);
            }
        }
    return img;
}

// Exact inputs (primal = img, dx/dy its forward differences, 0 on missing edges).
inline GradientImages ExactInputs(const std::vector<float> &img, int W, int H, int C = 3) {
    GradientImages g;
    g.width = W;
    g.height = H;
    g.channels = C;
    g.primal = img;
    g.dx.assign(img.size(), 0.f);
    g.dy.assign(img.size(), 0.f);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < C; ++c) {
                size_t i = (size_t(y) * W + x) * C + c;
                if (x + 1 < W) g.dx[i] = img[i + C] - img[i];
                if (y + 1 < H) g.dy[i] = img[i + size_t(W) * C] - img[i];
            }
    return g;
}

// Adds zero-mean noise: Gaussian with standard deviations sp (primal) and sg
// (gradients), plus rare "fireflies" of mean zero when fireflyProb > 0
// (value +A with probability q, -A q/(1-q) otherwise: unbiased but heavy-tailed).
inline void AddNoise(GradientImages &g, double sp, double sg, unsigned seed,
                     double fireflyProb = 0, double fireflyAmp = 0) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto noise = [&](double s) {
        double v = s * n(rng);
        if (fireflyProb > 0)
            v += u(rng) < fireflyProb ? fireflyAmp : -fireflyAmp * fireflyProb / (1 - fireflyProb);
        return v;
    };
    for (auto &v : g.primal) v = float(v + noise(sp));
    for (auto &v : g.dx) v = float(v + noise(sg));
    for (auto &v : g.dy) v = float(v + noise(sg));
}

inline double MaxAbs(const std::vector<float> &a) {
    double m = 0;
    for (float v : a) m = std::max(m, double(std::fabs(v)));
    return m;
}

inline double MaxAbsDiff(const std::vector<float> &a, const std::vector<float> &b) {
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, double(std::fabs(a[i] - b[i])));
    return m;
}

inline double Mse(const std::vector<float> &a, const std::vector<float> &b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += double(a[i] - b[i]) * (a[i] - b[i]);
    return s / a.size();
}

}  // namespace testutil
}  // namespace gradus
