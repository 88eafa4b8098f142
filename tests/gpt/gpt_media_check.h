// Agreement of G-PT with participating media and path (an independent
// estimator of the same image), shared by the media tests of gpt.
//
// CheckAgainstPath: K runs of gpt and 2K of path (disjoint fixed seeds, 2
// threads: images do not depend on the thread count), each reduced to the
// mean luminance of the image and of six blocks (3 x 2):
//  - gpt's primal and its reconstruction (the unprefixed image, hybrid) vs
//    path by Welch's t per set; false positives alpha = 1e-4 per scene,
//    Bonferroni over 2 x 7 sets. Power: gpt's runs scaled to a mean
//    powerBias above and below path's are rejected (image mean).
//  - gradients: per pixel pair (disjoint pairs: even x for dx, even y for dy)
//    z = (mean dx - (P(x+1) - P(x))) / sqrt(var), the variances of the means
//    estimated from the runs. Unbiased: S = mean z^2 ~ 1 (t-tails of 15 and 31
//    dof make it ~1.1) and Z = sum z / sqrt(n) ~ N(0, ~1.1); thresholds
//    S < 1.6 and |Z| < 4.5 (Gaussian false-positive rates < 1e-9 and 1e-5).
//    Power: gradients biased by 2% of the pair's mean pixel value are rejected.
//    Pairs with separated light (emitters seen through Dirac chains) are left
//    out, as in tests/common/render_test_util.h's GradientZStats.
#pragma once
#include <gtest/gtest.h>

#include <cmath>

#include "common/render_test_util.h"
#include "conformance/conformance_util.h"
#include "gpt_media_util.h"

namespace gradus::gptmedia {

using conformance::StudentCritical;
using conformance::Welch;
using conformance::WelchTest;

constexpr int kSets = 7;

// Image mean and six blocks (3 x 2).
inline void Reduce(const Image &img, const std::string &layer, std::vector<double> sets[kSets]) {
    const int W = img.width(), H = img.height(), bw = W / 3, bh = H / 2;
    sets[0].push_back(test::BlockMean(img, 0, 0, W, H, layer));
    for (int b = 0; b < 6; ++b) {
        const int x0 = (b % 3) * bw, y0 = (b / 3) * bh;
        sets[1 + b].push_back(test::BlockMean(img, x0, y0, x0 + bw, y0 + bh, layer));
    }
}

struct Moments {
    std::vector<double> sum, sum2;
    int n = 0;
    void add(const Image &rgb) {
        if (sum.empty()) sum.assign(rgb.data().size(), 0), sum2.assign(rgb.data().size(), 0);
        for (size_t i = 0; i < rgb.data().size(); ++i) {
            sum[i] += rgb.data()[i];
            sum2[i] += double(rgb.data()[i]) * rgb.data()[i];
        }
        ++n;
    }
    double mean(size_t i) const { return sum[i] / n; }
    double varMean(size_t i) const {
        const double m = mean(i);
        return std::max(0.0, (sum2[i] / n - m * m) * n / (n - 1)) / n;
    }
};

// `grad` against `ref` (gbdpt's media tests: gbdpt against bdpt).
inline void CheckAgainstPath(const std::string &name, const std::string &text, int K, int spp, int minTerms,
                             double powerBias = 0.02, const char *grad = "gpt", const char *ref = "path",
                             bool l1l2 = false) {
    ASSERT_FALSE(text.empty());
    const SceneDesc desc = ParseString(text, name + ".pbrt", ".");
    // l1l2: also the L1 and L2 reconstructions (layers reconstructed_l1, _l2).
    std::vector<double> path[kSets], primal[kSets], recon[kSets], rl1[kSets], rl2[kSets];
    Moments P, DX, DY, SEP;
    int W = 0, H = 0;
    for (int k = 0; k < 2 * K; ++k) {
        const Image img = test::RenderTestDesc(desc, spp, 4000 + k, 2, ref).image;
        Reduce(img, "", path);
        P.add(img.layerRGB(""));
        W = img.width();
        H = img.height();
    }
    for (int k = 0; k < K; ++k) {
        const Image img = test::RenderTestDesc(desc, spp, 1000 + k, 2, grad).image;
        Reduce(img, "primal", primal);
        Reduce(img, "", recon);
        if (l1l2) {
            Reduce(img, "reconstructed_l1", rl1);
            Reduce(img, "reconstructed_l2", rl2);
        }
        DX.add(img.layerRGB("dx"));
        DY.add(img.layerRGB("dy"));
        SEP.add(img.layerRGB("separated"));
    }
    const int nWhich = l1l2 ? 4 : 2;
    const double alpha = 1e-4 / (nWhich * kSets);
    for (int which = 0; which < nWhich; ++which) {
        std::vector<double> *x = which == 0 ? primal : which == 1 ? recon : which == 2 ? rl1 : rl2;
        const char *what = which == 0 ? "primal" : which == 1 ? "reconstruction" : which == 2 ? "L1" : "L2";
        for (int set = 0; set < kSets; ++set) {
            const Welch w = WelchTest(x[set], path[set]);
            const double crit = StudentCritical(alpha, w.dof);
            if (set == 0)
                std::printf("[ %s ] %s %s vs %s, image mean: %.6f +- %.6f vs %.6f +- %.6f, t %.2f (critical %.2f)\n",
                            name.c_str(), grad, what, ref, w.meanA, w.seA, w.meanB, w.seB, w.t, crit);
            EXPECT_LT(std::abs(w.t), crit) << name << ": " << grad << " " << what << " vs " << ref << ", set " << set;
            if (set != 0) continue;
            for (double bias : {1 + powerBias, 1 / (1 + powerBias)}) {
                std::vector<double> scaled = x[0];
                for (double &v : scaled) v *= bias * w.meanB / w.meanA;
                const Welch ws = WelchTest(scaled, path[0]);
                std::printf("    power: x%.4f gives t %.2f\n", bias, ws.t);
                EXPECT_GT(std::abs(ws.t), StudentCritical(alpha, ws.dof))
                    << name << ": power check, " << what << " biased by x" << bias << " not detected";
            }
        }
    }
    // Gradients against path's neighbour differences; `bias` plants an error of
    // that fraction of the pair's mean value (power check).
    auto gradientZ = [&](double bias, double *S, double *Z) {
        double s = 0, s2 = 0;
        int n = 0;
        for (int y = 0; y < H; ++y)
            for (int xx = 0; xx < W; ++xx)
                for (int c = 0; c < 3; ++c) {
                    const size_t i = (size_t(y) * W + xx) * 3 + c;
                    auto term = [&](const Moments &D, size_t j) {
                        // The gradients leave out the separated light (gradient_film.h), which
                        // path's differences include: such pairs are not tested.
                        for (size_t q : {i - c, j - c})
                            for (int cc = 0; cc < 3; ++cc)
                                if (SEP.sum[q + cc] != 0) return;
                        const double d = P.mean(j) - P.mean(i);
                        const double v = D.varMean(i) + P.varMean(i) + P.varMean(j);
                        if (!(v > 1e-12)) return;
                        const double est = D.mean(i) + bias * 0.5 * (P.mean(i) + P.mean(j));
                        const double z = (est - d) / std::sqrt(v);
                        s += z;
                        s2 += z * z;
                        ++n;
                    };
                    if (xx % 2 == 0 && xx + 1 < W) term(DX, i + 3);
                    if (y % 2 == 0 && y + 1 < H) term(DY, i + size_t(W) * 3);
                }
        *S = s2 / n;
        *Z = s / std::sqrt(double(n));
        return n;
    };
    double S, Z;
    const int n = gradientZ(0, &S, &Z);
    std::printf("[ %s ] gradients: %d terms, mean z^2 %.3f, Z %.2f\n", name.c_str(), n, S, Z);
    EXPECT_GT(n, minTerms);
    EXPECT_LT(S, 1.6) << name << ": gradients vs path differences";
    EXPECT_LT(std::abs(Z), 4.5) << name << ": gradients vs path differences";
    for (double bias : {0.02, -0.02}) {
        double Sb, Zb;
        gradientZ(bias, &Sb, &Zb);
        std::printf("    gradient power: bias %+.2f gives mean z^2 %.3f, Z %.2f\n", bias, Sb, Zb);
        EXPECT_TRUE(Sb >= 1.6 || std::abs(Zb) >= 4.5) << name << ": a gradient bias of " << bias << " not detected";
    }
}

}  // namespace gradus::gptmedia
