// The MLT agreement tests (pbrt-v4 #525: the converged mean must not depend on
// the seed or the bootstrap size; and mlt agrees with bdpt in expectation).
//
// Design. Three groups of K independent in-memory renders of the 12x12 box
// scene (mlt_test_util.h), maxdepth 3, S samples (mutations) per pixel each:
//   small: mlt, bootstrapsamples 200 per depth (800 states), seeds 1..K
//   large: mlt, bootstrapsamples 5000 per depth, seeds 10001..10000+K
//   capped: mlt, bootstrapsamples 5000 and bootstrapvertices 4000: N_d = 500,
//          333, 250, 200 states at depths 0..3 (unequal: b and the chain starts
//          weight state (d, k) by 1 / N_d), seeds 30001..30000+K
//   mis:   mlt, bootstrapsamples 5000 and largestepmis (consistent: bias
//          O(1 / bootstrap size), far below the test's resolution), seeds 40001..
//   bdpt:  bdpt at S spp, seeds 20001..20000+K
// Each run is reduced to 10 pixel-set mean luminances (the whole image and
// 3x3 blocks of 4x4 pixels). Welch's t of small vs large, small vs bdpt,
// large vs bdpt, capped vs bdpt and mis vs bdpt on every set (exact Student
// tail), at alpha = 1e-4 per test split over the 5 x 10 statistics
// (Bonferroni: false-positive rate <= 1e-4 for any correlation between them).
// Power check on the same data: the small, large, capped and mis runs scaled by 1.05 must be
// rejected against bdpt (the global set alone has the power: it is b, whose
// relative error over K runs is well under 5% / critical t).
#pragma once
#include <functional>
#include <sstream>

#include "conformance/conformance_util.h"
#include "mlt_test_util.h"

namespace gradus::mlt_test {

inline std::vector<double> Reduce(const Image &img) {
    std::vector<double> v = {MeanLum(img)};
    for (int by = 0; by < 3; ++by)
        for (int bx = 0; bx < 3; ++bx) v.push_back(MeanLum(img, 4 * bx, 4 * by, 4 * bx + 4, 4 * by + 4));
    return v;
}

struct Comparison {
    double maxMargin = 0;  // max |t| / critical |t| over the sets: rejects iff > 1
    std::string describe;
};

inline Comparison Compare(const std::vector<std::vector<double>> &a, const std::vector<std::vector<double>> &b,
                          double scaleA, double alpha) {
    using conformance::WelchTest;
    Comparison c;
    std::ostringstream o;
    for (size_t i = 0; i < a[0].size(); ++i) {
        std::vector<double> x, y;
        for (const auto &r : a) x.push_back(r[i] * scaleA);
        for (const auto &r : b) y.push_back(r[i]);
        conformance::Welch w = WelchTest(x, y);
        double margin = std::abs(w.t) / conformance::StudentCritical(alpha, w.dof);
        if (i == 0) o << "global " << w.meanA << " +- " << w.seA << " vs " << w.meanB << " +- " << w.seB << ";";
        o << " t" << i << " " << w.t;
        c.maxMargin = std::max(c.maxMargin, margin);
    }
    c.describe = o.str();
    return c;
}

inline void ExpectAgreement(int K, int S) {
    const int maxDepth = 3;
    auto mltScene = [&](int bootstrap, const std::string &extra) {
        return BoxScene(MLTLine("\"integer maxdepth\" [" + std::to_string(maxDepth) +
                                "] \"integer chains\" [32] \"integer bootstrapsamples\" [" +
                                std::to_string(bootstrap) + "]" + extra));
    };
    const std::string small = mltScene(200, ""), large = mltScene(5000, ""),
                      capped = mltScene(5000, " \"integer bootstrapvertices\" [4000]"),
                      mis = mltScene(5000, " \"bool largestepmis\" [true]"),
                      bdpt = BoxScene("Integrator \"bdpt\" \"integer maxdepth\" [" + std::to_string(maxDepth) + "]");
    std::vector<std::vector<double>> rs, rl, rc, rm, rb;
    for (int k = 0; k < K; ++k) {
        rs.push_back(Reduce(Render(small, S, uint64_t(1 + k)).image));
        rl.push_back(Reduce(Render(large, S, uint64_t(10001 + k)).image));
        rc.push_back(Reduce(Render(capped, S, uint64_t(30001 + k)).image));
        rm.push_back(Reduce(Render(mis, S, uint64_t(40001 + k)).image));
        rb.push_back(Reduce(Render(bdpt, S, uint64_t(20001 + k)).image));
    }
    const double alpha = 1e-4 / 50;
    const Comparison sl = Compare(rs, rl, 1, alpha), sb = Compare(rs, rb, 1, alpha), lb = Compare(rl, rb, 1, alpha),
                     cb = Compare(rc, rb, 1, alpha), mb = Compare(rm, rb, 1, alpha);
    std::cout << "[ mlt ] K " << K << ", " << S << " spp: |t|/crit small-large " << sl.maxMargin << ", small-bdpt "
              << sb.maxMargin << ", large-bdpt " << lb.maxMargin << ", capped-bdpt " << cb.maxMargin << ", mis-bdpt "
              << mb.maxMargin << "\n";
    EXPECT_LE(sl.maxMargin, 1) << "bootstrap size changes the mean: " << sl.describe;
    EXPECT_LE(sb.maxMargin, 1) << "mlt (bootstrap 200) differs from bdpt: " << sb.describe;
    EXPECT_LE(lb.maxMargin, 1) << "mlt (bootstrap 5000) differs from bdpt: " << lb.describe;
    EXPECT_LE(cb.maxMargin, 1) << "mlt (bootstrap capped by bootstrapvertices) differs from bdpt: " << cb.describe;
    EXPECT_LE(mb.maxMargin, 1) << "mlt (largestepmis) differs from bdpt: " << mb.describe;
    for (double scale : {1.05, 1 / 1.05}) {
        const Comparison ps = Compare(rs, rb, scale, alpha), pl = Compare(rl, rb, scale, alpha),
                         pc = Compare(rc, rb, scale, alpha), pm = Compare(rm, rb, scale, alpha);
        std::cout << "[ mlt ] power x" << scale << ": small-bdpt " << ps.maxMargin << ", large-bdpt " << pl.maxMargin
                  << ", capped-bdpt " << pc.maxMargin << ", mis-bdpt " << pm.maxMargin << "\n";
        EXPECT_GT(ps.maxMargin, 1) << "power check: a " << scale << " bias of the small-bootstrap runs is not detected";
        EXPECT_GT(pl.maxMargin, 1) << "power check: a " << scale << " bias of the large-bootstrap runs is not detected";
        EXPECT_GT(pc.maxMargin, 1) << "power check: a " << scale << " bias of the capped-bootstrap runs is not detected";
        EXPECT_GT(pm.maxMargin, 1) << "power check: a " << scale << " bias of the largestepmis runs is not detected";
    }
}

}  // namespace gradus::mlt_test
