// G-MLT's shift and gradient integrand (gradient-domain-mlt.md Secs. 4-5)
// without the Markov chains.
//
// Scenes: the conformance table's diffuse box, specular box (mirror and glass:
// eye chains and manifold walks) and outdoor (sky, sun and a point light:
// emitters at infinity keep their direction), and the glossy box (both spheres
// near-specular, treated as specular by the shift: Fig. 5a; the finite
// differences of its Jacobians are in test_near_specular.cpp).
// 1. Reversibility: every successful shift T_d(x) = y shifts back, T_-d(y) = x
//    (same vertices), with |T_-d'(y)| |T_d'(x)| = 1: the bijection behind
//    n(z) = 1/2 (Sec. 4.2.2).
// 2. Jacobian against finite differences: for paths whose primary hit x_1 is
//    non-specular, |T'| is dA(x_1') / dA(x_1) per film area (Eq. 15's special
//    case); the film-to-surface maps are differenced numerically (central
//    differences of camera rays, 1e-3 pixel).
// 3. Unbiased gradient integrand: bidirectional samples (every bdpt strategy,
//    MIS-weighted) estimate, per pixel j, the G-MLT gradient integrand of
//    Eqs. 7, 9 and 10 summed over the four directions, and the image; per
//    sample k and 4 x 4 block of pixels, S_k = sum over the block of
//    [dx_k(j) - (I_k(j + 1) - I_k(j))] (and the same for dy) has mean 0
//    exactly when the integrand is unbiased. Student's t over the iid samples,
//    two-sided, alpha = 1e-3 split over all blocks of all scenes
//    (Bonferroni). Power: the same samples with n = 1 for every shift (the
//    reversible pairs counted twice) and with the Jacobian left out (Fig. 4)
//    must be rejected.
#include <algorithm>
#include <array>
#include <cmath>

#include "conformance/conformance_util.h"
#include "gmlt/gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

// The scenes of the shift tests: the conformance table's three and the
// glossy box with its near-specular spheres treated as specular (Fig. 5a).
struct ShiftScene {
    std::string name, text;
    double threshold;
};
std::vector<ShiftScene> ShiftScenes() {
    std::vector<ShiftScene> v;
    for (const char *s : {"diffuse-box", "specular-box", "outdoor"}) v.push_back({s, ConformanceScene(s), -1});
    v.push_back({"glossy-box", GlossyBox(), kGlossyBoxThreshold});
    return v;
}

TEST(GMLTShift, ReversibleWithReciprocalJacobians) {
    for (const ShiftScene &sc : ShiftScenes()) {
        const std::string &scene = sc.name;
        GMLTSetup g(sc.text, sc.threshold);
        const Float thr = g.gm->gsettings().shiftThreshold;
        const pmlt::Mutator &mut = g.gm->mutator();
        Arena arena, scratch;
        int shifted = 0, chains = 0, oneWay = 0, nearSpecular = 0, nearTwice = 0, illConditioned = 0;
        double worstJ = 0, worstP = 0, worstNearJ = 0, worstNearP = 0;
        ForEachStrategyPath(
            g, 3000, 0x5eed, arena,
            [&](const pmlt::State &x, const Spectrum &) {
                for (int d = 0; d < kNumNeighbours; ++d) {
                    pmlt::State y, z;
                    double J = 0, Jback = 0;
                    if (mut.shift(x, Shifted(x, d), scratch, &y, &J) != ShiftStatus::Shifted) continue;
                    ++shifted;
                    bool specular = false, near = false;
                    int nearRefractions = 0;
                    for (int i = 0; i < x.x.size(); ++i) {
                        const pmlt::ShiftClass c = pmlt::ShiftClassOf(x.x.v[size_t(i)], x.bsdf[size_t(i)], thr);
                        specular |= c != pmlt::ShiftClass::Rough;
                        near |= c == pmlt::ShiftClass::NearSpecular;
                        if (c == pmlt::ShiftClass::NearSpecular) {
                            const PathVertex &v = x.x.v[size_t(i)];
                            const Vec3 ng(v.ng);
                            nearRefractions +=
                                Dot(ng, x.x.v[size_t(i - 1)].p - v.p) * Dot(ng, x.x.v[size_t(i + 1)].p - v.p) < 0;
                        }
                    }
                    chains += specular;
                    nearSpecular += near;
                    const ShiftStatus back = mut.shift(y, Shifted(y, d ^ 1), scratch, &z, &Jback);
                    if (back != ShiftStatus::Shifted) {
                        ++oneWay;
                        continue;
                    }
                    ASSERT_EQ(z.x.size(), x.x.size());
                    double errP = 0;
                    for (int i = 0; i < x.x.size(); ++i) {
                        const Vec3 e = z.x.v[size_t(i)].p - x.x.v[size_t(i)].p;
                        const Float scale = std::max<Float>(1, (x.x.v[size_t(i)].p - x.x.v[0].p).length());
                        errP = std::max(errP, double(e.length() / scale));
                    }
                    const double errJ = std::abs(J * Jback - 1);
                    // Refracted twice or more by the rough sphere: may be ill-conditioned (below).
                    const bool twice = nearRefractions >= 2;
                    (twice ? worstNearP : worstP) = std::max(twice ? worstNearP : worstP, errP);
                    (twice ? worstNearJ : worstJ) = std::max(twice ? worstNearJ : worstJ, errJ);
                    nearTwice += twice;
                    illConditioned += twice && (errP > 1e-4 || errJ > 1e-3);
                }
                scratch.reset();
            },
            [](int) {});
        std::cout << "[ shift ] " << scene << ": " << shifted << " shifts (" << chains
                  << " through specular vertices), " << oneWay << " not shifting back; back-shift vertex error "
                  << worstP << ", |J J' - 1| " << worstJ << "\n";
        if (nearSpecular > 0)
            std::cout << "[ shift ] " << scene << ": " << nearSpecular << " through near-specular vertices, "
                      << nearTwice << " refracted by them twice or more, " << illConditioned
                      << " of these with a vertex error > 1e-4 or |J J' - 1| > 1e-3 (largest " << worstNearP << ", "
                      << worstNearJ << ")\n";
        // A re-traced vertex differs from the original by float rounding, so a
        // shadow ray grazing an occluder's edge can decide differently: rare
        // (measured: 2 in 96 000 on specular-box, 0 on diffuse-box).
        EXPECT_LE(oneWay, shifted / 10000) << scene << ": shifts that do not shift back";
        EXPECT_GT(shifted, 1000) << scene;
        if (scene == "specular-box" || scene == "glossy-box") {
            EXPECT_GT(chains, 50) << scene << ": too few shifts through specular chains";
        }
        EXPECT_LT(worstP, 1e-3) << scene;
        EXPECT_LT(worstJ, 1e-3) << scene;
        // Copied half vectors come from the vertices, whose positions are
        // rounded; a chain refracted twice or more by the rough glass sphere
        // can pass near its critical angle, where the way back magnifies that
        // (measured: vertex errors of 1e-12 grow to 4e-6 over one refraction,
        // |J J' - 1| up to 0.97 where J ~ 1e-5). Such trips are rare (measured:
        // 14 of 4080 twice-refracted shifts of 97 000); every other shift is
        // held to the bounds above.
        if (scene == "glossy-box") {
            EXPECT_GT(nearSpecular, 5000) << scene;
            EXPECT_GT(nearTwice, 500) << scene;
        }
        EXPECT_LE(illConditioned, nearTwice / 100) << scene << ": twice-refracted shifts that do not shift back closely";
    }
}

// The shift evaluates its offset on the changed prefix only (EvaluateChangedPrefix:
// the factors of x_0 .. x_{last+1} on y, the rest from x's evaluation): F,
// I, the film position and the camera side's densities up to the last moved
// vertex must equal a full Evaluate of the offset (factors multiplied in
// another order: rounding only). A stale factor (one not recomputed where
// the shift moved a neighbour) changes F by far more than the bound.
TEST(GMLTShift, ChangedPrefixEvaluationMatchesFullEvaluation) {
    for (const ShiftScene &sc : ShiftScenes()) {
        GMLTSetup g(sc.text, sc.threshold);
        const Float thr = g.gm->gsettings().shiftThreshold;
        const pmlt::Mutator &mut = g.gm->mutator();
        Arena arena, scratch;
        int shifted = 0, chains = 0, prefixes = 0;
        double worstF = 0, worstP = 0;
        ForEachStrategyPath(
            g, 1500, 0xfeed, arena,
            [&](const pmlt::State &x, const Spectrum &) {
                for (int d = 0; d < kNumNeighbours; ++d) {
                    pmlt::State y;
                    double J = 0;
                    if (mut.shift(x, Shifted(x, d), scratch, &y, &J) != ShiftStatus::Shifted) continue;
                    ++shifted;
                    pmlt::PathEval full;
                    ASSERT_TRUE(pmlt::Evaluate(g.ctx(), g.gm->filmDomain(), y.x, y.bsdf.data(), &full)) << sc.name;
                    ASSERT_TRUE(full.complete);
                    prefixes += !y.e.complete;  // x was evaluated in full: the prefix path was taken
                    for (const auto &[a, ref] : {std::pair{y.e.F.r, full.F.r}, std::pair{y.e.F.g, full.F.g},
                                                 std::pair{y.e.F.b, full.F.b}})
                        worstF = std::max(worstF, std::abs(double(a - ref)) / std::max(std::abs(double(ref)), 1e-300));
                    EXPECT_EQ(y.e.pRaster.x, full.pRaster.x);
                    EXPECT_EQ(y.e.pRaster.y, full.pRaster.y);
                    // The eye chain x_1 .. x_b (the shift's specular classes), and whether a
                    // second chain follows (the manifold branch: moved up to x_{c-1}).
                    const int n = x.x.size();
                    auto specular = [&](int i) {
                        return pmlt::ShiftClassOf(x.x.v[size_t(i)], x.bsdf[size_t(i)], thr) != pmlt::ShiftClass::Rough;
                    };
                    int b = 1;
                    while (b < n - 1 && specular(b)) ++b;
                    chains += b < n - 1 && specular(b + 1);
                    for (int i = 0; i <= b; ++i) {
                        worstP = std::max(worstP, std::abs(double(y.e.pE[size_t(i)]) / double(full.pE[size_t(i)]) - 1));
                        EXPECT_EQ(y.e.lobeE[size_t(i)], full.lobeE[size_t(i)]) << sc.name << " vertex " << i;
                    }
                }
                scratch.reset();
            },
            [](int) {});
        std::cout << "[ prefix ] " << sc.name << ": " << shifted << " shifts (" << prefixes
                  << " evaluated on the changed prefix, " << chains
                  << " with a second chain), largest relative difference of F " << worstF
                  << ", of the eye densities " << worstP << "\n";
        EXPECT_GT(shifted, 500) << sc.name;
        EXPECT_EQ(prefixes, shifted) << sc.name;
        EXPECT_LT(worstF, 1e-9) << sc.name;
        EXPECT_LT(worstP, 1e-12) << sc.name;
        if (sc.name == "specular-box" || sc.name == "glossy-box") {
            EXPECT_GT(chains, 50) << sc.name << ": too few shifts through second chains";
        }
    }
}

// First hit of the camera ray from lens point o through film point s.
bool PrimaryHit(const BidirContext &ctx, const Point3 &o, Point2 s, Point3 *p) {
    Ray ray;
    if (!ctx.camera->rayThrough(o, s, &ray)) return false;
    SurfaceInteraction si;
    if (ctx.scene->intersectSurface(&ray, &si) != Scene::SurfaceHit::Hit) return false;
    *p = si.p;
    return true;
}

// dA(x_1) / ds by central differences.
double AreaPerFilm(const BidirContext &ctx, const Point3 &o, Point2 s, double eps) {
    Point3 px0, px1, py0, py1;
    if (!PrimaryHit(ctx, o, Point2(s.x - eps, s.y), &px0) || !PrimaryHit(ctx, o, Point2(s.x + eps, s.y), &px1) ||
        !PrimaryHit(ctx, o, Point2(s.x, s.y - eps), &py0) || !PrimaryHit(ctx, o, Point2(s.x, s.y + eps), &py1))
        return -1;
    return Cross(px1 - px0, py1 - py0).length() / (4 * eps * eps);
}

TEST(GMLTShift, JacobianMatchesFiniteDifferences) {
    GMLTSetup g(ConformanceScene("diffuse-box"));
    const pmlt::Mutator &mut = g.gm->mutator();
    Arena arena, scratch;
    int checked = 0;
    double worst = 0, spread = 0;
    ForEachStrategyPath(
        g, 1500, 0xfd, arena,
        [&](const pmlt::State &x, const Spectrum &) {
            if (x.x.v[1].delta()) return;
            for (int d = 0; d < kNumNeighbours; ++d) {
                pmlt::State y;
                double J = 0;
                if (mut.shift(x, Shifted(x, d), scratch, &y, &J) != ShiftStatus::Shifted) continue;
                // Stay away from edges of surfaces (the differences straddle them).
                const double ax = AreaPerFilm(g.ctx(), x.x.v[0].p, x.e.pRaster, 1e-3);
                const double ay = AreaPerFilm(g.ctx(), x.x.v[0].p, Shifted(x, d), 1e-3);
                const double ax2 = AreaPerFilm(g.ctx(), x.x.v[0].p, x.e.pRaster, 2e-3);
                const double ay2 = AreaPerFilm(g.ctx(), x.x.v[0].p, Shifted(x, d), 2e-3);
                if (!(ax > 0 && ay > 0) || std::abs(ax2 / ax - 1) > 1e-3 || std::abs(ay2 / ay - 1) > 1e-3) continue;
                ++checked;
                worst = std::max(worst, std::abs(J / (ay / ax) - 1));
                spread = std::max(spread, std::abs(J - 1));
            }
            scratch.reset();
        },
        [](int) {});
    std::cout << "[ jacobian ] " << checked << " shifts of non-specular primary hits: largest |J / J_fd - 1| " << worst
              << " (largest |J - 1| " << spread << ")\n";
    EXPECT_GT(checked, 500);
    EXPECT_LT(worst, 2e-3);
    EXPECT_GT(spread, 20 * worst) << "the Jacobians differ too little from 1 for the comparison to mean anything";
}

// Per-sample block sums of the gradient integrand minus the image's differences.
struct BlockStats {
    static constexpr int kVariants = 3;  // as specified; n = 1 always; no Jacobian
    // [variant][axis][block]: sums and sums of squares over samples.
    std::vector<double> s1[kVariants][2], s2[kVariants][2];
};

TEST(GMLTGradient, IntegrandIsUnbiased) {
    const std::vector<ShiftScene> cases = ShiftScenes();
    const int samples = 60000;
    const size_t nc = cases.size();
    std::vector<std::array<double, BlockStats::kVariants>> margins(nc);
    std::vector<std::array<std::string, BlockStats::kVariants>> worst(nc);
    int totalBlocks = 0;
    std::vector<BlockStats> stats;
    std::vector<int> blocksPerScene;
    for (const ShiftScene &c : cases) {
        GMLTSetup g(c.text, c.threshold);
        const int W = g.film().pixels.width(), H = g.film().pixels.height();
        const int bw = W / 4, bh = H / 4, nb = bw * bh;
        BlockStats bs;
        for (int v = 0; v < BlockStats::kVariants; ++v)
            for (int a = 0; a < 2; ++a) bs.s1[v][a].assign(size_t(nb), 0), bs.s2[v][a].assign(size_t(nb), 0);
        // This sample's images: primal and, per variant, dx and dy (luminance).
        std::vector<double> P(size_t(W * H)), D[BlockStats::kVariants][2];
        for (auto &dv : D)
            for (auto &da : dv) da.assign(size_t(W * H), 0);
        Arena arena, scratch;
        auto inside = [&](int x, int y) { return x >= 0 && y >= 0 && x < W && y < H; };
        ForEachStrategyPath(
            g, samples, 0x9d17, arena,
            [&](const pmlt::State &x, const Spectrum &C) {
                const int px = int(std::floor(x.e.pRaster.x)), py = int(std::floor(x.e.pRaster.y));
                if (!inside(px, py)) return;
                P[size_t(py * W + px)] += C.y();
                const double w = C.y() / double(x.e.I);  // MIS weight / density of x
                for (int d = 0; d < kNumNeighbours; ++d) {
                    const GMLTIntegrator::Target t = g.gm->evaluate(x, d, scratch);
                    const Spectrum raw[BlockStats::kVariants] = {
                        t.diff, t.offset - x.e.F,
                        (t.jacobian > 0 ? t.offset * Float(1 / t.jacobian) : Spectrum(0)) * t.n - x.e.F * t.n};
                    // Eq. 10: +d at the base's pixel; -d at the neighbour, sign flipped.
                    const Point2i off = kNeighbourOffsets[d];
                    const bool forward = off.x + off.y > 0;
                    const int qx = forward ? px : px + off.x, qy = forward ? py : py + off.y;
                    if (!inside(qx, qy)) continue;
                    for (int v = 0; v < BlockStats::kVariants; ++v)
                        D[v][off.x != 0 ? 0 : 1][size_t(qy * W + qx)] += (forward ? 1 : -1) * w * raw[v].y();
                }
                scratch.reset();
            },
            [&](int) {
                for (int v = 0; v < BlockStats::kVariants; ++v)
                    for (int a = 0; a < 2; ++a) {
                        std::vector<double> blockSum(size_t(nb), 0);
                        for (int y = 0; y < H; ++y)
                            for (int x = 0; x < W; ++x) {
                                const int nx = x + (a == 0), ny = y + (a == 1);
                                if (!inside(nx, ny)) continue;
                                const double diff = D[v][a][size_t(y * W + x)] -
                                                    (P[size_t(ny * W + nx)] - P[size_t(y * W + x)]);
                                blockSum[size_t(std::min(y / 4, bh - 1) * bw + std::min(x / 4, bw - 1))] += diff;
                            }
                        for (int b = 0; b < nb; ++b) {
                            bs.s1[v][a][size_t(b)] += blockSum[size_t(b)];
                            bs.s2[v][a][size_t(b)] += blockSum[size_t(b)] * blockSum[size_t(b)];
                        }
                    }
                std::fill(P.begin(), P.end(), 0);
                for (auto &dv : D)
                    for (auto &da : dv) std::fill(da.begin(), da.end(), 0);
            });
        totalBlocks += 2 * nb;
        blocksPerScene.push_back(nb);
        stats.push_back(std::move(bs));
    }
    const double alpha = 1e-3 / totalBlocks;
    for (size_t i = 0; i < stats.size(); ++i) {
        const double n = samples;
        for (int v = 0; v < BlockStats::kVariants; ++v)
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < blocksPerScene[i]; ++b) {
                    const double mean = stats[i].s1[v][a][size_t(b)] / n;
                    const double var = (stats[i].s2[v][a][size_t(b)] - n * mean * mean) / (n - 1);
                    if (!(var > 0)) continue;
                    const double t = mean / std::sqrt(var / n);
                    const double m = std::abs(t) / conformance::StudentCritical(alpha, n - 1);
                    if (m > margins[i][v]) {
                        margins[i][v] = m;
                        worst[i][v] = std::string(a == 0 ? "dx" : "dy") + " block " + std::to_string(b) + ", t " +
                                      std::to_string(t);
                    }
                }
        std::cout << "[ gradient ] " << cases[i].name << ": largest |t|/critical " << margins[i][0] << " ("
                  << worst[i][0] << "); n = 1 always: " << margins[i][1] << " (" << worst[i][1]
                  << "); without the Jacobian: " << margins[i][2] << " (" << worst[i][2] << ")\n";
        EXPECT_LE(margins[i][0], 1) << cases[i].name << ": gradient integrand biased, " << worst[i][0];
    }
    // Power: both wrong integrands are detected (on at least one scene each).
    for (int v : {1, 2}) {
        double m = 0;
        for (size_t i = 0; i < nc; ++i) m = std::max(m, margins[i][size_t(v)]);
        EXPECT_GT(m, 1)
            << (v == 1 ? "n(z) = 1 for reversible shifts" : "a missing Jacobian") << " not detected";
    }
}

}  // namespace
}  // namespace gradus::pmlt_test
