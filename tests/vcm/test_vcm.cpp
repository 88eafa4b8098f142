// VCM (integrators/vcm): the photon grid against brute force; the recursive
// MIS weights against the O(n) reference (MISWeight with merging terms,
// common/bidir.h) on random subpaths; each mode against bdpt in expectation
// (the conformance agreement test with its false-positive rate and power check).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "bdpt/bdpt_test_util.h"
#include "conformance/agreement.h"
#include "integrators/common/bidir.h"
#include "integrators/common/photon_grid.h"
#include "integrators/vcm/vcm.h"
#include "lights/light_sampler.h"

namespace gradus {
namespace {

PhotonGrid::ParallelFor Serial(bool reverse) {
    return [reverse](int64_t n, int64_t grain, const std::function<void(int64_t, int64_t)> &fn) {
        const int64_t ranges = (n + grain - 1) / grain;
        for (int64_t k = 0; k < ranges; ++k) {
            const int64_t r = reverse ? ranges - 1 - k : k;
            fn(r * grain, std::min(n, (r + 1) * grain));
        }
    };
}

// Every point within r is reported once, none beyond, in an order that does
// not depend on the order in which build ranges ran.
TEST(PhotonGrid, QueriesEqualBruteForce) {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<Point3> pts;
    for (int i = 0; i < 20000; ++i) pts.push_back(Point3(u(rng), u(rng), u(rng)));
    for (int i = 0; i < 2000; ++i) pts.push_back(Point3(0.3 + 1e-3 * u(rng), -0.2, 0.1 * u(rng)));  // a cluster
    pts.push_back(pts[5]);                                                                          // a duplicate
    for (double r : {0.003, 0.02, 0.1}) {
        PhotonGrid a, b;
        auto at = [&](size_t i) { return pts[i]; };
        a.build(pts.size(), at, r, Serial(false));
        b.build(pts.size(), at, r, Serial(true));
        for (int q = 0; q < 300; ++q) {
            Point3 p = q < 100 ? pts[q * 37] : Point3(u(rng), u(rng), u(rng));
            std::vector<uint32_t> got, got2, want;
            a.query(p, [&](uint32_t i, Float d2) {
                got.push_back(i);
                EXPECT_DOUBLE_EQ(d2, (pts[i] - p).lengthSquared());
            });
            b.query(p, [&](uint32_t i, Float) { got2.push_back(i); });
            EXPECT_EQ(got, got2);
            for (uint32_t i = 0; i < pts.size(); ++i)
                if ((pts[i] - p).lengthSquared() < r * r) want.push_back(i);
            std::sort(got.begin(), got.end());
            EXPECT_EQ(got, want) << "r " << r << " query " << q;
        }
    }
}

// Far from the origin the grid's float positions are coarser than the radius
// (1e6: steps of 0.06 against r = 0.004): the points found are still exactly
// those of the exact positions, with their exact distances.
TEST(PhotonGrid, FloatPositionsFindExactlyTheExactNeighbours) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    const Point3 c(1e6, -2e6, 3e5);
    std::vector<Point3> pts;
    for (int i = 0; i < 5000; ++i) pts.push_back(c + Vec3(u(rng), u(rng), u(rng)));
    const double r = 0.004;
    PhotonGrid g;
    g.build(pts.size(), [&](size_t i) { return pts[i]; }, r, Serial(false));
    for (int q = 0; q < 400; ++q) {
        const Point3 p = q % 2 ? pts[q] + Vec3(0.7 * r, 0, 0) : c + Vec3(u(rng), u(rng), u(rng));
        std::vector<uint32_t> got, want;
        g.query(p, [&](uint32_t i, Float d2) {
            got.push_back(i);
            EXPECT_EQ(d2, (pts[i] - p).lengthSquared());
        });
        for (uint32_t i = 0; i < pts.size(); ++i)
            if ((pts[i] - p).lengthSquared() < r * r) want.push_back(i);
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, want) << "query " << q;
    }
}

// The recursive weights of vcm (VCMLightVertices / VCMCameraEta / VCMCameraB
// and the sums) equal the O(n) reference MISWeight with the same merging terms
// for connections (s >= 2, t >= 2), light tracing (t = 1) and emitter hits
// (s = 0) of random subpaths in a box with a mirror and a glossy sphere. Kernels:
// one eta for every vertex (from 0, mode vc, to dominant; the reference takes
// StrategySet::mergeFactor, the recursion a MergeKernel) and the adaptive
// kernel of G-VCM Sec. 6 (the reference computes each path's radii from the
// whole path, merge_kernel.h; the recursion from its two subpaths), with
// shrink exponents that leave the light side's split B visible; both heuristics.
struct KernelCase {
    const char *name;
    double eta;    // fixed: eta at every vertex
    double shrink; // adaptive (eta < 0): G-VCM Sec. 6 with this exponent
};
// media: the box filled with fog, a material-less sphere of denser smoke
// (medium vertices on both subpaths, connected, never merged at); only the
// fixed kernels, as vcm renders media only with them.
std::string WeightsScene(bool media) {
    using namespace bdpt_test;
    std::string objects = Sphere("Material \"mirror\"", 0.5, 0.35, 0.3, 0.35) +
                          Sphere("Material \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.1]",
                                 -0.4, 0.5, -0.2, 0.5);
    std::string cameraLine = "Camera \"perspective\" \"float fov\" [40]", lights = CeilingLight(0.3, 10);
    if (media) {
        cameraLine = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] "
                 "\"rgb sigma_s\" [0.6 0.5 0.4] \"float g\" [0.4]\n"
                 "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 0.2 0.2] "
                 "\"rgb sigma_s\" [2 2 2] \"float g\" [-0.3]\nMediumInterface \"\" \"fog\"\n" + cameraLine;
        lights = "MediumInterface \"fog\" \"fog\"\n" + lights;
        objects += Sphere("MediumInterface \"smoke\" \"fog\"\nMaterial \"\"", 0.1, 1.3, 0.2, 0.3);
    }
    return BoxScene("bdpt", lights, objects, 16, cameraLine, true);
}

MergeKernel CaseKernel(const KernelCase &kc, const Camera &camera) {
    const bool adaptive = kc.eta < 0;
    MergeKernel k;
    k.piN = 1;
    k.r2 = adaptive ? 1e-3 : kc.eta;
    if (adaptive) {
        // eta at the first mergeable vertex about 1 .. 100 (footprint^2 ~ 1e-4 .. 1e-2 in this box).
        k.footprint2 = 3e3;
        k.r2Max = 1e9;
        k.shrink = kc.shrink;
        k.pixels = Float(camera.fullResolution.x) * camera.fullResolution.y;
        k.camera = &camera;
    }
    return k;
}

// What one kernel case checks against: the reference's strategies and the
// recursion's weights (both pointing at k).
struct WeightsCase {
    const BidirContext &ctx;
    const KernelCase &kc;
    const MergeKernel &k;
    const StrategySet &set;
    const VCMWeights &w;
};

struct WeightCounts {
    int checked = 0, withSpecular = 0, lightTraced = 0, shrunk = 0, mediumEnds = 0;
};

// One camera and one light subpath with the recursion's quantities.
struct WeightSubpaths {
    std::vector<PathVertex> cv, lv;
    std::vector<BSDF> cb, lb;
    int nC = 0, nL = 0;
    std::vector<LightVertex> recs;  // the light vertices vcm stores
    std::vector<Float> B, eta;      // per camera vertex
    explicit WeightSubpaths(int maxDepth) : cv(maxDepth + 2), lv(maxDepth + 1), cb(maxDepth + 2), lb(maxDepth + 1) {}
    SubpathView cam() const { return {cv.data(), cb.data(), nC}; }
    SubpathView light() const { return {lv.data(), lb.data(), nL}; }
};

// Sample i: a camera subpath through pixel (i % 16, i / 16 % 16) and a light subpath.
void GenerateWeightSubpaths(const WeightsCase &wc, int i, int maxDepth, Sampler &sampler, Arena &arena, RNG &rng,
                            bool media, WeightSubpaths &p) {
    const Camera &camera = *wc.ctx.scene->camera;
    sampler.startPixelSample({i % 16, (i / 16) % 16}, i / 256);
    CameraSample cs;
    Point2 u = sampler.get2D();
    cs.pFilm = Point2(i % 16 + u.x, (i / 16) % 16 + u.y);
    cs.pLens = sampler.get2D();
    Ray ray;
    camera.generateRay(cs, &ray);
    rng = RNG(uint64_t(i));
    RNG *mrng = media ? &rng : nullptr;
    p.nC = GenerateCameraSubpath(wc.ctx, ray, sampler, arena, maxDepth + 2, p.cv.data(), p.cb.data(), mrng);
    p.nL = GenerateLightSubpath(wc.ctx, sampler, arena, maxDepth + 1, p.lv.data(), p.lb.data(), mrng);
    VCMLightVertices(wc.ctx, p.lv.data(), p.lb.data(), p.nL, wc.w, &p.recs);
    p.B.resize(p.nC);
    p.eta.resize(p.nC);
    VCMCameraEta(wc.w, p.cv.data(), p.cb.data(), p.nC, p.eta.data());
    VCMCameraB(wc.ctx, p.cv.data(), p.cb.data(), p.nC, wc.w, p.eta.data(), p.B.data());
}

// t = 1: light tracing from every stored vertex, eta at y_i from its footprint.
void CheckLightTracingWeights(const WeightsCase &wc, const WeightSubpaths &p, Sampler &sampler, WeightCounts &n) {
    const BidirContext &ctx = wc.ctx;
    for (const LightVertex &y : p.recs) {
        const int s = y.depth + 1;
        const PathVertex &yv = p.lv[s - 1];
        PathVertex lens;
        CameraWiSample cws;
        if (!SampleLensVertex(ctx, yv, sampler.get2D(), &lens, &cws) || !EdgeConnectible(ctx, yv, lens)) continue;
        const Float ref = MISWeight(ctx, wc.set, p.light(), p.cam(), s, 1, &lens);
        const Float oi = PdfArea(ctx, lens, nullptr, nullptr, yv, TransportMode::Radiance);
        const Float oim1 = PdfArea(ctx, yv, &p.lb[s - 1], &lens, p.lv[s - 2], TransportMode::Radiance);
        Float hy = 0;
        if (wc.set.merging) {
            const Vec3 d = yv.p - lens.p;
            hy = wc.k.firstEta(lens.p, Normalize(d), d.length());
        }
        const Float rec = 1 / (1 + VCMLightSum(y, oi, oim1, hy, wc.w.sigma(&p.lb[s - 1]), wc.w));
        EXPECT_NEAR(rec, ref, 1e-6 * (1 + ref)) << "s=" << s << " t=1 " << wc.kc.name;
        ++n.lightTraced;
    }
}

// s = 0 at camera vertex uu = t - 1 when it is an emitter.
void CheckEmitterHitWeight(const WeightsCase &wc, const WeightSubpaths &p, int t, WeightCounts &n) {
    const BidirContext &ctx = wc.ctx;
    const int uu = t - 1;
    const PathVertex &z = p.cv[uu];
    if (EmittedRadiance(ctx, z, p.cv[uu - 1]).isBlack()) return;
    const Float ref = MISWeight(ctx, wc.set, p.light(), p.cam(), 0, t, nullptr);
    const Float rec = 1 / (1 + VCMCameraSum(VCMCameraAt(ctx, p.cv.data(), p.cb.data(), uu, p.B[uu], p.eta.data(), wc.w),
                                            PdfLightOrigin(ctx, z, p.cv[uu - 1]),
                                            PdfLightDirection(ctx, z, p.cv[uu - 1]), false, true, wc.w));
    EXPECT_NEAR(rec, ref, 1e-9 * (1 + ref)) << "s=0 t=" << t << " " << wc.kc.name;
    ++n.checked;
}

// s >= 2, t: connections of camera vertex t - 1 to every stored light vertex.
void CheckConnectionWeights(const WeightsCase &wc, const WeightSubpaths &p, int t, ConnectSamples &cu,
                            WeightCounts &n) {
    const BidirContext &ctx = wc.ctx;
    const VCMWeights &w = wc.w;
    const std::vector<PathVertex> &cv = p.cv, &lv = p.lv;
    const std::vector<BSDF> &cb = p.cb, &lb = p.lb;
    const int uu = t - 1;
    const PathVertex &z = cv[uu];
    const VCMCameraTerms terms = VCMCameraAt(ctx, cv.data(), cb.data(), uu, p.B[uu], p.eta.data(), w);
    for (const LightVertex &y : p.recs) {
        const int s = y.depth + 1;
        ConnectResult r;
        if (!ConnectBDPT(ctx, p.light(), p.cam(), s, t, cu, &r)) continue;
        const PathVertex &yv = lv[s - 1];
        const Float ref = MISWeight(ctx, wc.set, p.light(), p.cam(), s, t, nullptr);
        const Float oi = PdfArea(ctx, z, &cb[uu], &cv[uu - 1], yv, TransportMode::Radiance);
        const Float oim1 = PdfArea(ctx, yv, &lb[s - 1], &z, lv[s - 2], TransportMode::Radiance);
        const Float oz = PdfArea(ctx, yv, &lb[s - 1], &lv[s - 2], z, TransportMode::Importance);
        const Float op = PdfArea(ctx, z, &cb[uu], &yv, cv[uu - 1], TransportMode::Importance);
        const Float rec = 1 / (1 + VCMLightSum(y, oi, oim1, terms.H, w.sigma(&lb[s - 1]), w) +
                               VCMCameraSum(terms, oz, op, w.merging && !z.inMedium(), false, w));
        EXPECT_NEAR(rec, ref, 1e-6 * (1 + ref)) << "s=" << s << " t=" << t << " " << wc.kc.name;
        bool spec = false;
        for (int q = 1; q < s - 1; ++q) spec |= lv[q].delta();
        for (int q = 1; q < uu; ++q) spec |= cv[q].delta();
        n.withSpecular += spec;
        n.mediumEnds += z.inMedium() || yv.inMedium();
        ++n.checked;
    }
}

// 1500 subpath pairs with one kernel: every strategy's recursive weight
// against the reference, and enough of each kind checked.
void CheckKernelCase(const BidirContext &ctx, const KernelCase &kc, MISHeuristic h, bool media, Sampler &sampler) {
    const int maxDepth = 6;
    const bool adaptive = kc.eta < 0;
    const MergeKernel k = CaseKernel(kc, *ctx.scene->camera);
    StrategySet set;
    set.merging = adaptive || kc.eta > 0;
    set.mergeFactor = adaptive ? 0 : kc.eta;
    set.kernel = adaptive ? &k : nullptr;
    const VCMWeights w{set.merging ? &k : nullptr, set.merging, true, h == MISHeuristic::Power};
    const WeightsCase wc{ctx, kc, k, set, w};
    WeightCounts n;
    RNG rng;
    ConnectSamples cu;
    cu.rng = &rng;
    Arena arena;
    for (int i = 0; i < 1500; ++i) {
        arena.reset();
        WeightSubpaths p(maxDepth);
        GenerateWeightSubpaths(wc, i, maxDepth, sampler, arena, rng, media, p);
        for (int j = 2; j < p.nC; ++j) n.shrunk += p.eta[j - 1] > 0 && p.eta[j] > 0 && p.eta[j] < 0.99 * p.eta[j - 1];
        CheckLightTracingWeights(wc, p, sampler, n);
        for (int t = 2; t <= p.nC; ++t) {
            CheckEmitterHitWeight(wc, p, t, n);
            const PathVertex &z = p.cv[t - 1];
            if (z.scatters() && IsConnectible(z, &p.cb[t - 1])) CheckConnectionWeights(wc, p, t, cu, n);
        }
    }
    EXPECT_GE(n.checked, 1000) << kc.name;
    EXPECT_GE(n.lightTraced, 300) << kc.name;
    EXPECT_GE(n.withSpecular, 30) << "connections with a specular interior vertex, " << kc.name;
    if (media) {
        EXPECT_GE(n.mediumEnds, 300) << "connections at a medium vertex, " << kc.name;
    }
    if (adaptive && kc.shrink > 0) {
        EXPECT_GE(n.shrunk, 300) << "camera vertices with a shrunk radius, " << kc.name;
    }
}

void CheckRecursiveWeights(MISHeuristic h, bool media = false) {
    BuildOptions bo;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseString(WeightsScene(media)), bo);
    LightSampler ls(job.scene->lights, "power", FileLoc());
    BidirContext ctx;
    ctx.init(*job.scene, ls, h);
    auto sampler = job.sampler->clone();
    for (KernelCase kc : {KernelCase{"fixed 0", 0, 0}, KernelCase{"fixed 1e-2", 1e-2, 0}, KernelCase{"fixed 1", 1, 0},
                          KernelCase{"fixed 100", 100, 0}, KernelCase{"adaptive s=10", -1, 10},
                          KernelCase{"adaptive s=1", -1, 1}, KernelCase{"footprint s=0", -1, 0}}) {
        if (media && kc.eta < 0) continue;
        CheckKernelCase(ctx, kc, h, media, *sampler);
    }
}
TEST(VCMWeights, RecursiveEqualsReferenceBalance) { CheckRecursiveWeights(MISHeuristic::Balance); }
TEST(VCMWeights, RecursiveEqualsReferencePower) { CheckRecursiveWeights(MISHeuristic::Power); }
TEST(VCMWeights, RecursiveEqualsReferenceMediaBalance) { CheckRecursiveWeights(MISHeuristic::Balance, true); }
TEST(VCMWeights, RecursiveEqualsReferenceMediaPower) { CheckRecursiveWeights(MISHeuristic::Power, true); }

// Settings that another choice would silently ignore are located errors.
TEST(MergeKernel, IgnoredSettingsAreLocatedErrors) {
    using namespace bdpt_test;
    for (const char *bad : {"\"float kernelshrink\" [3]", "\"float radius\" [0.1] \"string footprint\" \"path\""})
        for (const char *integrator : {"vcm", "gvcm"}) {
            std::string text = BoxScene(integrator, CeilingLight(0.3, 10), "");
            const size_t eol = text.find('\n');
            text.insert(eol, std::string(" ") + bad);
            BuildOptions bo;
            bo.quiet = true;
            try {
                BuildRenderJob(ParseString(text), bo);
                ADD_FAILURE() << integrator << " accepted " << bad;
            } catch (const Error &e) {
                EXPECT_NE(std::string(e.what()).find("<string>:1:"), std::string::npos) << e.what();
            }
        }
    // The same settings where they take effect are accepted.
    BuildOptions bo;
    bo.quiet = true;
    std::string text = BoxScene("vcm", CeilingLight(0.3, 10), "");
    text.insert(text.find('\n'), " \"string kernel\" \"adaptive\" \"float kernelshrink\" [3] \"string footprint\" \"path\"");
    EXPECT_NO_THROW(BuildRenderJob(ParseString(text), bo));
}

// With both Sec. 6 options on, vcm and gvcm stay independent of the thread
// count (the conformance table renders the defaults): bit-identical images,
// every layer, for 1, 2 and 7 threads; and the options change the image.
TEST(MergeKernel, AdaptiveOptionsAreThreadCountIndependent) {
    using namespace bdpt_test;
    const std::string objects = Sphere("Material \"glass\"", 0.2, 0.45, 0.1, 0.4);
    for (const char *integrator : {"vcm", "gvcm"}) {
        std::string text = BoxScene(integrator, CeilingLight(0.3, 10), objects);
        const std::string plain = text;
        text.insert(text.find('\n'), " \"string kernel\" \"adaptive\" \"string footprint\" \"path\"");
        const Image ref = test::RenderTestDesc(ParseString(text), 4, 42, 1).image;
        for (int n : {2, 7}) {
            const Image img = test::RenderTestDesc(ParseString(text), 4, 42, n).image;
            ASSERT_EQ(img.channelNames(), ref.channelNames()) << integrator;
            EXPECT_TRUE(img.data() == ref.data()) << integrator << ": --nthreads " << n << " differs from 1";
        }
        EXPECT_FALSE(test::RenderTestDesc(ParseString(plain), 4, 42, 1).image.data() == ref.data()) << integrator;
    }
}

// The footprint radius of G-VCM Sec. 6 by hand: the centre pixel of a pinhole
// camera (fov 40 degrees, 16 x 16 pixels) is 4.5 * 2 tan(20 deg) / 16 wide on
// the wall 4.5 units ahead; behind a first vertex the
// radius shrinks by 0.5^(s tau) per vertex (tau = 1 on the matte wall).
TEST(MergeKernel, FootprintAndShrinkByHand) {
    using namespace bdpt_test;
    RenderJob job = [] {
        BuildOptions bo;
        bo.quiet = true;
        return BuildRenderJob(ParseString(BoxScene("bdpt", CeilingLight(0.3, 10), "")), bo);
    }();
    LightSampler ls(job.scene->lights, "power", FileLoc());
    BidirContext ctx;
    ctx.init(*job.scene, ls, MISHeuristic::Balance);
    const Camera &camera = *job.scene->camera;
    MergeKernel k;
    k.piN = 2;
    k.r2 = 1e-9;
    k.footprint2 = 0.25;  // radiusscale 0.5
    k.r2Max = 1e9;
    k.shrink = 3;
    k.pixels = 256;
    k.camera = &camera;
    auto sampler = job.sampler->clone();
    sampler->startPixelSample({8, 8}, 0);
    CameraSample cs;
    cs.pFilm = Point2(8, 8);
    cs.pLens = Point2(0.5, 0.5);
    Ray ray;
    camera.generateRay(cs, &ray);
    Arena arena;
    std::vector<PathVertex> cv(4);
    std::vector<BSDF> cb(4);
    const int n = GenerateCameraSubpath(ctx, ray, *sampler, arena, 4, cv.data(), cb.data());
    ASSERT_GE(n, 3);
    ASSERT_NEAR(cv[1].p.z, -1, 1e-9);
    const VCMWeights w{&k, true, true, false};
    std::vector<Float> eta(n);
    VCMCameraEta(w, cv.data(), cb.data(), n, eta.data());
    const Float side = 4.5 * 2 * std::tan(20 * Pi / 180) / 16;
    EXPECT_NEAR(eta[1], 2 * 0.25 * side * side, 1e-9 * eta[1]);
    EXPECT_NEAR(eta[2], eta[1] * std::pow(0.25, 3.0), 1e-12 * eta[1]);
    // Off axis (pixel column 2): the pixel's solid angle shrinks by cos^3 of the angle to the view axis.
    cs.pFilm = Point2(2, 8);
    Ray ray2;
    camera.generateRay(cs, &ray2);
    const int n2 = GenerateCameraSubpath(ctx, ray2, *sampler, arena, 4, cv.data(), cb.data());
    ASSERT_GE(n2, 2);
    std::vector<Float> eta2(n2);
    VCMCameraEta(w, cv.data(), cb.data(), n2, eta2.data());
    const Float l = Distance(cv[1].p, ray2.o), cosT = Dot(Normalize(ray2.d), Vec3(0, 0, -1));
    const Float w0 = 2 * std::tan(20 * Pi / 180) / 16;
    EXPECT_LT(cosT, 0.99);
    EXPECT_NEAR(eta2[1], 2 * 0.25 * l * l * w0 * w0 * cosT * cosT * cosT, 1e-9 * eta2[1]);
    // Clamped to r2Max, and the fixed radius through the filter margin (no camera density).
    k.r2Max = 1e-4;
    VCMCameraEta(w, cv.data(), cb.data(), n2, eta2.data());
    EXPECT_DOUBLE_EQ(eta2[1], 2 * 1e-4);
    EXPECT_DOUBLE_EQ(k.firstEta(ray.o, Normalize(Vec3(0, -1, -1e-3)), 1), 2 * 1e-9);
}

// Modes vc (= BDPT) and vm (progressive photon mapping) and the power
// heuristic agree with bdpt in expectation on the conformance table's scene
// with a mirror (mode vcm with the balance heuristic is in the table itself).
// K = 16 runs of 8 spp; alpha 1e-4 per case, power check: a 5% bias is detected.
TEST(VCM, ModesAgreeWithBdpt) {
    using namespace conformance;
    CheckAgreement("vcm", "specular-box", {16, 8, 5000, 6000, {"--param", "mode=vc"}});
    CheckAgreement("vcm", "specular-box", {16, 8, 5100, 6100, {"--param", "mode=vm"}});
    CheckAgreement("vcm", "specular-box", {16, 8, 5200, 6200, {"--param", "misheuristic=power"}});
}

}  // namespace
}  // namespace gradus

// Regression (bench/stress empty_env): a world without shapes under a
// uniform environment of radiance 1. The environment's light-tracing disk came
// from empty scene bounds (radius 0, NaN centre) and every vcm sample was
// non-finite; now every integrator sees exactly 1 (a white furnace).
TEST(VCM, EmptyWorldUnderAnEnvironmentIsExactlyOne) {
    const std::string scene = R"(
LookAt 0 0 0  0 0 1  0 1 0
Camera "perspective" "float fov" [60]
Sampler "random"
PixelFilter "box" "float xwidth" [0.5] "float ywidth" [0.5]
Film "image" "integer xresolution" [16] "integer yresolution" [16]
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
WorldEnd
)";
    for (const char *integrator : {"vcm", "bdpt", "mbdpt", "gbdpt"}) {
        gradus::test::TestRender r =
            gradus::test::RenderTestDesc(gradus::ParseString(scene, "env.pbrt", "."), 4, 0, 0, integrator);
        EXPECT_EQ(r.stats.nonFinite, 0u) << integrator;
        gradus::Image rgb = r.image.layerRGB("");
        for (float v : rgb.data()) ASSERT_NEAR(v, 1.0, 1e-6) << integrator;
    }
}
