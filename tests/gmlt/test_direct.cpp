// directsamples (pmlt and gmlt): the direct pass (paths of at most one
// scattering vertex; gmlt: G-PT at maxdepth 1 with its gradients, added
// before the reconstruction) plus the chains (the longer paths) estimates the
// same image as the chains alone.
//
// Statistic: K renders of each setting, each reduced to its image mean and
// 4 block means of 12 x 12 pixels (gmlt: of its primal, dx and dy, and of
// its L2 reconstruction); Welch's t per statistic, alpha = 1e-3 over
// all statistics of the test (Bonferroni): the false-positive rate of the
// whole test is at most 1e-3 (Welch's t is near-exact for these means of
// many mutations). Power: the runs with the direct pass, scaled by 1.05 or
// 1 / 1.05 as a whole, must be rejected (a 5% bias anywhere is resolved).
#include <algorithm>
#include <iostream>

#include "gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

using mlt_test::Compare;
using mlt_test::Comparison;
using mlt_test::Render;

// The conformance table's specular box (24 x 24, glass and metal spheres, a
// mirror, the ceiling light in view: G-PT's separated light).
std::string Box(const std::string &integrator) {
    return WithIntegrator(ConformanceScene("specular-box"), integrator);
}

std::vector<double> Reduce(const Image &img) {
    std::vector<double> v = {mlt_test::MeanLum(img)};
    for (int y = 0; y + 12 <= img.height(); y += 12)
        for (int x = 0; x + 12 <= img.width(); x += 12) v.push_back(mlt_test::MeanLum(img, x, y, x + 12, y + 12));
    return v;
}

// gmlt: what the reconstruction sees, the primal, dx and dy (signed block
// means: a gradient summed over a block is the difference of the image along
// its sides). The last column's dx and the last row's dy (pairs that leave the
// film, which the reconstruction does not use) are left out: there the chains
// splat -F of shifts off the film, G-PT nothing. Separated light (the emitter
// seen directly or through Dirac vertices) takes no gradients, and the direct
// pass separates more of it (G-PT's paths of one scattering vertex) than the
// chains alone: its differences are added back to dx and dy of both.
std::vector<double> Layers(const Image &img) {
    std::vector<double> v;
    const std::vector<std::string> names = img.layers();
    const bool sep = std::find(names.begin(), names.end(), "separated") != names.end();
    const Image s = sep ? img.layerRGB("separated") : Image();
    for (const char *layer : {"primal", "dx", "dy"}) {
        Image im = img.layerRGB(layer);
        const bool dx = layer == std::string("dx"), dy = layer == std::string("dy");
        for (int y = 0; y < im.height(); ++y)
            for (int x = 0; x < im.width(); ++x)
                for (int c = 0; c < 3; ++c) {
                    if ((dx && x == im.width() - 1) || (dy && y == im.height() - 1))
                        im.at(x, y, c) = 0;
                    else if (sep && dx)
                        im.at(x, y, c) += s.at(x + 1, y, c) - s.at(x, y, c);
                    else if (sep && dy)
                        im.at(x, y, c) += s.at(x, y + 1, c) - s.at(x, y, c);
                }
        const std::vector<double> r = Reduce(im);
        v.insert(v.end(), r.begin(), r.end());
    }
    return v;
}

void ExpectSame(const std::string &name, const std::vector<std::vector<double>> &withDirect,
                const std::vector<std::vector<double>> &chainsOnly, double alpha) {
    const Comparison c = Compare(withDirect, chainsOnly, 1, alpha);
    std::cout << "[ directsamples ] " << name << ": |t|/crit " << c.maxMargin << " ("
              << c.describe.substr(0, c.describe.find(';')) << ")\n";
    EXPECT_LE(c.maxMargin, 1) << name << ": " << c.describe;
    for (double scale : {1.05, 1 / 1.05}) {
        const Comparison p = Compare(withDirect, chainsOnly, scale, alpha);
        std::cout << "[ directsamples ] " << name << " power x" << scale << ": " << p.maxMargin << "\n";
        EXPECT_GT(p.maxMargin, 1) << name << ": a " << scale << " bias is not detected";
    }
}

TEST(MetropolisDirectSamples, DirectPassPlusChainsEqualsChainsAlone) {
    const int K = 24, S = 32;
    const std::string common = "\"integer maxdepth\" [5] \"integer bootstrapsamples\" [20000] \"integer chains\" [64]";
    // gmlt with alpha 4: f ~ |f*| + I keeps the coarse primal's noise in the
    // means low enough to resolve 5% at this budget (alpha 0.2: ~2.3% sd).
    const std::string gcommon = common + " \"float alpha\" [4]";
    std::vector<std::vector<double>> p0, p1, g0, g1, l0, l1;
    for (int k = 0; k < K; ++k) {
        const uint64_t seed = uint64_t(81001 + k);
        p0.push_back(Reduce(Render(Box("Integrator \"pmlt\" " + common), S, seed).image));
        p1.push_back(Reduce(Render(Box("Integrator \"pmlt\" \"integer directsamples\" [4] " + common), S, seed + 100).image));
        const Image a = Render(Box("Integrator \"gmlt\" " + gcommon), S, seed + 200).image;
        const Image b = Render(Box("Integrator \"gmlt\" \"integer directsamples\" [4] " + gcommon), S, seed + 300).image;
        g0.push_back(Layers(a));
        g1.push_back(Layers(b));
        l0.push_back(Reduce(a.layerRGB("reconstructed_l2")));
        l1.push_back(Reduce(b.layerRGB("reconstructed_l2")));
    }
    const double alpha = 1e-3 / double(p0[0].size() + g0[0].size() + l0[0].size());
    ExpectSame("pmlt", p1, p0, alpha);
    ExpectSame("gmlt primal, dx, dy", g1, g0, alpha);
    ExpectSame("gmlt reconstructed_l2", l1, l0, alpha);
}

}  // namespace
}  // namespace gradus::pmlt_test
