// Helpers shared by the renderer test suites: in-memory renders of scene
// descriptions and small statistics on images.
#pragma once
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "image/image.h"
#include "parser/scene_desc.h"
#include "job/job.h"

namespace gradus::test {

struct TestRender {
    Image image;                 // film image with all layers, after Integrator::finish
    RenderStats stats;
    std::string statistics;      // Integrator::statistics()
    std::unique_ptr<Integrator> integrator;
};

// The lines before WorldBegin of the small test scenes: camera, random
// sampler (16 spp), box filter, a w x h film and the integrator line.
inline std::string TestSceneHeader(const std::string &lookAt, int fovDegrees, int w, int h,
                                   const std::string &integratorLine) {
    return "LookAt " + lookAt + "\nCamera \"perspective\" \"float fov\" [" + std::to_string(fovDegrees) +
           "]\nSampler \"random\" \"integer pixelsamples\" [16]\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [" + std::to_string(w) + "] \"integer yresolution\" [" +
           std::to_string(h) + "]\n  \"string filename\" [\"unused.exr\"]\n" + integratorLine + "\n";
}

// A two-triangle quad with its material (pbrt syntax).
inline std::string Quad(const std::string &mat, const char *P) {
    return "AttributeBegin\n" + mat + "\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [" + P +
           "]\nAttributeEnd\n";
}

// The walls of the closed box [-1,1] x [0,2] x [-1,1.2] (grey, a red and a
// green side) and a diffuse sphere on its floor, in world-block syntax.
inline std::string ClosedBoxWallsAndSphere() {
    const std::string grey = "Material \"matte\" \"rgb Kd\" [0.7 0.7 0.7]";
    std::string s = Quad(grey, "-1 0 -1  -1 0 1.2  1 0 1.2  1 0 -1");
    s += Quad(grey, "-1 2 -1  1 2 -1  1 2 1.2  -1 2 1.2");
    s += Quad(grey, "-1 0 -1  1 0 -1  1 2 -1  -1 2 -1");
    s += Quad(grey, "-1 0 1.2  -1 2 1.2  1 2 1.2  1 0 1.2");
    s += Quad("Material \"matte\" \"rgb Kd\" [0.63 0.065 0.05]", "-1 0 -1  -1 2 -1  -1 2 1.2  -1 0 1.2");
    s += Quad("Material \"matte\" \"rgb Kd\" [0.14 0.45 0.09]", "1 0 -1  1 0 1.2  1 2 1.2  1 2 -1");
    s += "AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.6 0.6 0.3]\nTranslate 0.4 0.35 -0.3\n"
         "Shape \"sphere\" \"float radius\" [0.35]\nAttributeEnd\n";
    return s;
}

// variance: gradient integrators keep their variance layers (gradus --variance).
inline RenderJob MakeTestJob(const SceneDesc &desc, int spp, uint64_t seed, const std::string &integrator = "",
                             bool variance = false) {
    BuildOptions bo;
    bo.variance = variance;
    bo.sppOverride = spp;
    bo.seed = seed;
    bo.integratorOverride = integrator;
    bo.quiet = true;
    return BuildRenderJob(desc, bo);
}

// Renders a prepared job (nthreads 0 = all cores).
inline TestRender RenderTestJob(RenderJob job, int spp, uint64_t seed, int nthreads = 0) {
    RenderOptions ro;
    ro.spp = spp;
    ro.nthreads = nthreads;
    ro.quiet = true;
    (void)seed;  // the job's sampler carries the seed (MakeTestJob)
    TestRender r;
    RenderResult res = RenderJobImage(job, ro);
    r.stats = res.stats;
    r.image = std::move(res.image);
    r.statistics = job.integrator->statistics();
    r.integrator = std::move(job.integrator);
    return r;
}

inline TestRender RenderTestDesc(const SceneDesc &desc, int spp, uint64_t seed, int nthreads = 0,
                                 const std::string &integrator = "", bool variance = false) {
    return RenderTestJob(MakeTestJob(desc, spp, seed, integrator, variance), spp, seed, nthreads);
}

// Mean luminance of a layer ("" = main image) over [x0,x1) x [y0,y1).
inline double BlockMean(const Image &img, int x0, int y0, int x1, int y1, const std::string &layer = "") {
    Image rgb = layer.empty() ? img : img.layerRGB(layer);
    double sum = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            sum += 0.2126 * rgb.at(x, y, 0) + 0.7152 * rgb.at(x, y, 1) + 0.0722 * rgb.at(x, y, 2);
    return sum / (double(x1 - x0) * (y1 - y0));
}

// Mean and (unbiased) variance of one run, over repeated runs.
struct RunStats {
    double mean = 0, var = 0;
    int n = 0;
};
inline RunStats Stats(const std::vector<double> &v) {
    RunStats s;
    s.n = int(v.size());
    for (double x : v) s.mean += x;
    s.mean /= std::max(1, s.n);
    for (double x : v) s.var += (x - s.mean) * (x - s.mean);
    s.var /= std::max(1, s.n - 1);
    return s;
}

// Welch's t of the means of two sets of independent run values, the first
// scaled by scaleA (a power check scales it by a bias that must be seen).
inline double WelchT(const std::vector<double> &a, const std::vector<double> &b, double scaleA = 1) {
    const RunStats sa = Stats(a), sb = Stats(b);
    return (scaleA * sa.mean - sb.mean) / std::sqrt(scaleA * scaleA * sa.var / sa.n + sb.var / sb.n + 1e-300);
}

// Per-pixel mean of independent renders and the variance of that mean
// (RGB images), for z-tests against a converged reference.
struct MeanOfRuns {
    Image mean, varMean;
};
template <typename RenderFn>  // RenderFn(int run) -> RGB Image
MeanOfRuns AverageRuns(int runs, RenderFn render) {
    MeanOfRuns r;
    Image sum, sum2;
    for (int k = 0; k < runs; ++k) {
        Image img = render(k);
        if (k == 0) {
            sum = Image::RGB(img.width(), img.height());
            sum2 = Image::RGB(img.width(), img.height());
        }
        for (size_t i = 0; i < img.data().size(); ++i) {
            sum.data()[i] += img.data()[i];
            sum2.data()[i] += double(img.data()[i]) * img.data()[i];
        }
    }
    r.mean = Image::RGB(sum.width(), sum.height());
    r.varMean = r.mean;
    for (size_t i = 0; i < sum.data().size(); ++i) {
        double m = sum.data()[i] / runs, m2 = sum2.data()[i] / runs;
        r.mean.data()[i] = float(m);
        r.varMean.data()[i] = float(std::max(0.0, (m2 - m * m) * runs / std::max(1, runs - 1)) / runs);
    }
    return r;
}

// z-scores of a gradient render's dx/dy (with their variance layers) against
// differences of neighbouring pixels of a reference mean, on disjoint pixel
// pairs (even x for dx, even y for dy) so the terms are independent. The
// gradients leave out the separated light (gradient_film.h), which the
// reference's differences include: pairs with a pixel where g's "separated"
// layer is non-zero are not tested (they are counted in `separatedPairs`).
struct GradientZ {
    int n = 0;          // terms tested
    double meanZ2 = 0;  // ~1 when unbiased with correct variances
    double Z = 0;       // sum of z / sqrt(n), ~N(0,1) when unbiased
    int separatedPairs = 0;  // pairs left out: separated light at one of their pixels
};
inline GradientZ GradientZStats(const Image &g, const MeanOfRuns &ref) {
    Image dx = g.layerRGB("dx"), dy = g.layerRGB("dy"), vx = g.layerRGB("dx_var"), vy = g.layerRGB("dy_var");
    const Image &P = ref.mean, &V = ref.varMean;
    const bool hasSep = g.channelIndex("separated.R") >= 0;
    const Image S = hasSep ? g.layerRGB("separated") : Image();
    auto sep = [&](int x, int y) {
        return hasSep && (S.at(x, y, 0) != 0 || S.at(x, y, 1) != 0 || S.at(x, y, 2) != 0);
    };
    double s2 = 0, s = 0;
    int n = 0, skipped = 0;
    auto term = [&](double est, double varEst, double diff, double varDiff) {
        double v = varEst + varDiff;
        if (!(v > 1e-12)) return;  // both exactly zero: nothing to test
        double z = (est - diff) / std::sqrt(v);
        s2 += z * z;
        s += z;
        ++n;
    };
    for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                if (x % 2 == 0 && x + 1 < g.width()) {
                    if (sep(x, y) || sep(x + 1, y))
                        skipped += c == 0;
                    else
                        term(dx.at(x, y, c), vx.at(x, y, c), P.at(x + 1, y, c) - P.at(x, y, c),
                             V.at(x + 1, y, c) + V.at(x, y, c));
                }
                if (y % 2 == 0 && y + 1 < g.height()) {
                    if (sep(x, y) || sep(x, y + 1))
                        skipped += c == 0;
                    else
                        term(dy.at(x, y, c), vy.at(x, y, c), P.at(x, y + 1, c) - P.at(x, y, c),
                             V.at(x, y + 1, c) + V.at(x, y, c));
                }
            }
    GradientZ r;
    r.n = n;
    r.separatedPairs = skipped;
    if (n > 0) {
        r.meanZ2 = s2 / n;
        r.Z = s / std::sqrt(double(n));
    }
    return r;
}

}  // namespace gradus::test
