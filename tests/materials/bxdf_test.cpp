// Statistical and analytic tests of every BxDF: chi-square goodness of fit of
// sample() against pdf(), pdf mass, sample/eval consistency, reciprocity and
// energy (white furnace).
#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "materials/bxdfs.h"
#include "materials/gltf_pbr.h"
#include "common/chi2_test.h"
#include "material_test_util.h"

using namespace gradus;
using namespace gradus::mattest;

namespace {

struct Case {
    std::string name;
    std::function<std::unique_ptr<BxDF>()> make;
    bool reciprocal;  // f(wo, wi) == f(wi, wo) in both modes
    // False for models that are not energy-conserving by definition (glTF 2.0's
    // fresnel_mix weighs the diffuse base by 1 - F at the pair's own half vector):
    // the furnace test then checks the albedo against a quadrature of f |cos|.
    bool conserving = true;
};

MicrofacetDistribution GGX(Float ax, Float ay) { return {MicrofacetDistribution::TrowbridgeReitz, ax, ay}; }
MicrofacetDistribution Beck(Float ax, Float ay) { return {MicrofacetDistribution::Beckmann, ax, ay}; }

// A composite like "plastic": diffuse + rough dielectric-coated reflection.
struct Plastic : BxDF {
    LambertianReflection d{Spectrum(0.5)};
    MicrofacetReflection s;
    CompositeBxDF c;
    explicit Plastic(Float alpha) : BxDF(0), s(Spectrum(0.5), GGX(alpha, alpha), Fresnel::MakeDielectric(1.5)) {
        c.add(&d);
        c.add(&s, 3);
    }
    Spectrum f(const Vec3 &o, const Vec3 &i, TransportMode m) const override { return c.f(o, i, m); }
    bool sample(const Vec3 &o, Float uc, Point2 u, TransportMode m, BSDFSample *s) const override {
        return c.sample(o, uc, u, m, s);
    }
    Float pdf(const Vec3 &o, const Vec3 &i, TransportMode m) const override { return c.pdf(o, i, m); }
    Float roughness() const override { return c.roughness(); }
};

// Diffuse transmission + rough dielectric (pbrt-v3 "translucent").
struct Translucent : BxDF {
    LambertianReflection r{Spectrum(0.2)};
    LambertianTransmission t{Spectrum(0.2)};
    MicrofacetDielectric g;
    CompositeBxDF c;
    explicit Translucent(Float alpha) : BxDF(0), g(Spectrum(0.5), Spectrum(0.5), 1.5, GGX(alpha, alpha)) {
        c.add(&r);
        c.add(&t);
        c.add(&g);
    }
    Spectrum f(const Vec3 &o, const Vec3 &i, TransportMode m) const override { return c.f(o, i, m); }
    bool sample(const Vec3 &o, Float uc, Point2 u, TransportMode m, BSDFSample *s) const override {
        return c.sample(o, uc, u, m, s);
    }
    Float pdf(const Vec3 &o, const Vec3 &i, TransportMode m) const override { return c.pdf(o, i, m); }
    Float roughness() const override { return c.roughness(); }
};

std::vector<Case> Cases() {
    std::vector<Case> cs;
    cs.push_back({"lambert", [] { return std::make_unique<LambertianReflection>(Spectrum(0.7)); }, true});
    cs.push_back({"lambertT", [] { return std::make_unique<LambertianTransmission>(Spectrum(0.7)); }, true});
    cs.push_back({"orennayar20", [] { return std::make_unique<OrenNayar>(Spectrum(0.7), 20); }, true});
    for (Float a : {0.1, 0.3, 0.8}) {
        std::string s = std::to_string(a).substr(0, 3);
        cs.push_back({"ggx" + s, [a] {
                          return std::make_unique<MicrofacetReflection>(Spectrum(1), GGX(a, a), Fresnel::One());
                      }, true});
        cs.push_back({"beckmann" + s, [a] {
                          return std::make_unique<MicrofacetReflection>(Spectrum(1), Beck(a, a), Fresnel::One());
                      }, true});
        cs.push_back({"roughglass" + s, [a] {
                          return std::make_unique<MicrofacetDielectric>(Spectrum(1), Spectrum(1), 1.5, GGX(a, a));
                      }, false});
        cs.push_back({"roughglassBeck" + s, [a] {
                          return std::make_unique<MicrofacetDielectric>(Spectrum(1), Spectrum(1), 1.33, Beck(a, a));
                      }, false});
        cs.push_back({"substrate" + s, [a] {
                          return std::make_unique<FresnelBlend>(Spectrum(0.5), Spectrum(0.2), GGX(a, a));
                      }, true});
        cs.push_back({"plastic" + s, [a] { return std::make_unique<Plastic>(a); }, true});
    }
    cs.push_back({"ggxAniso", [] {
                      return std::make_unique<MicrofacetReflection>(Spectrum(1), GGX(0.15, 0.5), Fresnel::One());
                  }, true});
    cs.push_back({"beckAniso", [] {
                      return std::make_unique<MicrofacetReflection>(Spectrum(1), Beck(0.5, 0.15), Fresnel::One());
                  }, true});
    cs.push_back({"conductor", [] {
                      return std::make_unique<MicrofacetReflection>(
                          Spectrum(1), GGX(0.25, 0.25),
                          Fresnel::MakeConductor(Spectrum(0.2, 1.0, 1.2), Spectrum(3.7, 2.6, 2.4)));
                  }, true});
    cs.push_back({"roughglassAniso", [] {
                      return std::make_unique<MicrofacetDielectric>(Spectrum(1), Spectrum(1), 1.5, GGX(0.1, 0.4));
                  }, false});
    cs.push_back({"roughglassTonly", [] {
                      return std::make_unique<MicrofacetDielectric>(Spectrum(0), Spectrum(1), 1.5, GGX(0.3, 0.3));
                  }, false});
    cs.push_back({"translucent", [] { return std::make_unique<Translucent>(0.3); }, false});
    // glTF 2.0 metallic-roughness (alpha given directly): dielectric, metal, half
    // metallic, and with KHR_materials_transmission (not reciprocal: 1/eta^2 scaling).
    auto gltf = [&cs](std::string name, Spectrum base, Float metallic, Float alpha, Float t) {
        cs.push_back({name, [=] { return std::make_unique<GltfPbrBxDF>(base, metallic, alpha, 1.5, t); }, t == 0,
                      metallic == 1 || t == 1});
    };
    gltf("gltfDielectric0.05", Spectrum(1), 0, 0.05, 0);
    gltf("gltfDielectric0.3", Spectrum(0.9, 0.5, 0.2), 0, 0.3, 0);
    gltf("gltfDielectric1", Spectrum(1), 0, 1, 0);
    gltf("gltfMetal0.1", Spectrum(1), 1, 0.1, 0);
    gltf("gltfMetal0.6", Spectrum(0.95, 0.64, 0.54), 1, 0.6, 0);
    gltf("gltfHalfMetal0.3", Spectrum(1), 0.5, 0.3, 0);
    gltf("gltfTransmission1", Spectrum(1), 0, 0.3, 1);
    gltf("gltfTransmission0.5", Spectrum(1), 0, 0.3, 0.5);
    return cs;
}

int NumChi2Tests() { return int(Cases().size() * Wos().size()); }

}  // namespace

// Every case x direction is one chi-square test; the Sidak-corrected level makes
// the whole suite fail with probability 1% for correct code (seeds are fixed).
TEST(BxDF, ChiSquareSampleMatchesPdf) {
    double alpha = chi2::SidakAlpha(0.01, NumChi2Tests());
    int idx = 0;
    for (const Case &c : Cases()) {
        auto b = c.make();
        for (const Vec3 &wo : Wos()) {
            auto r = BxDFChi2(*b, wo, 100000, 1000 + idx++, alpha);
            EXPECT_TRUE(r.pass) << c.name << " wo=" << wo << ": " << r.message;
        }
    }
}

// sample() must report exactly what f() and pdf() give at the sampled direction,
// and its pdfRev must equal pdf(wi, wo).
TEST(BxDF, SampleConsistentWithEval) {
    for (const Case &c : Cases()) {
        auto b = c.make();
        RNG rng(7);
        for (const Vec3 &wo : Wos())
            for (int i = 0; i < 2000; ++i) {
                BSDFSample s;
                for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                    if (!b->sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, mode, &s)) continue;
                    ASSERT_FALSE(s.isSpecular());
                    ASSERT_NEAR(s.wi.length(), 1, 1e-9);
                    Spectrum f = b->f(wo, s.wi, mode);
                    Float pdf = b->pdf(wo, s.wi, mode);
                    TransportMode rev = mode == TransportMode::Radiance ? TransportMode::Importance
                                                                        : TransportMode::Radiance;
                    Float pdfRev = b->pdf(s.wi, wo, rev);
                    for (int k = 0; k < 3; ++k) ASSERT_NEAR(s.f[k], f[k], 1e-9 * (1 + f[k])) << c.name;
                    ASSERT_NEAR(s.pdf, pdf, 1e-9 * (1 + pdf)) << c.name;
                    ASSERT_NEAR(s.pdfRev, pdfRev, 1e-9 * (1 + pdfRev)) << c.name;
                    ASSERT_GT(s.pdf, 0);
                    bool transmit = s.wi.z * wo.z < 0;
                    ASSERT_EQ(bool(s.flags & BSDF_TRANSMISSION), transmit) << c.name;
                }
            }
    }
}

// Numerical integral of the pdf over the sphere is at most 1 and equals the
// fraction of calls that produced a sample (within 5 sigma + integration error).
TEST(BxDF, PdfIntegratesToSampledMass) {
    for (const Case &c : Cases()) {
        auto b = c.make();
        for (const Vec3 &wo : Wos()) {
            // Midpoint rule per hemisphere in (s, phi) with |cos theta| = 1 - s^2,
            // which resolves peaks at the poles.
            const int ns = 300, np = 200;
            double integral = 0;
            for (int h = 0; h < 2; ++h)
                for (int i = 0; i < ns; ++i)
                    for (int j = 0; j < np; ++j) {
                        double sv = (i + 0.5) / ns, ct = (1 - sv * sv) * (h ? -1 : 1);
                        double phi = 2 * Pi * (j + 0.5) / np;
                        integral += 2 * sv * b->pdf(wo, Dir(ct, phi), TransportMode::Radiance);
                    }
            integral *= (1.0 / ns) * (2 * Pi / np);
            RNG rng(11);
            const int n = 40000;
            int ok = 0;
            for (int i = 0; i < n; ++i) {
                BSDFSample s;
                if (b->sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Radiance, &s)) ++ok;
            }
            double frac = double(ok) / n, sigma = std::sqrt(frac * (1 - frac) / n);
            EXPECT_LE(integral, 1.01) << c.name << " wo=" << wo;
            EXPECT_NEAR(integral, frac, 5 * sigma + 0.01) << c.name << " wo=" << wo;
        }
    }
}

TEST(BxDF, Reciprocity) {
    RNG rng(3);
    for (const Case &c : Cases()) {
        auto b = c.make();
        for (int i = 0; i < 2000; ++i) {
            Vec3 wo = SphericalDirection(0, 0, 0), wi;
            Float c1 = 2 * rng.uniform() - 1, c2 = 2 * rng.uniform() - 1;
            wo = Dir(c1, 2 * Pi * rng.uniform());
            wi = Dir(c2, 2 * Pi * rng.uniform());
            if (std::abs(wo.z) < 1e-3 || std::abs(wi.z) < 1e-3) continue;
            Spectrum a = b->f(wo, wi, TransportMode::Radiance);
            // Adjoint BSDF: importance-mode f equals radiance-mode f with directions swapped
            // (Veach 1997, Sec. 3.7); for symmetric lobes both modes agree with the swap.
            Spectrum adj = b->f(wi, wo, TransportMode::Importance);
            for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], adj[k], 1e-9 * (1 + a[k])) << c.name << " " << wo << wi;
            if (c.reciprocal) {
                Spectrum sw = b->f(wi, wo, TransportMode::Radiance);
                for (int k = 0; k < 3; ++k) ASSERT_NEAR(a[k], sw[k], 1e-9 * (1 + a[k])) << c.name;
            }
        }
    }
}

// Directional albedo E[f |cos| / pdf] of every lossless or lossy BxDF is <= 1
// (importance mode: no radiance compression across refraction). Tolerance: 5 sigma.
// Non-conserving models: per channel, the estimate equals the midpoint-rule integral
// of f |cos| (the grid of PdfIntegratesToSampledMass, same 0.01 integration allowance).
TEST(BxDF, WhiteFurnaceAlbedoAtMostOne) {
    for (const Case &c : Cases()) {
        auto b = c.make();
        for (const Vec3 &wo : Wos()) {
            RNG rng(21);
            const int n = 40000;
            double sum = 0, sum2 = 0, sumC[3] = {0, 0, 0}, sum2C[3] = {0, 0, 0};
            for (int i = 0; i < n; ++i) {
                BSDFSample s;
                Spectrum w(0);
                if (b->sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Importance, &s))
                    w = s.f * (AbsCosTheta(s.wi) / s.pdf);
                sum += w.maxComponent();
                sum2 += w.maxComponent() * w.maxComponent();
                for (int k = 0; k < 3; ++k) {
                    sumC[k] += w[k];
                    sum2C[k] += w[k] * w[k];
                }
            }
            double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
            if (c.conserving) {
                EXPECT_LE(mean, 1 + 5 * sd + 1e-9) << c.name << " wo=" << wo;
                continue;
            }
            Spectrum integral = QuadratureAlbedo(*b, wo, 300, 200);
            for (int k = 0; k < 3; ++k) {
                double m = sumC[k] / n, sdk = std::sqrt(std::max(0.0, sum2C[k] / n - m * m) / n);
                EXPECT_NEAR(m, integral[k], 5 * sdk + 0.01) << c.name << " wo=" << wo << " channel " << k;
            }
        }
    }
}

TEST(BxDF, LambertianAlbedoIsExactlyR) {
    LambertianReflection b(Spectrum(1));
    RNG rng(5);
    for (int i = 0; i < 1000; ++i) {
        BSDFSample s;
        ASSERT_TRUE(b.sample(Vec3(0.3, 0.1, 0.9487), rng.uniform(), {rng.uniform(), rng.uniform()},
                             TransportMode::Radiance, &s));
        ASSERT_NEAR(s.f.r * AbsCosTheta(s.wi) / s.pdf, 1, 1e-12);
    }
}

// A rough dielectric with a small roughness loses little energy: albedo close to 1.
TEST(BxDF, RoughDielectricNearlyLossless) {
    MicrofacetDielectric b(Spectrum(1), Spectrum(1), 1.5, GGX(0.05, 0.05));
    for (Float ct : {0.9, -0.9}) {
        Vec3 wo = SphericalDirection(std::sqrt(1 - ct * ct), ct, 0.3);
        RNG rng(9);
        double sum = 0;
        const int n = 20000;
        for (int i = 0; i < n; ++i) {
            BSDFSample s;
            if (b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Importance, &s))
                sum += s.f.r * AbsCosTheta(s.wi) / s.pdf;
        }
        EXPECT_GT(sum / n, 0.97) << ct;
        EXPECT_LT(sum / n, 1.005) << ct;
    }
}

// Smooth dielectric: each sample carries weight exactly 1 in importance mode and
// 1/eta'^2 for refraction in radiance mode; reflection probability is Fresnel.
TEST(BxDF, SpecularDielectricLosslessAndFresnel) {
    const Float eta = 1.5;
    SpecularDielectric b(Spectrum(1), Spectrum(1), eta);
    EXPECT_EQ(b.roughness(), 0);
    for (Float ct : {0.95, 0.4, -0.95, -0.4}) {
        Vec3 wo = SphericalDirection(std::sqrt(1 - ct * ct), ct, 1.0);
        RNG rng(13);
        int nRefl = 0, n = 20000, nOk = 0;
        for (int i = 0; i < n; ++i) {
            BSDFSample s;
            for (TransportMode mode : {TransportMode::Importance, TransportMode::Radiance}) {
                RNG copy = rng;
                if (!b.sample(wo, copy.uniform(), {0.5, 0.5}, mode, &s)) continue;
                ASSERT_TRUE(s.isSpecular());
                Float w = s.f.r * AbsCosTheta(s.wi) / s.pdf;
                if (mode == TransportMode::Importance || !s.isTransmission())
                    ASSERT_NEAR(w, 1, 1e-12);
                else
                    ASSERT_NEAR(w, 1 / (s.eta * s.eta), 1e-12);
                if (mode == TransportMode::Importance) {
                    ++nOk;
                    if (!s.isTransmission()) ++nRefl;
                    // Snell's law.
                    if (s.isTransmission()) {
                        Float sinO = std::sqrt(1 - wo.z * wo.z), sinI = std::sqrt(1 - s.wi.z * s.wi.z);
                        Float etaO = wo.z > 0 ? 1 : eta, etaI = wo.z > 0 ? eta : 1;
                        ASSERT_NEAR(etaO * sinO, etaI * sinI, 1e-9);
                        ASSERT_NEAR(s.eta, etaI / etaO, 1e-12);
                    }
                }
            }
            rng.uniform();
        }
        Float F = FrDielectric(ct, eta);
        double frac = double(nRefl) / nOk;
        EXPECT_NEAR(frac, F, 5 * std::sqrt(F * (1 - F) / nOk) + 1e-9) << ct;
    }
}

TEST(Fresnel, KnownValues) {
    // Normal incidence: ((n-1)/(n+1))^2.
    EXPECT_NEAR(FrDielectric(1, 1.5), 0.04, 1e-12);
    EXPECT_NEAR(FrDielectric(-1, 1.5), 0.04, 1e-12);
    // Beyond the critical angle from inside: total internal reflection.
    EXPECT_EQ(FrDielectric(-0.5, 1.5), 1);
    EXPECT_NEAR(FrDielectric(0, 1.5), 1, 1e-12);
    // Conductor at normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
    Float n = 0.2, k = 3.7;
    EXPECT_NEAR(FrConductor1(1, n, k), ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k), 1e-12);
    // A conductor with k = 0 is a dielectric.
    for (Float c : {0.1, 0.5, 0.9}) EXPECT_NEAR(FrConductor1(c, 1.5, 0), FrDielectric(c, 1.5), 1e-9);
}

TEST(Microfacet, NormalizedProjectedArea) {
    // Integral of D(wh) cos(theta_h) over the hemisphere is 1; visible normal pdf integrates to 1.
    for (auto type : {MicrofacetDistribution::Beckmann, MicrofacetDistribution::TrowbridgeReitz})
        for (auto axy : {std::pair<Float, Float>(0.2, 0.2), {0.3, 0.7}, {0.9, 0.9}}) {
            MicrofacetDistribution d(type, axy.first, axy.second);
            const int nc = 1000, np = 200;
            double sumD = 0, sumV = 0;
            Vec3 wo = SphericalDirection(std::sqrt(1 - 0.3 * 0.3), 0.3, 0.4);
            for (int i = 0; i < nc; ++i)
                for (int j = 0; j < np; ++j) {
                    // Substitute cos = 1 - s^2 to resolve the peak at the pole.
                    double sv = (i + 0.5) / nc, ct = 1 - sv * sv, phi = 2 * Pi * (j + 0.5) / np;
                    Vec3 wh = Dir(ct, phi);
                    double jac = 2 * sv * (1.0 / nc) * (2 * Pi / np);
                    sumD += d.D(wh) * ct * jac;
                    sumV += d.pdf(wo, wh) * jac;
                }
            EXPECT_NEAR(sumD, 1, 2e-3) << type << " " << axy.first << "," << axy.second;
            EXPECT_NEAR(sumV, 1, 2e-3) << type << " " << axy.first << "," << axy.second;
        }
}

TEST(Microfacet, RemapRoughness) {
    // pbrt-v3's mapping is increasing and maps 1 to about 1.62 and 0.1 to about 0.44 (log-polynomial fit).
    Float prev = 0;
    for (Float r = 0.001; r <= 1; r *= 1.5) {
        Float a = MicrofacetDistribution::RoughnessToAlpha(r);
        EXPECT_GT(a, prev);
        prev = a;
    }
    EXPECT_NEAR(MicrofacetDistribution::RoughnessToAlpha(1), 1.62142, 1e-5);
    EXPECT_NEAR(ErfInv(std::erf(0.7)), 0.7, 1e-12);
    EXPECT_NEAR(ErfInv(std::erf(-2.5)), -2.5, 1e-9);
}

TEST(BxDF, RoughnessReported) {
    EXPECT_EQ(LambertianReflection(Spectrum(1)).roughness(), 1);
    EXPECT_EQ(SpecularReflection(Spectrum(1), Fresnel::One()).roughness(), 0);
    EXPECT_EQ(MicrofacetReflection(Spectrum(1), GGX(0.3, 0.05), Fresnel::One()).roughness(), 0.05);
    Plastic p(0.2);
    EXPECT_EQ(p.roughness(), 0.2);
}

// A composite with a specular lobe: the one-sample estimator of the albedo is
// unbiased over the mixture (diffuse 0.3 + perfect mirror 0.5 = 0.8), and
// specular samples carry the lobe-selection probability in their pdf.
TEST(BxDF, CompositeWithSpecularLobe) {
    LambertianReflection d(Spectrum(0.3));
    SpecularReflection m(Spectrum(0.5), Fresnel::One());
    CompositeBxDF c;
    c.add(&d, 1);
    c.add(&m, 3);
    EXPECT_EQ(c.flags(), unsigned(BSDF_REFLECTION | BSDF_DIFFUSE | BSDF_SPECULAR));
    EXPECT_EQ(c.roughness(), 0);
    Vec3 wo = Normalize(Vec3(0.3, -0.2, 0.7));
    RNG rng(17);
    const int n = 40000;
    double sum = 0, sum2 = 0;
    int nSpec = 0;
    for (int i = 0; i < n; ++i) {
        BSDFSample s;
        ASSERT_TRUE(c.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Radiance, &s));
        if (s.isSpecular()) {
            ++nSpec;
            ASSERT_NEAR(s.pdf, 0.75, 1e-12);
            ASSERT_NEAR(s.wi.z, wo.z, 1e-12);
        } else {
            ASSERT_NEAR(s.pdf, 0.25 * AbsCosTheta(s.wi) * InvPi, 1e-12);
        }
        double w = s.f.r * AbsCosTheta(s.wi) / s.pdf;
        sum += w;
        sum2 += w * w;
    }
    double mean = sum / n, sd = std::sqrt((sum2 / n - mean * mean) / n);
    EXPECT_NEAR(mean, 0.8, 5 * sd + 1e-12);
    EXPECT_NEAR(double(nSpec) / n, 0.75, 5 * std::sqrt(0.75 * 0.25 / n));
}
