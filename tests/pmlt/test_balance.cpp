// Detailed balance of every pmlt mutation, checked statistically.
//
// For bins A, B of path space, detailed balance of the kernel K(x -> y) =
// T(x -> y) a(x -> y) with respect to I means equal flows
//   Phi(A -> B) = int_A int_B I(x) T(x -> y) a(x -> y) dy dx = Phi(B -> A).
// States x distributed as I are drawn by importance sampling: every
// strategy (s, t) of an independent bdpt sample is a path x_c with weight
// w_c = Y(w_st C*_st) (the MIS-weighted contribution's luminance), so that
// E[sum_c w_c g(x_c)] = int I g. From each x_c one proposal y of the mutation
// under test is drawn (kRepeats of them); sample k adds D_k = sum_c w_c a(x_c -> y_c)
// ([x_c in A, y_c in B] - [x_c in B, y_c in A]), iid over k with mean
// Phi(A -> B) - Phi(B -> A) = 0 under detailed balance. Each pair of bins with
// at least 30 non-zero D_k gets Student's t = mean / standard error, tested
// two-sided at alpha = 1e-3 split over all pairs and mutations (Bonferroni:
// false-positive rate <= 1e-3 for any dependence between the pairs).
// Bins: path length (2 .. 7 vertices) x film quadrant for the bidirectional
// mutation; film cells of 4 x 4 pixels for the perturbations (which keep the
// length). Scenes: specular-box of the conformance table (bidirectional;
// manifold through its mirror and glass sphere, film offsets up to half the
// width) and
// a caustic scene (lens, caustic, multi-chain: their path types are rare in
// the box), 80 000 and 150 000 samples, several proposals per state for the
// perturbations; perturbation ranges wider than the defaults (more flow
// between bins; balance must hold for any range).
// Power: the same proposals accepted with a = min(1, I(y) / I(x)), i.e.
// without the transition densities, must be rejected for each mutation (the
// test sees a kernel that is wrong by T(y -> x) / T(x -> y)). Measured:
// largest |t|/critical 0.35 - 0.59 with the densities, 1.16 - 2.12 without,
// except the manifold perturbation (0.45 and 0.43: no power, see below).
#include <array>
#include <map>

#include "conformance/conformance_util.h"
#include "pmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

constexpr int kTypes = pmlt::kMutationTypes;
constexpr int kMinSamples = 50;
// Proposals drawn from each state, per mutation type (more for the
// perturbations of rare path types: their flows are sums over the repeats).
constexpr int kRepeats[kTypes] = {1, 2, 16, 128, 16};

struct Flow {
    double s1 = 0, s2 = 0;
    int forward = 0, backward = 0;  // samples with flow A -> B, B -> A
};

struct Result {
    double maxMargin = 0;  // max over tested pairs of |t| / critical
    int pairs = 0;
    std::string worst;
};

struct Balance {
    // flows[type][naive][pair]
    std::array<std::array<std::map<std::pair<int, int>, Flow>, 2>, kTypes> flows;
    int64_t proposals[kTypes] = {};
};

int Bin(const pmlt::State &s, bool byLength, int width, int height) {
    const int cx = std::min(int(s.e.pRaster.x) / 4, width / 4 - 1), cy = std::min(int(s.e.pRaster.y) / 4, height / 4 - 1);
    if (!byLength) return cy * (width / 4) + cx;
    const int quadrant = (s.e.pRaster.x >= width / 2 ? 1 : 0) + (s.e.pRaster.y >= height / 2 ? 2 : 0);
    return (s.x.size() - 2) * 4 + quadrant;
}

Balance Measure(const std::string &sceneText, int samples, uint64_t seed, const std::vector<pmlt::MutationType> &types,
                Float lensRange) {
    SceneSetup su(sceneText);
    const int width = su.film.pixels.width(), height = su.film.pixels.height();
    // Wider perturbations than the defaults: more flow between bins and
    // density ratios D(y) / D(x) further from 1 (balance must hold for any range).
    pmlt::MutationSettings ms;
    ms.maxDepth = su.maxDepth;
    ms.lensR2 = lensRange * Float(width);
    ms.theta2 = 0.4;
    EmbreeManifoldScene mscene(*su.job.scene);
    ms.mscene = &mscene;
    const pmlt::Mutator mut(su.ctx, su.film, ms);
    Arena arena, propArena;
    Balance bal;
    for (int k = 0; k < samples; ++k) {
        RNG rng(Hash(seed, uint64_t(k)));
        BidirSample smp;
        if (!smp.make(su, rng, arena)) continue;
        // This sample's contributions per (type, naive, ordered bin pair).
        std::map<std::tuple<int, int, int, int>, double> local;
        for (int t = 1; t <= smp.nC; ++t)
            for (int s = 0; s <= smp.nL; ++s) {
                if ((s == 1 && t == 1) || s + t - 2 > su.maxDepth) continue;
                const ConnectSamples cu = Numbers(rng);
                ConnectResult r;
                if (!ConnectBDPT(su.ctx, smp.light(s), smp.camera(t), s, t, cu, &r)) continue;
                if (r.splat && !su.film.contains(r.pRaster)) continue;
                const double w = r.L.y();
                if (!(w > 0)) continue;
                pmlt::State x;
                if (!pmlt::StrategyPath(su.ctx, smp.light(s), smp.camera(t), s, t, cu, &x.x)) continue;
                pmlt::BuildBSDFs(su.ctx, x.x, arena, &x.bsdf);
                if (!pmlt::Evaluate(su.ctx, su.film, x.x, x.bsdf.data(), &x.e)) {
                    ADD_FAILURE() << "a bdpt strategy's path does not evaluate";
                    continue;
                }
                for (pmlt::MutationType mt : types)
                    for (int type = int(mt), rep = 0; rep < kRepeats[type]; ++rep) {
                    RNGSampler u(rng);
                    pmlt::State y;
                    double ratio = 0;
                    if (mut.propose(pmlt::MutationType(type), x, u, propArena, &y, &ratio) !=
                        pmlt::ProposalResult::Proposed) {
                        propArena.reset();
                        continue;
                    }
                    const double a = std::min(1.0, ratio);
                    ++bal.proposals[type];
                    const bool byLength = type == int(pmlt::MutationType::Bidirectional);
                    const int A = Bin(x, byLength, width, height), B = Bin(y, byLength, width, height);
                    if (A != B) {
                        const double naive = std::min(1.0, double(y.e.I) / double(x.e.I));
                        local[{type, 0, A, B}] += w * a;
                        local[{type, 1, A, B}] += w * naive;
                    }
                    propArena.reset();
                    }
            }
        // D_k of every pair this sample touched (others add 0 and count as zeros).
        std::map<std::tuple<int, int, int, int>, std::pair<double, double>> pairD;
        for (const auto &[key, v] : local) {
            auto [type, naive, A, B] = key;
            if (A < B) pairD[{type, naive, A, B}].first += v;
            else pairD[{type, naive, B, A}].second += v;
        }
        for (const auto &[key, fb] : pairD) {
            auto [type, naive, A, B] = key;
            Flow &f = bal.flows[size_t(type)][size_t(naive)][{A, B}];
            const double d = fb.first - fb.second;
            f.s1 += d;
            f.s2 += d * d;
            f.forward += fb.first > 0;
            f.backward += fb.second > 0;
        }
        arena.reset();
    }
    return bal;
}

// Student's t per pair over `samples` iid D_k (zeros included).
Result TTest(const std::map<std::pair<int, int>, Flow> &flows, int samples, double alphaPerPair) {
    Result r;
    for (const auto &[pair, f] : flows) {
        // Both directions seen often enough for the mean's normal limit (a
        // flow seen only one way is a rare event of large weight the other way).
        if (std::min(f.forward, f.backward) < kMinSamples) continue;
        ++r.pairs;
        const double n = samples, mean = f.s1 / n;
        const double var = (f.s2 - n * mean * mean) / (n - 1);
        const double t = mean / std::sqrt(var / n);
        const double margin = std::abs(t) / conformance::StudentCritical(alphaPerPair, n - 1);
        if (margin > r.maxMargin) {
            r.maxMargin = margin;
            r.worst = "bins " + std::to_string(pair.first) + " <-> " + std::to_string(pair.second) + ": t " +
                      std::to_string(t) + " over " + std::to_string(f.forward) + " + " +
                       std::to_string(f.backward) + " samples";
        }
    }
    return r;
}

// A glass sphere above a diffuse floor under a small light: caustics seen
// directly (E D S S L: caustic perturbation) and through the sphere
// (E S S D S S L: multi-chain), the floor through the sphere (lens).
std::string CausticScene() {
    return "LookAt 0.3 1.0 1.4  0.3 0.2 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]\n"
           "Sampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n"
           "Film \"image\" \"integer xresolution\" [24] \"integer yresolution\" [24] "
           "\"string filename\" [\"unused.exr\"]\nIntegrator \"pmlt\" \"integer maxdepth\" [5]\nWorldBegin\n"
           "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [40 40 40]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
           "[-0.6 1.2 -0.15  -0.3 1.2 -0.15  -0.3 1.2 0.15  -0.6 1.2 0.15]\nAttributeEnd\n"
           "Material \"matte\" \"rgb Kd\" [0.7 0.7 0.7]\n"
           "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
           "[-2 0 -2  -2 0 2  2 0 2  2 0 -2]\n"
           "AttributeBegin\nMaterial \"glass\"\nTranslate 0 0.55 0\nShape \"sphere\" \"float radius\" [0.3]\n"
           "AttributeEnd\nWorldEnd\n";
}

struct Case {
    const char *scene;
    int samples;
    Float lensRange;  // largest film offset / film width
    std::vector<pmlt::MutationType> types;  // the mutations with enough flow in this scene
};

TEST(PMLTMutation, DetailedBalance) {
    const std::vector<std::pair<Case, std::string>> cases = {
        {{"specular-box", 80000, 0.5, {pmlt::MutationType::Bidirectional, pmlt::MutationType::Manifold}},
         ConformanceScene("specular-box")},
        {{"caustic", 150000, 0.25,
          {pmlt::MutationType::Lens, pmlt::MutationType::Caustic, pmlt::MutationType::MultiChain}},
         CausticScene()}};
    std::vector<Balance> bals;
    int pairs = 0;
    for (const auto &[c, text] : cases) {
        bals.push_back(Measure(text, c.samples, 0xba1a, c.types, c.lensRange));
        for (pmlt::MutationType type : c.types)
            for (const auto &[p, f] : bals.back().flows[size_t(type)][0])
                pairs += std::min(f.forward, f.backward) >= kMinSamples;
    }
    ASSERT_GT(pairs, 0);
    const double alpha = 1e-3 / pairs;
    for (size_t i = 0; i < cases.size(); ++i)
        for (pmlt::MutationType type : cases[i].first.types) {
            const std::string name = std::string(cases[i].first.scene) + " " + pmlt::MutationName(type);
            const Balance &bal = bals[i];
            const int samples = cases[i].first.samples;
            const Result ok = TTest(bal.flows[size_t(type)][0], samples, alpha);
            const Result naive = TTest(bal.flows[size_t(type)][1], samples, alpha);
            std::cout << "[ balance ] " << name << ": " << bal.proposals[int(type)] << " proposals, " << ok.pairs
                      << " bin pairs tested, largest |t|/critical " << ok.maxMargin << " (" << ok.worst
                      << "); without T: " << naive.maxMargin << " (" << naive.worst << ")\n";
            EXPECT_GT(ok.pairs, 0) << name << ": no bin pair had enough flow to test";
            EXPECT_LE(ok.maxMargin, 1) << name << ": detailed balance violated, " << ok.worst;
            // The manifold perturbation's density ratios stay within a few percent
            // of 1 over the film offsets whose walks succeed (measured: the kernel
            // without them reaches |t|/critical 0.43, like the correct one): this
            // test cannot resolve that error, so its power is not claimed there.
            // Its chain factor J is the manifold library's ChainSolidAnglePerArea
            // (tested against finite differences in tests/gbdpt), the other
            // factors are the densities checked by PMLTPath.
            if (type == pmlt::MutationType::Manifold) continue;
            EXPECT_GT(naive.maxMargin, 1) << name << ": the test cannot see a kernel without its transition densities";
        }
}

}  // namespace
}  // namespace gradus::pmlt_test
