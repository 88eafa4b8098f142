// Helpers for renderer tests: render a scene given as text, in memory.
#pragma once
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "common/render_test_util.h"
#include "job/job.h"

namespace gradus::test {

// RenderResult (job/job.h): image and render statistics.
inline RenderResult RenderDesc(const SceneDesc &desc, int spp, uint64_t seed, int nthreads,
                               const std::string &integrator) {
    TestRender t = RenderTestDesc(desc, spp, seed, nthreads, integrator);
    return {std::move(t.image), t.stats};
}

inline RenderResult RenderSceneText(const std::string &text, int spp, uint64_t seed = 0, int nthreads = 0,
                                    const std::string &integrator = "", const std::string &dir = ".") {
    return RenderDesc(ParseString(text, "test.pbrt", dir), spp, seed, nthreads, integrator);
}

inline RenderResult RenderSceneFile(const std::string &path, int spp, uint64_t seed = 0,
                                    const std::string &integrator = "") {
    return RenderDesc(ParseFile(path), spp, seed, 0, integrator);
}

// Mean and standard error of the mean of channel c over all pixels.
inline void PixelMeanAndStdErr(const Image &img, int c, double *mean, double *stderrOut) {
    double s = 0, s2 = 0;
    int n = img.width() * img.height();
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) {
            double v = img.at(x, y, c);
            s += v;
            s2 += v * v;
        }
    *mean = s / n;
    double var = std::max(0.0, s2 / n - *mean * *mean) * n / (n - 1);
    *stderrOut = std::sqrt(var / n);
}

// Largest |z| over blocks x channels of the paired difference of two
// independent renders of the same scene: per block, the mean of the per-pixel
// differences over its standard error (image structure cancels in the pairs).
// Blocks whose differences are all zero are skipped.
inline double MaxPairedBlockZ(const Image &a, const Image &b, int block) {
    double worst = 0;
    for (int by = 0; by + block <= a.height(); by += block)
        for (int bx = 0; bx + block <= a.width(); bx += block)
            for (int c = 0; c < 3; ++c) {
                double s = 0, s2 = 0;
                int n = 0;
                for (int y = by; y < by + block; ++y)
                    for (int x = bx; x < bx + block; ++x, ++n) {
                        double d = double(a.at(x, y, c)) - b.at(x, y, c);
                        s += d;
                        s2 += d * d;
                    }
                double m = s / n, se = std::sqrt(std::max(0.0, s2 / n - m * m) / (n - 1));
                if (se > 0) worst = std::max(worst, std::abs(m / se));
            }
    return worst;
}

}  // namespace gradus::test
