// Helpers of the G-MLT tests: an integrator set up on a scene of the
// conformance table, the bdpt strategy paths of bidirectional samples, the
// glossy box and render helpers.
#pragma once
#include <stdexcept>
#include <string>

#include "integrators/gmlt/gmlt.h"
#include "mlt/unbiased_util.h"
#include "pmlt/pmlt_test_util.h"

namespace gradus::pmlt_test {

using ShiftStatus = pmlt::Mutator::ShiftStatus;

struct GMLTSetup {
    SceneSetup su;
    std::unique_ptr<GMLTIntegrator> gm;
    // threshold: the shift's "shiftthreshold", maxDepth: "maxdepth" of the
    // integrator and of the bdpt samples (negative: the defaults). "separated"
    // false: every path is shifted (these tests are the shift's; separated
    // light: test_separated.cpp).
    explicit GMLTSetup(const std::string &text, double threshold = -1, int maxDepth = -1) : su(text) {
        EntityDesc d;
        d.type = "gmlt";
        Param sep;
        sep.type = "bool";
        sep.name = "separated";
        sep.bools = {false};
        d.params.add(sep);
        auto add = [&](const char *type, const char *name, double v) {
            Param p;
            p.type = type;
            p.name = name;
            p.numbers = {v};
            d.params.add(p);
        };
        if (threshold >= 0) add("float", "shiftthreshold", threshold);
        if (maxDepth >= 0) {
            add("integer", "maxdepth", maxDepth);
            su.maxDepth = maxDepth;
        }
        gm = std::make_unique<GMLTIntegrator>(d);
        gm->preprocess(*su.job.scene, *su.job.film);
    }
    const BidirContext &ctx() const { return gm->bidirContext(); }
    const pmlt::FilmDomain &film() const { return gm->filmDomain(); }
};

// Calls fn(x, C) for every bdpt strategy path x of `samples` bidirectional
// samples with its MIS-weighted contribution C (the paths in `arena`, reset
// per sample); sampleDone(k) after sample k.
template <class Fn, class Done>
void ForEachStrategyPath(const GMLTSetup &g, int samples, uint64_t seed, Arena &arena, Fn fn, Done sampleDone) {
    for (int k = 0; k < samples; ++k) {
        RNG rng(Hash(seed, uint64_t(k)));
        BidirSample smp;
        if (smp.make(g.su, rng, arena)) {
            for (int t = 1; t <= smp.nC; ++t)
                for (int s = 0; s <= smp.nL; ++s) {
                    if ((s == 1 && t == 1) || s + t - 2 > g.su.maxDepth) continue;
                    const ConnectSamples cu = Numbers(rng);
                    ConnectResult r;
                    if (!ConnectBDPT(g.ctx(), smp.light(s), smp.camera(t), s, t, cu, &r)) continue;
                    if (r.splat && !g.film().contains(r.pRaster)) continue;
                    if (!(r.L.y() > 0)) continue;
                    pmlt::State x;
                    if (!pmlt::StrategyPath(g.ctx(), smp.light(s), smp.camera(t), s, t, cu, &x.x)) continue;
                    pmlt::BuildBSDFs(g.ctx(), x.x, arena, &x.bsdf);
                    if (!pmlt::Evaluate(g.ctx(), g.film(), x.x, x.bsdf.data(), &x.e)) continue;
                    fn(x, r.L);
                }
        }
        sampleDone(k);
        arena.reset();
    }
}

inline Point2 Shifted(const pmlt::State &x, int dir) {
    return Point2(x.e.pRaster.x + Float(kNeighbourOffsets[dir].x), x.e.pRaster.y + Float(kNeighbourOffsets[dir].y));
}

// The conformance table's specular box with near-specular glossy spheres
// (G-MLT Fig. 5a): the glass sphere rough and the metal sphere, both of
// microfacet alpha 0.05; the mirror stays ideal. With shiftthreshold 0.1 the
// shift treats both spheres as specular.
inline std::string GlossyBox() {
    std::string s = ConformanceScene("specular-box");
    const auto replace = [&](const std::string &from, const std::string &to) {
        const size_t at = s.find(from);
        if (at == std::string::npos) throw std::runtime_error("GlossyBox: \"" + from + "\" not in specular-box");
        s.replace(at, from.size(), to);
    };
    replace("Material \"glass\"", "Material \"glass\" \"float uroughness\" [0.05] \"float vroughness\" [0.05] "
                                  "\"bool remaproughness\" \"false\"");
    replace("Material \"metal\" \"float roughness\" [ 0.05 ]",
            "Material \"metal\" \"float roughness\" [ 0.05 ] \"bool remaproughness\" \"false\"");
    return s;
}
constexpr double kGlossyBoxThreshold = 0.1;

inline const GMLTIntegrator &G(const mlt_test::Rendered &r) {
    return dynamic_cast<const GMLTIntegrator &>(*r.integrator);
}

// A scene's text with another Integrator directive.
inline std::string WithIntegrator(const std::string &text, const std::string &integrator) {
    const size_t at = text.find("Integrator ");
    return text.substr(0, at) + integrator + text.substr(text.find('\n', at));
}

// Mean luminance of the whole image and of its 4 x 4 blocks.
inline std::vector<double> Blocks(const Image &img) {
    std::vector<double> v = {mlt_test::MeanLum(img)};
    for (int y = 0; y + 4 <= img.height(); y += 4)
        for (int x = 0; x + 4 <= img.width(); x += 4) v.push_back(mlt_test::MeanLum(img, x, y, x + 4, y + 4));
    return v;
}

// Runs (per-run block means) against bdpt's by Welch's t at `alpha`: no
// rejection as they are, rejection when scaled by 1.1 or 1 / 1.1 (power).
inline void ExpectAgreesWithBdpt(const std::string &tag, const std::string &name,
                                 const std::vector<std::vector<double>> &runs,
                                 const std::vector<std::vector<double>> &bdpt, double alpha) {
    const mlt_test::Comparison c = mlt_test::Compare(runs, bdpt, 1, alpha);
    std::cout << "[ " << tag << " ] " << name << " vs bdpt: |t|/crit " << c.maxMargin << " ("
              << c.describe.substr(0, c.describe.find(';')) << ")\n";
    EXPECT_LE(c.maxMargin, 1) << name << ": " << c.describe;
    for (double scale : {1.1, 1 / 1.1}) {
        const mlt_test::Comparison p = mlt_test::Compare(runs, bdpt, scale, alpha);
        std::cout << "[ " << tag << " ] " << name << " power x" << scale << ": " << p.maxMargin << "\n";
        EXPECT_GT(p.maxMargin, 1) << name << ": a " << scale << " bias is not detected";
    }
}

}  // namespace gradus::pmlt_test
