// Property tests of the shared bidirectional core on random paths:
//  - the MIS weights of all evaluated strategies of a path sum to one
//    (balance and power heuristics, with delta vertices and an infinite light);
//  - the pdfs a connection evaluates in the reverse direction equal the
//    forward pdfs the opposite random walk produces (and an independent
//    evaluation from the BSDF and the geometry). Tolerance 3e-3 relative: the
//    walk samples directions from the ray, the connection code recomputes them
//    from hit points refined from float barycentrics (angular error ~1e-5 on
//    short edges, amplified by glossy lobes).
//  - with participating media (medium vertices on both subpaths, interfaces
//    without a material, a glass sphere that changes the medium) the weights
//    still sum to one, with and without merging (merges on surfaces only).
#include <gtest/gtest.h>

#include "bdpt_test_util.h"
#include "integrators/common/bidir.h"
#include "lights/light_sampler.h"
#include "media/medium.h"

namespace gradus::bdpt_test {
namespace {

struct Fixture {
    RenderJob job;
    LightSampler ls;
    BidirContext ctx;
    std::unique_ptr<Sampler> sampler;
    RNG rng;  // media (Generate reseeds it per path)
    explicit Fixture(const std::string &text, MISHeuristic h = MISHeuristic::Balance) {
        BuildOptions bo;
        bo.quiet = true;
        job = BuildRenderJob(ParseString(text), bo);
        ls = LightSampler(job.scene->lights, "power", FileLoc());
        ctx.init(*job.scene, ls, h);
        sampler = job.sampler->clone();
    }
};

std::string MixedScene() {
    std::string objects = Sphere("Material \"mirror\"", 0.5, 0.35, 0.3, 0.35) +
                          Sphere("Material \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.1]",
                                 -0.4, 0.5, -0.2, 0.5);
    return BoxScene("bdpt", CeilingLight(0.3, 10) + "LightSource \"point\" \"point from\" [0 1.5 0.5] \"rgb I\" [1 1 1]\n",
                    objects, 16, "Camera \"perspective\" \"float fov\" [40]", true);
}

std::string EnvScene() {
    return "Sampler \"random\" \"integer pixelsamples\" [4]\nFilm \"image\" \"integer xresolution\" [16] "
           "\"integer yresolution\" [16] \"string filename\" [\"unused.exr\"]\n"
           "LookAt 0 1.5 4  0 0.4 0  0 1 0\nCamera \"perspective\" \"float fov\" [45] \"float lensradius\" [0.1] "
           "\"float focaldistance\" [4]\nWorldBegin\n"
           "LightSource \"infinite\" \"rgb L\" [0.4 0.5 0.7]\n"
           "LightSource \"distant\" \"point from\" [1 3 1] \"point to\" [0 0 0] \"rgb L\" [1 1 1]\n" +
           Quad("Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]", "-3 0 -3  -3 0 3  3 0 3  3 0 -3") +
           Sphere("Material \"mirror\"", -0.5, 0.5, 0, 0.5) +
           Sphere("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]", 0.6, 0.4, 0.3, 0.4) + "WorldEnd\n";
}

// The box filled with fog (camera, lights and walls in it), a glass sphere
// holding vacuum and a material-less sphere holding a denser medium.
std::string MediaScene() {
    const std::string media =
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] "
        "\"rgb sigma_s\" [0.6 0.5 0.4] \"float g\" [0.4]\n"
        "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 0.2 0.2] "
        "\"rgb sigma_s\" [2 2 2] \"float g\" [-0.3]\n"
        "MediumInterface \"\" \"fog\"\n";
    const std::string lights = "MediumInterface \"fog\" \"fog\"\n" + CeilingLight(0.3, 10) +
                               "LightSource \"point\" \"point from\" [0 1.5 0.5] \"rgb I\" [1 1 1]\n";
    const std::string objects =
        Sphere("MediumInterface \"\" \"fog\"\nMaterial \"glass\"", 0.5, 0.35, 0.3, 0.35) +
        Sphere("MediumInterface \"smoke\" \"fog\"\nMaterial \"\"", -0.4, 0.5, -0.2, 0.45) +
        Sphere("Material \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.1]",
               -0.4, 1.4, 0.2, 0.25);
    return BoxScene("bdpt", lights, objects, 16, media + "Camera \"perspective\" \"float fov\" [40]");
}

struct Subpaths {
    std::vector<PathVertex> cv, lv;
    std::vector<BSDF> cb, lb;
    int nC = 0, nL = 0;
};

Subpaths Generate(Fixture &f, Arena &arena, int i, int maxDepth) {
    Subpaths sp;
    sp.cv.resize(maxDepth + 2);
    sp.cb.resize(maxDepth + 2);
    sp.lv.resize(maxDepth + 1);
    sp.lb.resize(maxDepth + 1);
    f.sampler->startPixelSample({i % 16, (i / 16) % 16}, i / 256);
    CameraSample cs;
    Point2 u = f.sampler->get2D();
    cs.pFilm = Point2(i % 16 + u.x, (i / 16) % 16 + u.y);
    cs.pLens = f.sampler->get2D();
    Ray ray;
    f.job.scene->camera->generateRay(cs, &ray);
    RNG *rng = f.job.scene->features.media ? &(f.rng = RNG(uint64_t(i))) : nullptr;
    sp.nC = GenerateCameraSubpath(f.ctx, ray, *f.sampler, arena, maxDepth + 2, sp.cv.data(), sp.cb.data(), rng);
    sp.nL = GenerateLightSubpath(f.ctx, *f.sampler, arena, maxDepth + 1, sp.lv.data(), sp.lb.data(), rng);
    return sp;
}

// Sum over the strategies `evaluated` leaves in play of their MIS weights
// over the strategies of `weighting` for the path x (light to camera); *wLT
// gets the light-tracing strategy's weight (0 when it is not valid or not in play),
// *wMerge the sum of the merging weights (VCM; when `evaluated` merges).
double WeightSum(const BidirContext &ctx, const StrategySet &evaluated, const StrategySet &weighting,
                 std::vector<PathVertex> x, const std::vector<BSDF> &b, int *nValid, double *wLT = nullptr,
                 double *wMerge = nullptr) {
    const int k = int(x.size());
    auto fwdL = [&](int i) {
        if (i == 0) return PdfLightOrigin(ctx, x[0], x[1]);
        return PdfArea(ctx, x[i - 1], &b[i - 1], i >= 2 ? &x[i - 2] : nullptr, x[i], TransportMode::Importance);
    };
    auto fwdC = [&](int i) {  // density of x[i] generated from the camera side
        if (i == k - 1) return Float(1);
        return PdfArea(ctx, x[i + 1], &b[i + 1], i + 2 <= k - 1 ? &x[i + 2] : nullptr, x[i], TransportMode::Radiance);
    };
    double sum = 0;
    *nValid = 0;
    if (wLT) *wLT = 0;
    if (wMerge) *wMerge = 0;
    // Light subpath x[0..sp-1] and camera subpath x[k-1..sp] with the exact densities.
    std::vector<PathVertex> L, C;
    std::vector<BSDF> LB, CB;
    auto split = [&](int sp) {
        L.assign(x.begin(), x.begin() + sp);
        LB.assign(b.begin(), b.begin() + sp);
        C.clear();
        CB.clear();
        for (int i = 0; i < sp; ++i) {
            L[i].pdfFwd = fwdL(i);
            L[i].pdfRev = fwdC(i);
        }
        for (int i = k - 1; i >= sp; --i) {
            C.push_back(x[i]);
            CB.push_back(b[i]);
            C.back().pdfFwd = fwdC(i);
            C.back().pdfRev = fwdL(i);
        }
    };
    for (int sp = 0; sp < k; ++sp) {
        int tp = k - sp;
        split(sp);
        bool valid;
        if (sp == 1 && tp == 1)
            valid = false;
        else if (sp == 0)
            valid = tp >= 2 && (x[0].isInfiniteLight() || EmitterOf(ctx, x[0])) && !x[0].isDeltaLight();
        else
            valid = !x[sp].delta() && (sp == 1 || !x[sp - 1].delta()) && EdgeConnectible(ctx, x[sp - 1], x[sp]) &&
                    x[sp].type != VertexType::Light;
        if (!valid || (tp == 1 && !evaluated.lightTracing)) continue;
        ++*nValid;
        double w = MISWeight(ctx, weighting, {L.data(), LB.data(), sp}, {C.data(), CB.data(), tp}, sp, tp, nullptr);
        sum += w;
        if (tp == 1 && wLT) *wLT = w;
    }
    // Vertex merging at every interior vertex with a non-specular BSDF: light
    // subpath x[0..j-1], camera subpath x[k-1..j].
    for (int sp = 1; evaluated.merging && sp + 1 < k; ++sp) {
        if (x[sp].type != VertexType::Surface || !b[sp] || !b[sp].hasNonSpecular()) continue;
        const int tp = k - sp;
        split(sp);
        ++*nValid;
        double w = MergeWeight(ctx, weighting, {L.data(), LB.data(), sp}, {C.data(), CB.data(), tp}, sp, tp);
        sum += w;
        if (wMerge) *wMerge += w;
    }
    return sum;
}

// Calls fn(x, b, s, t) for the full paths of (s >= 2, t >= 2) connections and
// of camera paths that hit emitters, up to `maxPaths` paths.
template <typename Fn>
void ForEachConnectedPath(Fixture &f, int maxPaths, Fn fn) {
    Arena arena;
    int checked = 0;
    for (int i = 0; i < 3000 && checked < maxPaths; ++i) {
        arena.reset();
        Subpaths sp = Generate(f, arena, i, 5);
        // Paths from (s >= 2, t >= 2) connections and from camera paths that hit emitters.
        for (int t = 2; t <= sp.nC; ++t)
            for (int s = 0; s <= sp.nL; ++s) {
                if (s == 1 || s + t - 2 > 5) continue;
                std::vector<PathVertex> x;
                std::vector<BSDF> b;
                if (s == 0) {
                    if (t < 2 || EmittedRadiance(f.ctx, sp.cv[t - 1], sp.cv[t - 2]).isBlack()) continue;
                } else {
                    ConnectResult r;
                    ConnectSamples cu;
                    cu.rng = &f.rng;
                    if (!ConnectBDPT(f.ctx, {sp.lv.data(), sp.lb.data(), sp.nL}, {sp.cv.data(), sp.cb.data(), sp.nC},
                                     s, t, cu, &r))
                        continue;
                }
                for (int j = 0; j < s; ++j) x.push_back(sp.lv[j]), b.push_back(sp.lb[j]);
                for (int j = t - 1; j >= 0; --j) x.push_back(sp.cv[j]), b.push_back(sp.cb[j]);
                // The connection endpoints scatter through the connection (non-delta).
                if (s > 0) x[s - 1].flags &= ~VERTEX_DELTA;
                x[s].flags &= ~VERTEX_DELTA;
                if (!fn(x, b, s, t)) return;
                ++checked;
            }
    }
}

void CheckWeightSums(const std::string &scene, MISHeuristic h, int minMedium = 0) {
    Fixture f(scene, h);
    int checked = 0, withDelta = 0, withMedium = 0, mediumEnds = 0;
    ForEachConnectedPath(f, 400, [&](const std::vector<PathVertex> &x, const std::vector<BSDF> &b, int s, int t) {
        bool delta = false, medium = false;
        for (auto &v : x) delta |= v.delta(), medium |= v.inMedium();
        int nValid;
        double sum = WeightSum(f.ctx, f.ctx.strategies, f.ctx.strategies, x, b, &nValid);
        EXPECT_NEAR(sum, 1.0, 1e-9) << "s=" << s << " t=" << t << " valid strategies " << nValid;
        ++checked;
        withDelta += delta;
        withMedium += medium;
        mediumEnds += s > 0 && (x[s - 1].inMedium() || x[s].inMedium());
        return sum == sum;
    });
    EXPECT_GE(checked, 200);
    EXPECT_GT(withDelta, 0);
    EXPECT_GE(withMedium, minMedium) << "paths with medium vertices";
    EXPECT_GE(mediumEnds, minMedium / 4) << "connections ending at a medium vertex";
}

TEST(BDPTMIS, WeightsSumToOneBalance) { CheckWeightSums(MixedScene(), MISHeuristic::Balance); }
TEST(BDPTMIS, WeightsSumToOnePower) { CheckWeightSums(MixedScene(), MISHeuristic::Power); }
TEST(BDPTMIS, WeightsSumToOneEnvironmentThinLens) { CheckWeightSums(EnvScene(), MISHeuristic::Balance); }
TEST(BDPTMIS, WeightsSumToOneWithMediaBalance) { CheckWeightSums(MediaScene(), MISHeuristic::Balance, 100); }
TEST(BDPTMIS, WeightsSumToOneWithMediaPower) { CheckWeightSums(MediaScene(), MISHeuristic::Power, 100); }

// StrategySet without light tracing (G-BDPT "lighttracing false"): the weights
// of the strategies still evaluated sum to one. Weighted with the t = 1 terms
// still in the sums they add up to 1 - w_LT instead, far from one on the
// paths where light tracing has a sizeable weight (so the check can fail).
void CheckWeightSumsWithoutLightTracing(const std::string &scene, MISHeuristic h, int minWithLT) {
    Fixture f(scene, h);
    StrategySet noLT;
    noLT.lightTracing = false;
    const StrategySet &all = f.ctx.strategies;
    int checked = 0, withLT = 0;
    ForEachConnectedPath(f, 400, [&](const std::vector<PathVertex> &x, const std::vector<BSDF> &b, int s, int t) {
        int nValid, nAll;
        double wLT;
        double sum = WeightSum(f.ctx, noLT, noLT, x, b, &nValid);
        EXPECT_NEAR(sum, 1.0, 1e-9) << "s=" << s << " t=" << t << " strategies " << nValid;
        WeightSum(f.ctx, all, all, x, b, &nAll, &wLT);
        if (wLT > 1e-3) {
            double counted = WeightSum(f.ctx, noLT, all, x, b, &nValid);
            EXPECT_NEAR(counted, 1 - wLT, 1e-9);
            EXPECT_LT(counted, 1 - 1e-3);
            ++withLT;
        }
        ++checked;
        return true;
    });
    EXPECT_GE(checked, 200);
    EXPECT_GE(withLT, minWithLT) << "paths on which light tracing has a sizeable weight";
}
TEST(BDPTMIS, WeightsSumToOneWithoutLightTracingBalance) {
    CheckWeightSumsWithoutLightTracing(MixedScene(), MISHeuristic::Balance, 20);
}
TEST(BDPTMIS, WeightsSumToOneWithoutLightTracingPower) {
    CheckWeightSumsWithoutLightTracing(MixedScene(), MISHeuristic::Power, 20);
}
// Infinite and distant lights (directional light vertices) and a thin lens.
TEST(BDPTMIS, WeightsSumToOneWithoutLightTracingEnvironment) {
    CheckWeightSumsWithoutLightTracing(EnvScene(), MISHeuristic::Balance, 5);
}

// n light-tracing samples per camera sample: the weights (n_k p_k)^beta /
// sum_j (n_j p_j)^beta still sum to one, and the t = 1 weight relates to the
// single-sample one w_1 by w_n = n^beta w_1 / (1 + (n^beta - 1) w_1).
void CheckLightTracingSampleCount(MISHeuristic h) {
    Fixture f(MixedScene(), h);
    StrategySet four;
    four.lightTracingSamples = 4;
    const double nb = h == MISHeuristic::Power ? 16 : 4;
    int withLT = 0;
    ForEachConnectedPath(f, 300, [&](const std::vector<PathVertex> &x, const std::vector<BSDF> &b, int s, int t) {
        int nValid;
        double w1, w4;
        WeightSum(f.ctx, four, f.ctx.strategies, x, b, &nValid, &w1);
        double sum = WeightSum(f.ctx, four, four, x, b, &nValid, &w4);
        EXPECT_NEAR(sum, 1.0, 1e-9) << "s=" << s << " t=" << t;
        if (w1 > 0) {
            EXPECT_NEAR(w4, nb * w1 / (1 + (nb - 1) * w1), 1e-9);
            ++withLT;
        }
        return true;
    });
    EXPECT_GE(withLT, 50);
}
TEST(BDPTMIS, LightTracingSampleCountBalance) { CheckLightTracingSampleCount(MISHeuristic::Balance); }
TEST(BDPTMIS, LightTracingSampleCountPower) { CheckLightTracingSampleCount(MISHeuristic::Power); }

// A t = 1 strategy that is not in play has weight 0.
TEST(BDPTMIS, StrategiesNotInPlay) {
    Fixture f(MixedScene());
    int lt = 0;
    StrategySet noLT;
    noLT.lightTracing = false;
    ForEachConnectedPath(f, 100, [&](const std::vector<PathVertex> &x, const std::vector<BSDF> &b, int s, int t) {
        const int k = int(x.size());
        if (k < 3 || x[k - 2].delta()) return true;
        // (k - 1, 1): light vertices x[0..k-2] and the lens vertex.
        std::vector<PathVertex> L(x.begin(), x.end() - 1), C{x.back()};
        std::vector<BSDF> LB(b.begin(), b.end() - 1), CB{b.back()};
        EXPECT_EQ(MISWeight(f.ctx, noLT, {L.data(), LB.data(), k - 1}, {C.data(), CB.data(), 1}, k - 1, 1, nullptr), 0);
        ++lt;
        return true;
    });
    EXPECT_GT(lt, 10);
}

// Vertex merging (VCM, G-VCM Eqs. 12-13): the weights of every connection and
// every merge of a path sum to one, for merge factors eta = pi r^2 N from
// negligible to dominant. The check can fail: with the merging terms left out of
// the connection weights the sum exceeds one by the merges' share, which is
// sizeable (> 0.01) on many of these paths for eta >= 100 (box of size 2).
void CheckWeightSumsWithMerging(const std::string &scene, MISHeuristic h) {
    Fixture f(scene, h);
    for (double eta : {1e-4, 1e-2, 1.0, 100.0, 1e4}) {
        StrategySet vcm;
        vcm.merging = true;
        vcm.mergeFactor = eta;
        int checked = 0, sizeable = 0;
        ForEachConnectedPath(f, 300, [&](const std::vector<PathVertex> &x, const std::vector<BSDF> &b, int s, int t) {
            int nValid;
            double wMerge;
            double sum = WeightSum(f.ctx, vcm, vcm, x, b, &nValid, nullptr, &wMerge);
            EXPECT_NEAR(sum, 1.0, 1e-9) << "eta=" << eta << " s=" << s << " t=" << t << " strategies " << nValid;
            if (std::abs(sum - 1) > 1e-9)
                for (size_t i = 0; i < x.size(); ++i)
                    std::printf("  x%zu type %d delta %d merge %d pdfFwd %g\n", i, int(x[i].type), int(x[i].delta()),
                                int(b[i] && b[i].hasNonSpecular()), x[i].pdfFwd);
            sizeable += wMerge > 0.01;
            ++checked;
            return sum == sum;
        });
        EXPECT_GE(checked, 200);
        if (eta >= 100) {
            EXPECT_GE(sizeable, 20) << "eta=" << eta << ": paths where merging has a sizeable weight";
        }
    }
}
TEST(BDPTMIS, WeightsSumToOneWithMergingBalance) { CheckWeightSumsWithMerging(MixedScene(), MISHeuristic::Balance); }
TEST(BDPTMIS, WeightsSumToOneWithMergingPower) { CheckWeightSumsWithMerging(MixedScene(), MISHeuristic::Power); }
TEST(BDPTMIS, WeightsSumToOneWithMergingEnvironment) { CheckWeightSumsWithMerging(EnvScene(), MISHeuristic::Balance); }
// Media: medium vertices connect but are never merged at (IsMergeable); the
// merge terms of the sums count exactly the surface merges.
TEST(BDPTMIS, WeightsSumToOneWithMergingMedia) { CheckWeightSumsWithMerging(MediaScene(), MISHeuristic::Balance); }

// The random walks store pdfFwd/pdfRev; the connection code recomputes the
// same quantities with PdfArea. They must agree, and agree with a direct
// evaluation (BSDF solid-angle pdf x |cos| / d^2).
void CheckReversePdfs(const std::string &scene) {
    Fixture f(scene);
    Arena arena;
    int checked = 0;
    auto rel = [](double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-300}); };
    for (int i = 0; i < 500; ++i) {
        arena.reset();
        Subpaths sp = Generate(f, arena, i, 5);
        for (int side = 0; side < 2; ++side) {
            const auto &v = side ? sp.lv : sp.cv;
            const auto &b = side ? sp.lb : sp.cb;
            int n = side ? sp.nL : sp.nC;
            TransportMode mode = side ? TransportMode::Importance : TransportMode::Radiance;
            TransportMode rev = side ? TransportMode::Radiance : TransportMode::Importance;
            for (int k = 2; k < n; ++k) {
                if (v[k - 1].delta() || v[k].type != VertexType::Surface) continue;
                // Forward pdf of vertex k as the connection code computes it.
                double fwd = PdfArea(f.ctx, v[k - 1], &b[k - 1], &v[k - 2], v[k], mode);
                ASSERT_LT(rel(fwd, v[k].pdfFwd), 3e-3) << "side " << side << " k " << k;
                // Independent evaluation.
                Vec3 wi = v[k].p - v[k - 1].p;
                double d2 = wi.lengthSquared();
                wi = wi / std::sqrt(d2);
                double direct = b[k - 1].pdf(Normalize(v[k - 2].p - v[k - 1].p), wi, mode) *
                                AbsDot(Vec3(v[k].ng), wi) / d2;
                ASSERT_LT(rel(direct, fwd), 1e-4);
                // Reverse pdf of vertex k-1 (stored when k sampled k+1) as a connection through k computes it.
                if (k + 1 < n && !v[k].delta() && v[k + 1].type == VertexType::Surface) {
                    double r = PdfArea(f.ctx, v[k], &b[k], &v[k + 1], v[k - 1], rev);
                    ASSERT_LT(rel(r, v[k - 1].pdfRev), 3e-3) << "side " << side << " k " << k;
                }
                ++checked;
            }
        }
    }
    EXPECT_GT(checked, 50);
}

TEST(BDPTMIS, ReversePdfsMatchForwardPdfs) { CheckReversePdfs(MixedScene()); }
TEST(BDPTMIS, ReversePdfsMatchForwardPdfsEnvironment) { CheckReversePdfs(EnvScene()); }

// With media: the densities the walks store at and around medium vertices
// equal PdfArea's, and an independent evaluation (HG phase of the scattering
// vertex, |cos| only at a surface end, 1/d^2). Fails if a medium end took a
// cosine or a medium vertex used a BSDF's density.
TEST(BDPTMIS, ReversePdfsMatchForwardPdfsMedia) {
    Fixture f(MediaScene());
    Arena arena;
    int checked = 0, fromMedium = 0;
    auto rel = [](double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-300}); };
    for (int i = 0; i < 500; ++i) {
        arena.reset();
        Subpaths sp = Generate(f, arena, i, 5);
        for (int side = 0; side < 2; ++side) {
            const auto &v = side ? sp.lv : sp.cv;
            const auto &b = side ? sp.lb : sp.cb;
            const int n = side ? sp.nL : sp.nC;
            const TransportMode mode = side ? TransportMode::Importance : TransportMode::Radiance;
            const TransportMode rev = side ? TransportMode::Radiance : TransportMode::Importance;
            for (int k = 2; k < n; ++k) {
                if (v[k - 1].delta() || !v[k].scatters() || !(v[k].inMedium() || v[k - 1].inMedium())) continue;
                // Edges below 1e-2 (a medium vertex just off a surface) carry the ray's
                // spawn offset as a relative error of ~1e-3 / length: left out.
                if ((v[k].p - v[k - 1].p).length() < 1e-2 || (v[k - 1].p - v[k - 2].p).length() < 1e-2 ||
                    (k + 1 < n && (v[k + 1].p - v[k].p).length() < 1e-2))
                    continue;
                const double fwd = PdfArea(f.ctx, v[k - 1], &b[k - 1], &v[k - 2], v[k], mode);
                ASSERT_LT(rel(fwd, v[k].pdfFwd), 3e-3) << "side " << side << " k " << k << " types " << int(v[k - 2].type)
                                                         << int(v[k - 1].type) << int(v[k].type) << " d "
                                                         << (v[k].p - v[k - 1].p).length() << " " << (v[k - 1].p - v[k - 2].p).length();
                Vec3 wi = v[k].p - v[k - 1].p;
                const double d2 = wi.lengthSquared();
                wi = wi / std::sqrt(d2);
                const Vec3 wo = Normalize(v[k - 2].p - v[k - 1].p);
                const double dirPdf = v[k - 1].inMedium() ? HenyeyGreenstein(Dot(-wo, wi), v[k - 1].medium->phase.g)
                                                          : b[k - 1].pdf(wo, wi, mode);
                const double cosEnd = v[k].inMedium() ? 1.0 : AbsDot(Vec3(v[k].ng), wi);
                ASSERT_LT(rel(dirPdf * cosEnd / d2, fwd), 1e-4) << "side " << side << " k " << k;
                if (k + 1 < n && !v[k].delta() && v[k + 1].scatters()) {
                    const double r = PdfArea(f.ctx, v[k], &b[k], &v[k + 1], v[k - 1], rev);
                    ASSERT_LT(rel(r, v[k - 1].pdfRev), 3e-3) << "side " << side << " k " << k;
                }
                ++checked;
                fromMedium += v[k - 1].inMedium();
            }
        }
    }
    EXPECT_GT(checked, 100);
    EXPECT_GT(fromMedium, 30);
}

TEST(BDPTMIS, CompactVertex) {
    // Stored light vertices must stay small (M-BDPT / VCM keep one iteration's worth).
    EXPECT_LE(sizeof(PathVertex), 120u);
}

// Throughputs keep double's range at float's precision: 1e39 (beyond float)
// and 1e-41 (below float's normal range) round-trip to 2^-24 relative; values
// in [1e-30, 1e30] are stored unscaled; zero and sign survive.
TEST(BDPTMIS, ThroughputKeepsDoubleRange) {
    for (double m : {1e300, 4e39, 1e31, 1.0, 0.3, 1e-31, 1e-41, 1e-300}) {
        PathVertex v;
        const Spectrum s(m, 0.25 * m, -0.5 * m);
        v.setThroughput(s);
        const Spectrum t = v.throughput();
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(t[c] / m, s[c] / m, 1.2e-7) << m << " channel " << c;
        EXPECT_EQ(v.betaExp == 0, m <= 1e30 && m >= 1e-30) << m;
    }
    PathVertex z;
    z.setThroughput(Spectrum(0));
    EXPECT_TRUE(z.throughput().isBlack());
    EXPECT_EQ(z.betaExp, 0);
}

}  // namespace
}  // namespace gradus::bdpt_test

// Regression (bench/stress camera_in_box): a camera inside a closed cube with
// only an environment outside sees nothing. Connections between a light vertex
// on the outside of a face and a camera vertex on its inside lie in the face's
// plane and passed the visibility test (pixels up to 1e-28 with bdpt, mbdpt,
// gbdpt); EdgeConnectible now leaves such tangent-plane edges out. gpt's
// offsets saw the environment the same way (8e-31 in its gradient layers)
// until ShiftEdgeVisible applied the rule to its shadow and reconnection rays.
TEST(BDPTMIS, NoLightThroughTheFacesOfAClosedCube) {
    const std::string scene = R"(
LookAt 0.2 0.1 -0.3  0.7 0.6 1  0 1 0
Camera "perspective" "float fov" [60]
Sampler "random"
Film "image" "integer xresolution" [32] "integer yresolution" [32]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "matte" "rgb Kd" [1 1 1]
Shape "trianglemesh" "point P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ]
    "integer indices" [ 0 2 1  0 3 2  4 5 6  4 6 7  0 1 5  0 5 4  3 6 2  3 7 6  0 4 7  0 7 3  1 2 6  1 6 5 ]
WorldEnd
)";
    for (const char *integrator : {"bdpt", "mbdpt", "gbdpt", "gpt"}) {
        gradus::Image img =
            gradus::test::RenderTestDesc(gradus::ParseString(scene, "cube.pbrt", "."), 16, 0, 0, integrator).image;
        double worst = 0;
        for (float v : img.data()) worst = std::max(worst, double(std::abs(v)));
        EXPECT_EQ(worst, 0.0) << integrator;
    }
}
