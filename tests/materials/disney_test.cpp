// pbrt-v3's "disney" material: chi-square of sample() against pdf() for several
// parameter sets, sample/eval consistency, white-furnace energy (<= 1 where the model
// conserves energy, against a quadrature of f |cos| where it does not), reciprocity,
// the diffuse lobes against Burley 2012's closed form, roughness reporting, parameter
// handling (defaults against pbrt-v3's literals, out-of-range texture values against the
// bounds written out) and located errors.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/arena.h"
#include "materials/disney.h"
#include "materials/material.h"
#include "parser/scene_desc.h"
#include "common/chi2_test.h"
#include "material_test_util.h"

using namespace gradus;
using namespace gradus::mattest;

namespace {

struct Config {
    std::string name;
    DisneyParams p;
};

DisneyParams Base(Spectrum color) {
    DisneyParams p;
    p.color = color;
    return p;
}

// Parameter sets for the statistical tests (roughness >= 0.3: the chi-square bins and
// the midpoint-rule expectations cannot resolve the peaks of alpha ~ 0.01 lobes).
std::vector<Config> Configs() {
    std::vector<Config> cs;
    cs.push_back({"default", DisneyParams()});
    {  // the zoo's first sphere, with a gloss the bins resolve
        DisneyParams p = Base(Spectrum(0.8, 0.3, 0.2));
        p.roughness = 0.35;
        p.clearcoat = 1;
        p.clearcoatGloss = 0.5;
        p.sheen = 0.5;
        cs.push_back({"clearcoatSheen", p});
    }
    {
        DisneyParams p = Base(Spectrum(0.9, 0.75, 0.4));
        p.metallic = 1;
        p.roughness = 0.45;
        p.anisotropic = 0.6;
        cs.push_back({"anisoMetal", p});
    }
    {
        DisneyParams p = Base(Spectrum(0.9, 0.95, 1.0));
        p.specTrans = 0.8;
        p.roughness = 0.45;
        p.eta = 1.5;
        cs.push_back({"spectrans", p});
    }
    {
        DisneyParams p = Base(Spectrum(0.7, 0.8, 0.6));
        p.thin = true;
        p.specTrans = 0.5;
        p.diffTrans = 0.6;
        p.flatness = 0.5;
        p.roughness = 0.6;
        p.eta = 1.3;
        p.sheen = 0.3;
        p.specularTint = 0.5;
        cs.push_back({"thin", p});
    }
    {
        DisneyParams p = Base(Spectrum(0.5, 0.6, 0.9));
        p.metallic = 0.5;
        p.specTrans = 0.3;
        p.roughness = 0.5;
        p.anisotropic = 0.9;
        p.eta = 1.8;
        p.clearcoat = 0.5;
        p.clearcoatGloss = 0.2;
        cs.push_back({"mixedAniso", p});
    }
    return cs;
}

// Directional albedo by sampling (importance mode: no radiance compression across
// refraction), per channel: mean and standard error.
struct Albedo {
    Spectrum mean, se;
};
Albedo EstimateAlbedo(const BxDF &b, const Vec3 &wo, int n, uint64_t seed) {
    RNG rng(seed);
    Spectrum sum(0), sum2(0);
    for (int i = 0; i < n; ++i) {
        BSDFSample s;
        Spectrum w(0);
        if (b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Importance, &s))
            w = s.f * (AbsCosTheta(s.wi) / s.pdf);
        sum += w;
        sum2 += w * w;
    }
    Albedo a;
    a.mean = sum / n;
    for (int k = 0; k < 3; ++k) a.se[k] = std::sqrt(std::max(0.0, sum2[k] / n - a.mean[k] * a.mean[k]) / n);
    return a;
}

}  // namespace

// Every config x direction is one test; Sidak-corrected so that correct code fails the
// whole suite with probability 1% (fixed seeds: deterministic).
TEST(Disney, ChiSquareSampleMatchesPdf) {
    auto cs = Configs();
    auto wos = Wos();
    double alpha = chi2::SidakAlpha(0.01, int(cs.size() * wos.size()));
    int idx = 0;
    for (const Config &c : cs) {
        DisneyBxDF b(c.p);
        for (const Vec3 &wo : wos) {
            auto r = BxDFChi2(b, wo, 100000, 4000 + idx++, alpha, 8, 256);
            EXPECT_TRUE(r.pass) << c.name << " wo=" << wo << ": " << r.message;
        }
    }
}

// The chi-square test has the power to see a wrong pdf: reporting the anisotropic
// metal's pdf with the two alphas swapped fails it.
TEST(Disney, ChiSquareDetectsSwappedAnisotropy) {
    DisneyParams p = Base(Spectrum(0.9));
    p.metallic = 1;
    p.roughness = 0.45;
    p.anisotropic = 0.6;
    DisneyBxDF b(p);
    struct Swapped : BxDF {
        const BxDF &b;
        explicit Swapped(const BxDF &x) : BxDF(x.flags()), b(x) {}
        Spectrum f(const Vec3 &o, const Vec3 &i, TransportMode m) const override { return b.f(o, i, m); }
        bool sample(const Vec3 &o, Float uc, Point2 u, TransportMode m, BSDFSample *s) const override {
            return b.sample(o, uc, u, m, s);
        }
        Float pdf(const Vec3 &o, const Vec3 &i, TransportMode m) const override {
            auto sw = [](const Vec3 &v) { return Vec3(v.y, v.x, v.z); };  // x <-> y: alphas swapped
            return b.pdf(sw(o), sw(i), m);
        }
        Float roughness() const override { return b.roughness(); }
    } bad(b);
    auto r = BxDFChi2(bad, Dir(0.5, 0.7), 100000, 99, chi2::SidakAlpha(0.01, 24), 8, 256);
    EXPECT_FALSE(r.pass) << r.message;
}

// sample() reports exactly f() and pdf() at the sampled direction, pdfRev = pdf(wi, wo),
// and the flags of the sampled side.
TEST(Disney, SampleConsistentWithEval) {
    for (const Config &c : Configs()) {
        DisneyBxDF b(c.p);
        RNG rng(7);
        for (const Vec3 &wo : Wos())
            for (int i = 0; i < 2000; ++i)
                for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                    BSDFSample s;
                    if (!b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, mode, &s)) continue;
                    ASSERT_FALSE(s.isSpecular()) << c.name;
                    Spectrum f = b.f(wo, s.wi, mode);
                    TransportMode rev =
                        mode == TransportMode::Radiance ? TransportMode::Importance : TransportMode::Radiance;
                    for (int k = 0; k < 3; ++k) ASSERT_NEAR(s.f[k], f[k], 1e-9 * (1 + f[k])) << c.name;
                    ASSERT_NEAR(s.pdf, b.pdf(wo, s.wi, mode), 1e-9 * (1 + s.pdf)) << c.name;
                    ASSERT_NEAR(s.pdfRev, b.pdf(s.wi, wo, rev), 1e-9 * (1 + s.pdfRev)) << c.name;
                    ASSERT_EQ(bool(s.flags & BSDF_TRANSMISSION), s.wi.z * wo.z < 0) << c.name;
                    // Rough refraction reports eta_wi / eta_wo; diffuse transmission does not bend.
                    if ((s.flags & BSDF_TRANSMISSION) && (s.flags & BSDF_GLOSSY))
                        ASSERT_EQ(s.eta, wo.z > 0 ? c.p.eta : 1 / c.p.eta) << c.name;
                    if (s.flags & BSDF_DIFFUSE) ASSERT_EQ(s.eta, 1) << c.name;
                }
    }
}

// White furnace. Configurations where pbrt-v3's Disney model conserves energy: metal
// (a Fresnel-weighted GGX), spectrans = 1 (a rough dielectric),
// and the diffuse lobes alone (eta = 1 removes the specular lobe) at roughness <= 0.25
// (then FD90 = 0.5 + 2 r cos^2 <= 1); thin diffuse reflection + transmission only at
// roughness 0 (pbrt-v3 does not scale the retro-reflection lobe by 1 - difftrans/2, so the
// thin sum exceeds 1 at grazing angles otherwise: see the next test).
// Estimated albedo <= 1 + 4 se per channel: a one-sided z-test with false-positive rate
// 3.2e-5 per test (< 0.1% over the suite). Power: 4 se < 0.015 everywhere, so an energy
// gain of 1.5% on a lossless case would be detected; the near-lossless rough dielectric at
// normal incidence checks that a 1% gain there exceeds the bound.
TEST(Disney, WhiteFurnaceAtMostOneWhereConserving) {
    std::vector<Config> cs;
    {
        DisneyParams p = Base(Spectrum(1));
        p.metallic = 1;
        p.roughness = 0.5;
        cs.push_back({"metal", p});
        p.anisotropic = 0.8;
        cs.push_back({"anisoMetal", p});
    }
    for (bool thin : {false, true}) {
        DisneyParams p = Base(Spectrum(1));
        p.specTrans = 1;
        p.roughness = 0.3;
        p.thin = thin;
        p.diffTrans = 0;  // pbrt-v3 adds thin diffuse transmission whatever spectrans
        cs.push_back({thin ? "thinDielectric" : "dielectric", p});
    }
    for (Float r : {0.0, 0.25}) {
        DisneyParams p = Base(Spectrum(1));
        p.eta = 1;
        p.roughness = r;
        cs.push_back({"diffuse" + std::to_string(r), p});
    }
    {
        DisneyParams p = Base(Spectrum(1));
        p.eta = 1;
        p.roughness = 0;
        p.thin = true;
        p.flatness = 0.5;
        cs.push_back({"thinDiffuse", p});
    }
    for (const Config &c : cs) {
        DisneyBxDF b(c.p);
        for (const Vec3 &wo : Wos()) {
            Albedo a = EstimateAlbedo(b, wo, 100000, 21);
            for (int k = 0; k < 3; ++k) {
                EXPECT_LE(a.mean[k], 1 + 4 * a.se[k]) << c.name << " wo=" << wo;
                EXPECT_LT(4 * a.se[k], 0.015) << c.name << " wo=" << wo << " (test power)";
            }
        }
    }
    // The rough dielectric is nearly lossless at normal incidence (single scattering
    // loses a little): a 1% gain would exceed 1.
    DisneyParams p = Base(Spectrum(1));
    p.specTrans = 1;
    p.roughness = 0.3;
    Albedo a = EstimateAlbedo(DisneyBxDF(p), Dir(0.95, 0.7), 100000, 5);
    EXPECT_GT(a.mean.g * 1.01, 1 + 4 * a.se.g) << a.mean.g;
}

// Where the model adds energy (pbrt-v3 sums the lobes: the diffuse base is not reduced by
// the specular Fresnel, sheen and clear coat add on top, Burley's retro-reflection exceeds
// 1 at grazing angles for roughness > 0.25 and, in thin mode, is not reduced by
// difftrans; thin mode adds the diffuse transmission difftrans/2 color even when spectrans
// or metallic leave no diffuse weight), the sampled albedo must still equal the
// quadrature of f |cos| (within 4 se + 0.005 integration allowance; a 2% error in the
// sample weights exceeds that), and the albedo above 1 is shown.
TEST(Disney, AlbedoMatchesQuadratureWhereNotConserving) {
    std::vector<Config> cs;
    {
        DisneyParams p = Base(Spectrum(1));
        p.roughness = 0.5;
        cs.push_back({"diffusePlusSpecular", p});
        p.sheen = 1;
        cs.push_back({"sheen", p});
        p.sheen = 0;
        p.clearcoat = 1;
        p.clearcoatGloss = 0.3;
        cs.push_back({"clearcoat", p});
        DisneyParams q = Base(Spectrum(1));
        q.eta = 1;
        q.roughness = 1;
        cs.push_back({"retroRough1", q});
        q.roughness = 0.25;
        q.thin = true;
        cs.push_back({"thinRetro", q});
        DisneyParams t = Base(Spectrum(1));
        t.specTrans = 1;
        t.roughness = 0.4;
        t.thin = true;  // difftrans 1: Lambertian transmission of color/2 on top of the dielectric
        cs.push_back({"thinDielectricDiffTrans", t});
    }
    for (const Config &c : cs) {
        DisneyBxDF b(c.p);
        double maxAlbedo = 0;
        for (const Vec3 &wo : Wos()) {
            Albedo a = EstimateAlbedo(b, wo, 100000, 33);
            Spectrum q = QuadratureAlbedo(b, wo, 400, 400);
            for (int k = 0; k < 3; ++k) {
                double tol = 4 * a.se[k] + 0.005;
                EXPECT_NEAR(a.mean[k], q[k], tol) << c.name << " wo=" << wo << " channel " << k;
                EXPECT_GT(std::abs(1.02 * a.mean[k] - q[k]), tol) << c.name << " (test power)";
            }
            maxAlbedo = std::max(maxAlbedo, q.g);
        }
        EXPECT_GT(maxAlbedo, 1) << c.name << ": expected to add energy at some wo";
    }
}

// Reflection-only configurations are reciprocal in both modes; with transmission the
// adjoint relation f(wo, wi) = f*(wi, wo) holds (Veach 1997, Sec. 3.7).
TEST(Disney, Reciprocity) {
    RNG rng(3);
    for (const Config &c : Configs()) {
        DisneyBxDF b(c.p);
        bool reflectionOnly = !(b.flags() & BSDF_TRANSMISSION);
        for (int i = 0; i < 4000; ++i) {
            Float c1 = 2 * rng.uniform() - 1, c2 = 2 * rng.uniform() - 1;
            Vec3 wo = Dir(c1, 2 * Pi * rng.uniform()), wi = Dir(c2, 2 * Pi * rng.uniform());
            if (std::abs(wo.z) < 1e-3 || std::abs(wi.z) < 1e-3) continue;
            Spectrum a = b.f(wo, wi, TransportMode::Radiance);
            Spectrum adj = b.f(wi, wo, TransportMode::Importance);
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], adj[k], 1e-9 * (1 + a[k])) << c.name << wo << wi;
            if (reflectionOnly) {
                Spectrum sw = b.f(wi, wo, TransportMode::Radiance);
                for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], sw[k], 1e-9 * (1 + a[k])) << c.name;
            }
        }
        if (c.name == "clearcoatSheen" || c.name == "anisoMetal" || c.name == "default") EXPECT_TRUE(reflectionOnly);
    }
}

// eta = 1, metallic 0, no spectrans/sheen/clearcoat: f is Burley 2012's diffuse (Sec. 5.3),
// f = baseColor/pi (1 + (FD90 - 1)(1 - cos l)^5)(1 + (FD90 - 1)(1 - cos v)^5),
// FD90 = 0.5 + 2 roughness cos^2(theta_d), theta_d the angle between l and the half vector.
TEST(Disney, PureDiffuseIsBurleyClosedForm) {
    const Spectrum color(0.8, 0.5, 0.2);
    const std::pair<Vec3, Vec3> pairs[] = {
        {Dir(1, 0), Dir(1, 0)}, {Dir(0.8, 0.3), Dir(0.6, 0.3 + Pi)}, {Dir(0.9, 0.1), Dir(0.4, 2.0)},
        {Dir(0.3, 1.0), Dir(0.95, 5.0)}, {Dir(0.15, 0.0), Dir(0.2, 0.1)},  // near retro-reflection, grazing
    };
    for (double r : {0.0, 0.3, 0.7, 1.0}) {
        DisneyParams p = Base(color);
        p.eta = 1;
        p.roughness = r;
        DisneyBxDF b(p);
        for (auto [v, l] : pairs) {
            Vec3 h = Normalize(v + l);
            double cd = Dot(l, h);
            double fd90 = 0.5 + 2 * r * cd * cd;
            double burley = (1 + (fd90 - 1) * std::pow(1 - l.z, 5)) * (1 + (fd90 - 1) * std::pow(1 - v.z, 5)) / Pi;
            for (int k = 0; k < 3; ++k) {
                EXPECT_NEAR(b.f(v, l, TransportMode::Radiance)[k], color[k] * burley, 1e-12) << r << v << l;
                // From below the surface: the mirrored pair.
                Vec3 vb(v.x, v.y, -v.z), lb(l.x, l.y, -l.z);
                EXPECT_NEAR(b.f(vb, lb, TransportMode::Radiance)[k], color[k] * burley, 1e-12);
            }
            EXPECT_TRUE(b.f(v, Vec3(l.x, l.y, -l.z), TransportMode::Radiance).isBlack());
        }
    }
}

// Sheen and clear coat against Burley 2012 (Sec. 5.3, Appendix B) at one pair:
// sheen = sheen * Csheen (1 - cos theta_d)^5, clear coat = 0.25 cc D_GTR1 F G / (4 cos cos).
TEST(Disney, SheenAndClearcoatClosedForm) {
    Vec3 v = Dir(0.7, 0.2), l = Dir(0.35, 2.9);
    Vec3 h = Normalize(v + l);
    double cd = Dot(l, h), w = std::pow(1 - cd, 5);
    DisneySheen sheen(Spectrum(0.3, 0.6, 0.9));
    EXPECT_NEAR(sheen.f(v, l, TransportMode::Radiance).b, 0.9 * w, 1e-14);
    for (double gloss : {0.0, 0.5, 1.0}) {
        double a = (1 - gloss) * 0.1 + gloss * 0.001, a2 = a * a;
        double D = (a2 - 1) / (Pi * std::log(a2) * (1 + (a2 - 1) * h.z * h.z));
        double F = 0.04 + 0.96 * w;
        auto G1 = [](double c) {  // Smith GGX masking with alpha 0.25
            double t2 = (1 - c * c) / (c * c);
            return 2 / (1 + std::sqrt(1 + 0.0625 * t2));
        };
        double expect = 0.25 * 0.8 * D * F * G1(v.z) * G1(l.z) / (4 * v.z * l.z);
        DisneyClearcoat cc(0.8, a);
        EXPECT_NEAR(cc.f(v, l, TransportMode::Radiance).r, expect, 1e-12 * expect) << gloss;
        EXPECT_NEAR(cc.roughness(), a, 1e-15);
    }
}

// Specular: a white metal has F = 1 (Schlick with R0 = 1), so f = D G / (4 cos o cos i)
// with the anisotropic GGX D (Burley 2012, Appendix B, Eq. 13; ax = r^2 / aspect,
// ay = r^2 aspect, aspect = sqrt(1 - 0.9 anisotropic)) and the height-correlated Smith G
// that pbrt-v3's lobes evaluate. The dielectric lobe's Fresnel is the exact one at eta.
TEST(Disney, SpecularClosedForm) {
    const double r = 0.6, an = 0.7, aspect = std::sqrt(1 - 0.9 * an);
    const double ax = r * r / aspect, ay = r * r * aspect;
    auto D = [&](const Vec3 &h) { return 1 / (Pi * ax * ay * Sqr(Sqr(h.x / ax) + Sqr(h.y / ay) + h.z * h.z)); };
    auto Lambda = [&](const Vec3 &w) {
        return (-1 + std::sqrt(1 + (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / (w.z * w.z))) / 2;
    };
    DisneyParams p = Base(Spectrum(1));
    p.metallic = 1;
    p.roughness = r;
    p.anisotropic = an;
    DisneyBxDF metal(p);
    p.metallic = 0;
    p.color = Spectrum(0);  // only the specular lobe has weight
    p.eta = 1.7;
    DisneyBxDF dielectric(p);
    const std::pair<Vec3, Vec3> pairs[] = {{Dir(0.8, 0.3), Dir(0.6, 0.3 + Pi)}, {Dir(0.9, 0.1), Dir(0.4, 2.0)},
                                           {Dir(0.3, 1.0), Dir(0.95, 5.0)}};
    for (auto [v, l] : pairs) {
        Vec3 h = Normalize(v + l);
        double expect = D(h) / (1 + Lambda(v) + Lambda(l)) / (4 * v.z * l.z);
        EXPECT_NEAR(metal.f(v, l, TransportMode::Radiance).g, expect, 1e-10 * expect) << v << l;
        // Exact dielectric Fresnel at cos(theta_d), eta 1.7.
        double c = Dot(l, h), g = std::sqrt(1.7 * 1.7 - 1 + c * c);
        double F = 0.5 * Sqr((g - c) / (g + c)) * (1 + Sqr((c * (g + c) - 1) / (c * (g - c) + 1)));
        EXPECT_NEAR(dielectric.f(v, l, TransportMode::Radiance).g, F * expect, 1e-10 * expect) << v << l;
    }
}

// Lowest roughness: BxDF::roughness() is the lowest alpha among its lobes, and the
// material's minRoughness() reports the same for constant parameters.
TEST(Disney, RoughnessReported) {
    struct Case {
        const char *params;
        double expect;
    } cases[] = {
        {"", 0.25},                                            // roughness 0.5: alpha 0.25
        {"\"float roughness\" [0]", 0.001},                    // pbrt-v3's alpha floor
        {"\"float roughness\" [0.5] \"float anisotropic\" [1]", 0.25 * std::sqrt(0.1)},
        {"\"float clearcoat\" [1] \"float clearcoatgloss\" [0.5]", 0.0505},
        {"\"float clearcoat\" [1]", 0.001},
        {"\"float spectrans\" [1] \"bool thin\" \"true\" \"float eta\" [1.2]", Sqr((0.65 * 1.2 - 0.35) * 0.5)},
        {"\"float spectrans\" [1] \"float eta\" [1.0]", 0},  // smooth pass-through
        {"\"float metallic\" [1] \"float roughness\" [0.8]", 0.64},
    };
    for (auto &c : cases) {
        MaterialDesc d = ParseMaterial(std::string("Material \"disney\" ") + c.params);
        auto m = CreateMaterial(d, {}, {});
        d.params.checkUnused("Material");
        EXPECT_NEAR(m->minRoughness(), c.expect, 1e-12) << c.params;
        SurfaceInteraction si = FlatHit();
        Arena arena;
        BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
        ASSERT_TRUE(b) << c.params;
        EXPECT_NEAR(b.roughness(), c.expect, 1e-12) << c.params;
        EXPECT_EQ(b.roughnessClass(kDefaultShiftThreshold) == RoughnessClass::Smooth, c.expect == 0) << c.params;
        EXPECT_FALSE(m->hasTextures());
    }
}

// Textured parameters: minRoughness falls back to a lower bound valid at every point
// (0.001, pbrt-v3's alpha floor; 0 when a textured eta may pass straight through), values
// outside the valid ranges are clamped per point (no NaN), and hasTextures() reports it.
TEST(Disney, TexturedParameters) {
    struct Ramp : FloatTexture {  // u * scale + offset: leaves [0, 1] on purpose
        Float scale, offset;
        Ramp(Float s, Float o) : scale(s), offset(o) {}
        Float evaluate(const SurfaceInteraction &si) const override { return si.uv.x * scale + offset; }
    };
    NamedTextures tex;
    tex.floats["r"] = std::make_shared<Ramp>(2, -0.5);   // roughness in [-0.5, 1.5]
    tex.floats["e"] = std::make_shared<Ramp>(3, -1);     // eta in [-1, 2]
    tex.floats["a"] = std::make_shared<Ramp>(3, -1);     // anisotropic in [-1, 2]
    auto make = [&](const std::string &params) {
        MaterialDesc d = ParseMaterial("Material \"disney\" " + params);
        auto m = CreateMaterial(d, tex, {});
        d.params.checkUnused("Material");
        return m;
    };
    auto m1 = make("\"texture roughness\" \"r\" \"texture anisotropic\" \"a\"");
    EXPECT_EQ(m1->minRoughness(), 0.001);
    EXPECT_TRUE(m1->hasTextures());
    auto m2 = make("\"texture eta\" \"e\" \"float spectrans\" [0.5]");
    EXPECT_EQ(m2->minRoughness(), 0);
    auto m3 = make("\"texture eta\" \"e\" \"texture roughness\" \"r\" \"texture anisotropic\" \"a\" "
                   "\"float spectrans\" [0.5] \"float clearcoat\" [1] \"bool thin\" \"true\"");
    for (auto *m : {m1.get(), m2.get(), m3.get()}) {
        for (int i = 0; i <= 20; ++i) {
            SurfaceInteraction si = FlatHit();
            si.uv = Point2(i / 20.0, 0.5);
            Arena arena;
            BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
            ASSERT_TRUE(b);
            EXPECT_GE(b.roughness(), m->minRoughness());
            RNG rng(i);
            for (int k = 0; k < 200; ++k) {
                Vec3 wo = Dir(2 * rng.uniform() - 1, 2 * Pi * rng.uniform());
                BSDFSample s;
                if (b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Radiance, &s)) {
                    ASSERT_TRUE(s.f.isFinite() && s.pdf > 0 && std::isfinite(s.pdf)) << i;
                    Spectrum f = b.f(wo, s.wi);
                    ASSERT_TRUE(f.isFinite() && f.r >= 0) << i;
                }
            }
        }
    }
}

// The zoo scene's parameter sets are consumed, and the refracting sphere reports its eta.
TEST(Disney, ZooParameterSetsAndDefaults) {
    const char *sets[] = {
        "\"rgb color\" [0.8 0.3 0.2] \"float metallic\" [0] \"float roughness\" [0.35] \"float clearcoat\" [1] "
        "\"float clearcoatgloss\" [0.9] \"float sheen\" [0.5]",
        "\"rgb color\" [0.9 0.75 0.4] \"float metallic\" [1] \"float roughness\" [0.25] \"float anisotropic\" [0.6]",
        "\"rgb color\" [0.9 0.95 1.0] \"float spectrans\" [0.8] \"float roughness\" [0.1] \"float eta\" [1.5] "
        "\"bool thin\" \"false\"",
        "\"float speculartint\" [0.2] \"float sheentint\" [0.1] \"float flatness\" [0.3] \"float difftrans\" [0.4] "
        "\"rgb scatterdistance\" [0 0 0]",
    };
    for (const char *s : sets) {
        MaterialDesc d = ParseMaterial(std::string("Material \"disney\" ") + s);
        auto m = CreateMaterial(d, {}, {});
        EXPECT_NO_THROW(d.params.checkUnused("Material")) << s;
    }
    MaterialDesc d = ParseMaterial(std::string("Material \"disney\" ") + sets[2]);
    auto m = CreateMaterial(d, {}, {});
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
    EXPECT_EQ(b.eta(), 1.5);
    EXPECT_TRUE(b.flags() & BSDF_TRANSMISSION);
    MaterialDesc dd = ParseMaterial("Material \"disney\"");
    auto md = CreateMaterial(dd, {}, {});
    SurfaceInteraction si2 = FlatHit();
    EXPECT_EQ(md->getBSDF(si2, arena, TransportMode::Radiance).eta(), 1);  // no transmission by default
}

namespace {

// f and pdf of two materials at a fixed set of direction pairs (both hemispheres,
// both transport modes): bit-identical, or (when differ is set) not identical.
void ExpectSameScattering(const std::shared_ptr<Material> &a, const std::shared_ptr<Material> &b,
                          const std::string &what, bool differ = false) {
    Arena arena;
    SurfaceInteraction sa = FlatHit(), sb = FlatHit();
    const BSDF ba = a->getBSDF(sa, arena, TransportMode::Radiance), bb = b->getBSDF(sb, arena, TransportMode::Radiance);
    ASSERT_TRUE(ba && bb) << what;
    bool same = ba.eta() == bb.eta();
    for (Float co : {0.9, 0.45, -0.3})
        for (Float ci : {0.8, 0.2, -0.6, -0.95})
            for (Float phi : {0.4, 2.5})
                for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                    const Vec3 wo = Dir(co, 1.1), wi = Dir(ci, 1.1 + phi);
                    const Spectrum fa = ba.f(wo, wi, mode), fb = bb.f(wo, wi, mode);
                    same = same && fa.r == fb.r && fa.g == fb.g && fa.b == fb.b &&
                           ba.pdf(wo, wi, mode) == bb.pdf(wo, wi, mode);
                }
    EXPECT_EQ(same, !differ) << what;
}

std::shared_ptr<Material> Disney(const std::string &params, const NamedTextures &tex = {}) {
    MaterialDesc d = ParseMaterial("Material \"disney\" " + params);
    auto m = CreateMaterial(d, tex, {});
    d.params.checkUnused("Material");
    return m;
}

}  // namespace

// Defaults: pbrt-v3's CreateDisneyMaterial (materials/disney.cpp) reads color 0.5,
// metallic 0, eta 1.5, roughness 0.5, speculartint 0, anisotropic 0, sheen 0,
// sheentint 0.5, clearcoat 0, clearcoatgloss 1, spectrans 0, scatterdistance 0,
// thin false, flatness 0, difftrans 1. Each omitted parameter must scatter exactly as
// that literal written out, in a setting where the parameter shows (e.g. sheentint
// with sheen on), and differently from a nearby value (so the comparison can fail).
TEST(Disney, DefaultsArePbrtV3s) {
    struct Case {
        const char *context, *literal, *nearby;
    } cases[] = {
        {"", "\"rgb color\" [0.5 0.5 0.5]", "\"rgb color\" [0.55 0.5 0.5]"},
        {"", "\"float metallic\" [0]", "\"float metallic\" [0.1]"},
        {"", "\"float eta\" [1.5]", "\"float eta\" [1.45]"},
        {"", "\"float roughness\" [0.5]", "\"float roughness\" [0.45]"},
        // (the tint shows in the Schlick part of the Fresnel blend: metallic in (0, 1))
        {"\"rgb color\" [0.8 0.3 0.2] \"float metallic\" [0.5]", "\"float speculartint\" [0]",
         "\"float speculartint\" [0.1]"},
        {"", "\"float anisotropic\" [0]", "\"float anisotropic\" [0.1]"},
        {"", "\"float sheen\" [0]", "\"float sheen\" [0.1]"},
        {"\"rgb color\" [0.8 0.3 0.2] \"float sheen\" [1]", "\"float sheentint\" [0.5]", "\"float sheentint\" [0.4]"},
        {"", "\"float clearcoat\" [0]", "\"float clearcoat\" [0.1]"},
        {"\"float clearcoat\" [1]", "\"float clearcoatgloss\" [1]", "\"float clearcoatgloss\" [0.9]"},
        {"", "\"float spectrans\" [0]", "\"float spectrans\" [0.1]"},
        {"", "\"bool thin\" \"false\"", "\"bool thin\" \"true\""},
        {"\"bool thin\" \"true\"", "\"float flatness\" [0]", "\"float flatness\" [0.1]"},
        {"\"bool thin\" \"true\"", "\"float difftrans\" [1]", "\"float difftrans\" [0.9]"},
        {"", "\"rgb scatterdistance\" [0 0 0]", nullptr},  // > 0 is refused (see below)
    };
    for (const Case &c : cases) {
        const std::string ctx = c.context;
        auto omitted = Disney(ctx), literal = Disney(ctx + " " + c.literal);
        ExpectSameScattering(omitted, literal, ctx + " / " + c.literal);
        if (c.nearby) ExpectSameScattering(omitted, Disney(ctx + " " + c.nearby), ctx + " / " + c.nearby, true);
    }
}

// Out-of-range values (a texture may give them; constants are located errors) act as
// the nearest valid value, written here as a literal: [0, 1] for the weights, tints,
// gloss and anisotropy, >= 0 for roughness, sheen, clearcoat and the colour (pbrt-v3
// clamps the colour), [0.001, 1000] for eta.
TEST(Disney, OutOfRangeTextureValuesClamp) {
    struct Fixed : FloatTexture {  // a constant that is not a ConstantTexture (no range check)
        Float v;
        explicit Fixed(Float x) : v(x) {}
        Float evaluate(const SurfaceInteraction &) const override { return v; }
    };
    struct FixedColor : SpectrumTexture {
        Spectrum v;
        explicit FixedColor(Spectrum x) : v(x) {}
        Spectrum evaluate(const SurfaceInteraction &) const override { return v; }
    };
    // Settings in which the parameter shows (the tint through the Schlick part of the
    // metallic Fresnel blend).
    const char *tint = "\"rgb color\" [0.8 0.3 0.2] \"float metallic\" [0.5]",
               *sheen = "\"rgb color\" [0.8 0.3 0.2] \"float sheen\" [1]", *coat = "\"float clearcoat\" [1]",
               *thin = "\"bool thin\" \"true\"", *trans = "\"float spectrans\" [0.5]";
    struct Case {
        const char *context, *name;
        Float value;
        const char *literal, *inside;  // the bound, and a value just inside it
    } cases[] = {
        {"", "metallic", 1.7, "\"float metallic\" [1]", "\"float metallic\" [0.9]"},
        {"", "metallic", -0.4, "\"float metallic\" [0]", "\"float metallic\" [0.1]"},
        {"", "spectrans", 1.3, "\"float spectrans\" [1]", "\"float spectrans\" [0.9]"},
        {"", "spectrans", -0.2, "\"float spectrans\" [0]", "\"float spectrans\" [0.1]"},
        {"", "roughness", -0.3, "\"float roughness\" [0]", "\"float roughness\" [0.1]"},
        {tint, "speculartint", 2, "\"float speculartint\" [1]", "\"float speculartint\" [0.9]"},
        {tint, "speculartint", -1, "\"float speculartint\" [0]", "\"float speculartint\" [0.1]"},
        {"", "anisotropic", 1.5, "\"float anisotropic\" [1]", "\"float anisotropic\" [0.9]"},
        {"", "anisotropic", -0.5, "\"float anisotropic\" [0]", "\"float anisotropic\" [0.1]"},
        {"", "sheen", -1, "\"float sheen\" [0]", "\"float sheen\" [0.1]"},
        {sheen, "sheentint", 1.8, "\"float sheentint\" [1]", "\"float sheentint\" [0.9]"},
        {sheen, "sheentint", -0.8, "\"float sheentint\" [0]", "\"float sheentint\" [0.1]"},
        {"", "clearcoat", -2, "\"float clearcoat\" [0]", "\"float clearcoat\" [0.1]"},
        {coat, "clearcoatgloss", 1.5, "\"float clearcoatgloss\" [1]", "\"float clearcoatgloss\" [0.9]"},
        {coat, "clearcoatgloss", -1, "\"float clearcoatgloss\" [0]", "\"float clearcoatgloss\" [0.1]"},
        {thin, "flatness", 2, "\"float flatness\" [1]", "\"float flatness\" [0.9]"},
        {thin, "flatness", -2, "\"float flatness\" [0]", "\"float flatness\" [0.1]"},
        {thin, "difftrans", 3, "\"float difftrans\" [1]", "\"float difftrans\" [0.9]"},
        {thin, "difftrans", -1, "\"float difftrans\" [0]", "\"float difftrans\" [0.1]"},
        {trans, "eta", 5000, "\"float eta\" [1000]", "\"float eta\" [900]"},
        {trans, "eta", -1, "\"float eta\" [0.001]", "\"float eta\" [0.002]"},
    };
    for (const Case &c : cases) {
        NamedTextures tex;
        tex.floats["t"] = std::make_shared<Fixed>(c.value);
        const std::string ctx = c.context, what = ctx + " " + c.name + " " + std::to_string(c.value);
        auto textured = Disney(ctx + " \"texture " + c.name + "\" \"t\"", tex);
        ExpectSameScattering(textured, Disney(ctx + " " + c.literal), what + " / " + c.literal);
        // ... and the bound shows in this setting (the comparison can fail).
        ExpectSameScattering(textured, Disney(ctx + " " + c.inside), what + " / " + c.inside, true);
    }
    NamedTextures tex;
    tex.spectra["c"] = std::make_shared<FixedColor>(Spectrum(-0.5, 0.3, 1.2));
    ExpectSameScattering(Disney("\"texture color\" \"c\"", tex), Disney("\"rgb color\" [0 0.3 1.2]"),
                         "color (-0.5, 0.3, 1.2) / [0 0.3 1.2]");
    ExpectSameScattering(Disney("\"texture color\" \"c\"", tex), Disney("\"rgb color\" [0.05 0.3 1.2]"),
                         "color (-0.5, 0.3, 1.2) / [0.05 0.3 1.2]", true);
}

TEST(Disney, BadParametersAreLocatedErrors) {
    struct Case {
        const char *params, *name;
    } cases[] = {
        {"\"float roughness\" [-0.1]", "roughness"}, {"\"float eta\" [0]", "eta"},
        {"\"float eta\" [-1.5]", "eta"},             {"\"float metallic\" [1.5]", "metallic"},
        {"\"float anisotropic\" [-0.2]", "anisotropic"}, {"\"float clearcoat\" [-1]", "clearcoat"},
        {"\"float spectrans\" [2]", "spectrans"},
    };
    for (auto &c : cases) {
        MaterialDesc d = ParseMaterial(std::string("Material \"disney\"\n  ") + c.params);
        try {
            CreateMaterial(d, {}, {});
            ADD_FAILURE() << "no error for " << c.params;
        } catch (const Error &e) {
            std::string w = e.what();
            EXPECT_NE(w.find("test.pbrt:3:"), std::string::npos) << w;  // the parameter's own line
            EXPECT_NE(w.find(c.name), std::string::npos) << w;
        }
    }
    // The BSSRDF path is refused (located), except in thin mode, where pbrt-v3 ignores it.
    MaterialDesc d = ParseMaterial("Material \"disney\"\n \"rgb scatterdistance\" [0.1 0.2 0.3]");
    try {
        CreateMaterial(d, {}, {});
        ADD_FAILURE() << "scatterdistance accepted";
    } catch (const UnsupportedError &e) {
        EXPECT_NE(std::string(e.what()).find("test.pbrt:3:"), std::string::npos) << e.what();
    }
    MaterialDesc t = ParseMaterial("Material \"disney\" \"bool thin\" \"true\" \"rgb scatterdistance\" [0.1 0.2 0.3]");
    EXPECT_NO_THROW(CreateMaterial(t, {}, {}));
    // A misspelt parameter stays unused.
    MaterialDesc m = ParseMaterial("Material \"disney\" \"float roughnes\" [0.2]");
    CreateMaterial(m, {}, {});
    EXPECT_THROW(m.params.checkUnused("Material"), Error);
}

// Random (also out-of-range, as textures may give) parameters and directions, including
// grazing and exactly opposite pairs: f, pdf and samples stay finite and non-negative.
TEST(Disney, FiniteEverywhere) {
    RNG rng(17);
    for (int t = 0; t < 300; ++t) {
        DisneyParams p;
        auto u = [&](double lo, double hi) { return lo + (hi - lo) * rng.uniform(); };
        p.color = Spectrum(u(-0.2, 1.5), u(0, 1), u(0, 1));
        p.metallic = u(-0.1, 1.1);
        p.eta = t % 7 == 0 ? 1 : u(-0.5, 3);
        p.roughness = t % 5 == 0 ? 0 : u(-0.1, 1.2);
        p.specularTint = u(0, 1);
        p.anisotropic = u(-0.5, 1.5);
        p.sheen = u(0, 2);
        p.sheenTint = u(0, 1);
        p.clearcoat = u(0, 1);
        p.clearcoatGloss = u(-0.5, 1.5);
        p.specTrans = u(0, 1);
        p.flatness = u(0, 1);
        p.diffTrans = u(0, 2);
        p.thin = t % 2;
        DisneyBxDF b(p);
        for (int i = 0; i < 50; ++i) {
            Vec3 wo = Dir(i == 0 ? 1e-9 : u(-1, 1), u(0, 2 * Pi));
            Vec3 wi = i == 1 ? -wo : (i == 2 ? Vec3(-wo.x, -wo.y, wo.z) : Dir(u(-1, 1), u(0, 2 * Pi)));
            for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                Spectrum f = b.f(wo, wi, mode);
                Float pd = b.pdf(wo, wi, mode);
                ASSERT_TRUE(f.isFinite() && f.r >= 0 && f.g >= 0 && f.b >= 0) << t << " " << i;
                ASSERT_TRUE(std::isfinite(pd) && pd >= 0) << t << " " << i;
                BSDFSample s;
                if (b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, mode, &s)) {
                    ASSERT_TRUE(s.f.isFinite() && std::isfinite(s.pdf) && std::isfinite(s.pdfRev)) << t << " " << i;
                }
            }
        }
        ASSERT_TRUE(std::isfinite(b.roughness()));
    }
}
