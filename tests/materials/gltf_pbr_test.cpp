// The glTF 2.0 metallic-roughness BxDF against values computed here from the
// formulas of the glTF 2.0 specification, Appendix B (closed-form GGX D and
// height-correlated V_GGX, Schlick Fresnel), KHR_materials_ior (f0) and
// KHR_materials_transmission (Walter et al. 2007 rough transmission); roughness and
// flag reporting, the smooth limit, and finiteness at degenerate inputs.
// (Statistical tests run in bxdf_test.cpp's table.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "materials/gltf_pbr.h"
#include "samplers/rng.h"
#include "samplers/sampling.h"
#include "material_test_util.h"

using namespace gradus;
using namespace gradus::mattest;

namespace {

// Appendix B: D = alpha^2 chi(N.H) / (pi ((N.H)^2 (alpha^2 - 1) + 1)^2).
double D_GGX(double nh, double a) {
    double a2 = a * a;
    return nh > 0 ? a2 / (Pi * Sqr(nh * nh * (a2 - 1) + 1)) : 0;
}
// Appendix B: V = 0.5 / (N.L sqrt((N.V)^2 (1 - a^2) + a^2) + N.V sqrt((N.L)^2 (1 - a^2) + a^2)).
double V_GGX(double nl, double nv, double a) {
    double a2 = a * a;
    return 0.5 / (nl * std::sqrt(nv * nv * (1 - a2) + a2) + nv * std::sqrt(nl * nl * (1 - a2) + a2));
}
double Schlick(double f0, double vh) { return f0 + (1 - f0) * std::pow(1 - vh, 5); }
double F0(double ior) { return Sqr((1 - ior) / (1 + ior)); }

// Appendix B reflection for one channel (no transmission), upper hemisphere.
double AppendixB(const Vec3 &v, const Vec3 &l, double base, double metallic, double a, double ior) {
    Vec3 h = Normalize(v + l);
    double vh = std::abs(Dot(v, h));
    double spec = D_GGX(h.z, a) * V_GGX(l.z, v.z, a);
    double F = Schlick(F0(ior), vh);
    double dielectric = (1 - F) * base / Pi + F * spec;
    double metal = spec * (base + (1 - base) * std::pow(1 - vh, 5));
    return (1 - metallic) * dielectric + metallic * metal;
}

const std::pair<Vec3, Vec3> kPairs[] = {
    {Vec3(0, 0, 1), Vec3(0, 0, 1)},
    {Dir(0.8, 0.3), Dir(0.6, 0.3 + Pi)},  // mirror-like azimuth
    {Dir(0.9, 0.1), Dir(0.4, 2.0)},
    {Dir(0.3, 1.0), Dir(0.95, 5.0)},
    {Dir(0.15, 0.0), Dir(0.2, 3.0)},
};

}  // namespace

TEST(GltfPbr, MetalIsDTimesVTimesSchlickOfBaseColor) {
    const Spectrum base(0.95, 0.64, 0.54);
    for (double a : {0.05, 0.3, 0.6, 1.0}) {
        GltfPbrBxDF b(base, 1, a, 1.5, 0);
        for (auto [wo, wi] : kPairs)
            for (int k = 0; k < 3; ++k) {
                double expect = AppendixB(wo, wi, base[k], 1, a, 1.5);
                Spectrum f = b.f(wo, wi, TransportMode::Radiance);
                EXPECT_NEAR(f[k], expect, 1e-9 * expect) << a << " " << wo << wi;
                // Importance mode and swapped directions agree (reflection is symmetric).
                EXPECT_NEAR(b.f(wi, wo, TransportMode::Importance)[k], expect, 1e-9 * expect);
            }
        // Normal incidence: D = 1/(pi a^2), V = 1/4, F = baseColor.
        Vec3 n(0, 0, 1);
        EXPECT_NEAR(b.f(n, n, TransportMode::Radiance).g, 0.64 / (4 * Pi * a * a), 1e-9 / (a * a));
    }
}

TEST(GltfPbr, DielectricRoughIsDiffuseTimesOneMinusFPlusSpecular) {
    // alpha = 1: D = 1/pi everywhere, V = 0.5 / (N.L + N.V).
    const Spectrum base(0.8, 0.5, 0.1);
    GltfPbrBxDF b(base, 0, 1, 1.5, 0);
    EXPECT_NEAR(b.f0(), 0.04, 1e-15);
    for (auto [wo, wi] : kPairs) {
        Vec3 h = Normalize(wo + wi);
        double F = 0.04 + 0.96 * std::pow(1 - Dot(wo, h), 5);
        for (int k = 0; k < 3; ++k) {
            double expect = (1 - F) * base[k] / Pi + F / Pi * 0.5 / (wo.z + wi.z);
            EXPECT_NEAR(b.f(wo, wi, TransportMode::Radiance)[k], expect, 1e-12) << wo << wi;
            EXPECT_NEAR(AppendixB(wo, wi, base[k], 0, 1, 1.5), expect, 1e-12);
        }
    }
    // Other roughness, ior and a half-metallic mix follow the same formulas.
    for (double ior : {1.0, 1.33, 2.0})
        for (double m : {0.0, 0.5})
            for (double a : {0.02, 0.3}) {
                GltfPbrBxDF c(base, m, a, ior, 0);
                EXPECT_NEAR(c.f0(), F0(ior), 1e-15);
                for (auto [wo, wi] : kPairs)
                    for (int k = 0; k < 3; ++k) {
                        double expect = AppendixB(wo, wi, base[k], m, a, ior);
                        EXPECT_NEAR(c.f(wo, wi, TransportMode::Radiance)[k], expect, 1e-9 * expect)
                            << ior << " " << m << " " << a << " " << wo << wi;
                    }
            }
}

// Reflection on the side of wo only; from below, the mirrored configuration.
TEST(GltfPbr, ReflectionOnlyWithoutTransmission) {
    GltfPbrBxDF b(Spectrum(0.7), 0.3, 0.4, 1.5, 0);
    EXPECT_EQ(b.flags() & BSDF_TRANSMISSION, 0u);
    Vec3 wo = Dir(0.7, 0.2), wi = Dir(0.5, 2.5);
    EXPECT_TRUE(b.f(wo, -wi, TransportMode::Radiance).isBlack());
    EXPECT_EQ(b.pdf(wo, -wi, TransportMode::Radiance), 0);
    Vec3 woB(wo.x, wo.y, -wo.z), wiB(wi.x, wi.y, -wi.z);
    EXPECT_NEAR(b.f(woB, wiB, TransportMode::Radiance).r, b.f(wo, wi, TransportMode::Radiance).r, 1e-12);
}

TEST(GltfPbr, TransmissionIsWalterBtdfWithoutItsFresnel) {
    const double ior = 1.5, a = 0.3;
    const Spectrum base(0.9, 0.7, 0.4);
    for (double t : {1.0, 0.5})
        for (double m : {0.0, 0.25}) {
            GltfPbrBxDF b(base, m, a, ior, t);
            EXPECT_TRUE(b.flags() & BSDF_TRANSMISSION);
            EXPECT_TRUE(b.flags() & BSDF_GLOSSY);
            auto lambda = [&](const Vec3 &w) {
                double t2 = (1 - w.z * w.z) / (w.z * w.z);
                return (-1 + std::sqrt(1 + a * a * t2)) / 2;
            };
            // wo outside (eta 1), wi inside (eta ior): Walter et al. 2007, Eq. 16 and 21
            // for radiance (light arrives along wi): h = -(wo + ior wi) normalised.
            for (auto [wo, wiUp] : kPairs) {
                Vec3 wi(wiUp.x, wiUp.y, -wiUp.z);
                Vec3 h = Normalize(wo + wi * ior);
                if (h.z < 0) h = -h;
                double oh = Dot(wo, h), ih = Dot(wi, h);
                if (oh <= 0 || ih >= 0) {  // no microfacet refracts this pair
                    EXPECT_TRUE(b.f(wo, wi, TransportMode::Radiance).isBlack());
                    continue;
                }
                double G = 1 / (1 + lambda(wo) + lambda(wi));
                double walter = std::abs(ih) * std::abs(oh) / (std::abs(wi.z) * wo.z) * G * D_GGX(h.z, a) /
                                Sqr(ior * ih + oh);
                double F = Schlick(F0(ior), oh);
                for (int k = 0; k < 3; ++k) {
                    double expect = (1 - m) * t * (1 - F) * base[k] * walter;
                    EXPECT_NEAR(b.f(wo, wi, TransportMode::Radiance)[k], expect, 1e-9 * expect) << wo << wi;
                    // Importance: no 1/eta^2 radiance compression (eta_wi / eta_wo = ior).
                    EXPECT_NEAR(b.f(wo, wi, TransportMode::Importance)[k], expect * ior * ior, 1e-9 * expect);
                    // Adjoint: the reverse pair in the other mode.
                    EXPECT_NEAR(b.f(wi, wo, TransportMode::Importance)[k], expect, 1e-9 * expect);
                }
            }
        }
}

TEST(GltfPbr, RoughnessAndFlags) {
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 0, 0.3, 1.5, 0).roughness(), 0.3);
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 1, 1, 1.5, 0).roughness(), 1);
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 1, 0.05, 1.5, 0.5).roughness(), 0.05);
    // Smooth limit below SmoothAlpha: delta lobes, roughness 0.
    GltfPbrBxDF smooth(Spectrum(1), 0, 0.5 * GltfPbrBxDF::SmoothAlpha, 1.5, 0.5);
    EXPECT_EQ(smooth.roughness(), 0);
    EXPECT_EQ(smooth.flags(),
              unsigned(BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_SPECULAR | BSDF_DIFFUSE));
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 1, 0, 1.5, 0).flags(), unsigned(BSDF_REFLECTION | BSDF_SPECULAR));
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 0, 0.3, 1.5, 0).flags(),
              unsigned(BSDF_REFLECTION | BSDF_GLOSSY | BSDF_DIFFUSE));
    // Metallic 1 or transmission 1 have no diffuse lobe; black base color no diffuse
    // or transmission (only the Fresnel-weighted specular layer is left).
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 1, 0.3, 1.5, 1).flags(), unsigned(BSDF_REFLECTION | BSDF_GLOSSY));
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 0, 0.3, 1.5, 1).flags(),
              unsigned(BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY));
    EXPECT_EQ(GltfPbrBxDF(Spectrum(0), 0, 0.3, 1.5, 0.5).flags(), unsigned(BSDF_REFLECTION | BSDF_GLOSSY));
    // ior 1: transmission passes straight through (a delta lobe whatever alpha).
    GltfPbrBxDF ior1(Spectrum(1), 0, 0.5, 1, 1);
    EXPECT_EQ(ior1.roughness(), 0);
    EXPECT_EQ(ior1.flags(), unsigned(BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY | BSDF_SPECULAR));
    EXPECT_EQ(GltfPbrBxDF(Spectrum(1), 0, 0.5, 1, 0).roughness(), 0.5);
    // Clamping of the inputs.
    GltfPbrBxDF c(Spectrum(2, -1, 0.5), 3, 4, 0.5, -2);
    EXPECT_EQ(c.alpha(), 1);
    EXPECT_EQ(c.f0(), 0);
    EXPECT_EQ(c.flags() & (BSDF_DIFFUSE | BSDF_TRANSMISSION), 0u);  // metallic clamped to 1
}

// Smooth limit: metal mirror weight F = baseColor + (1 - baseColor)(1 - cos)^5;
// dielectric with transmission 1: mirror F_d or refraction (1 - F_d) (F_d at the
// outside cosine), Snell's law, 1/eta'^2 only in radiance mode.
TEST(GltfPbr, SmoothLimit) {
    const Spectrum base(0.9, 0.6, 0.3);
    GltfPbrBxDF metal(base, 1, 0, 1.5, 0);
    Vec3 wo = Dir(0.6, 1.0);
    BSDFSample s;
    ASSERT_TRUE(metal.sample(wo, 0.5, {0.3, 0.7}, TransportMode::Radiance, &s));
    EXPECT_TRUE(s.isSpecular());
    EXPECT_NEAR(s.wi.z, wo.z, 1e-12);
    EXPECT_NEAR(s.wi.x, -wo.x, 1e-12);
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(s.f[k] * AbsCosTheta(s.wi) / s.pdf, base[k] + (1 - base[k]) * std::pow(0.4, 5), 1e-12);
    EXPECT_TRUE(metal.f(wo, s.wi, TransportMode::Radiance).isBlack());
    EXPECT_EQ(metal.pdf(wo, s.wi, TransportMode::Radiance), 0);

    const double ior = 1.5;
    GltfPbrBxDF glass(Spectrum(1), 0, 0, ior, 1);
    for (double ct : {0.9, 0.4, -0.9, -0.95}) {
        Vec3 w = Dir(ct, 0.4);
        GltfPbrBxDF::LobeProbs p = glass.lobeProbs(w);
        EXPECT_EQ(p.diffuse, 0);
        EXPECT_NEAR(p.specular + p.transmission, 1, 1e-15);
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
            ASSERT_TRUE(glass.sample(w, 0.999, {0.5, 0.5}, mode, &s)) << ct;
            ASSERT_TRUE(s.isTransmission());
            ASSERT_TRUE(s.isSpecular());
            double etaO = ct > 0 ? 1 : ior, etaI = ct > 0 ? ior : 1;
            EXPECT_NEAR(etaO * std::sqrt(1 - ct * ct), etaI * std::sqrt(1 - s.wi.z * s.wi.z), 1e-12);
            EXPECT_NEAR(s.eta, etaI / etaO, 1e-12);
            double cOut = ct > 0 ? std::abs(ct) : std::abs(s.wi.z);
            double expect = (1 - Schlick(0.04, cOut)) / p.transmission;
            if (mode == TransportMode::Radiance) expect /= Sqr(etaI / etaO);
            EXPECT_NEAR(s.f.g * AbsCosTheta(s.wi) / s.pdf, expect, 1e-12) << ct;
            EXPECT_NEAR(s.pdfRev, glass.lobeProbs(s.wi).transmission, 1e-15);
            ASSERT_TRUE(glass.sample(w, 0, {0.5, 0.5}, mode, &s));
            ASSERT_FALSE(s.isTransmission());
            EXPECT_NEAR(s.f.g * AbsCosTheta(s.wi) / s.pdf, Schlick(0.04, std::abs(ct)) / p.specular, 1e-12);
        }
    }
    // Beyond the critical angle from inside the refraction sample fails (no TIR lobe).
    EXPECT_FALSE(glass.sample(Dir(-0.5, 0.4), 0.999, {0.5, 0.5}, TransportMode::Radiance, &s));
    // ior 1: straight through with weight (1 - F) at the incidence cosine (f0 = 0).
    GltfPbrBxDF thin(Spectrum(1), 0, 0.4, 1, 1);
    Vec3 w = Dir(0.7, 2.0);
    ASSERT_TRUE(thin.sample(w, 0.999, {0.5, 0.5}, TransportMode::Radiance, &s));
    ASSERT_TRUE(s.isSpecular() && s.isTransmission());
    EXPECT_NEAR((s.wi + w).length(), 0, 1e-12);
    EXPECT_NEAR(s.f.r * AbsCosTheta(s.wi) / s.pdf, (1 - std::pow(0.3, 5)) / thin.lobeProbs(w).transmission, 1e-12);
}

// No NaN or Inf: grazing and exactly tangent directions, alpha 0 .. 1, baseColor 0
// and 1, metallic 0 and 1, ior 1, with and without transmission.
TEST(GltfPbr, FiniteAtDegenerateInputs) {
    std::vector<Vec3> dirs;
    for (double z : {1e-12, 1e-7, 1e-4, 0.0, 1.0, -1e-12, -1e-7, -1.0})
        for (double phi : {0.0, 1.3}) dirs.push_back(Dir(z, phi));
    dirs.push_back(Vec3(1, 0, 0));
    int nSamples = 0;
    for (double a : {0.0, 1e-5, GltfPbrBxDF::SmoothAlpha, 1.001 * GltfPbrBxDF::SmoothAlpha, 0.05, 1.0})
        for (double base : {0.0, 1.0})
            for (double m : {0.0, 1.0})
                for (double ior : {1.0, 1.0001, 1.5})
                    for (double t : {0.0, 1.0}) {
                        GltfPbrBxDF b(Spectrum(base), m, a, ior, t);
                        RNG rng(5);
                        for (const Vec3 &wo : dirs) {
                            for (const Vec3 &wi : dirs)
                                for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
                                    Spectrum f = b.f(wo, wi, mode);
                                    Float p = b.pdf(wo, wi, mode);
                                    ASSERT_TRUE(f.isFinite() && std::min({f.r, f.g, f.b}) >= 0)
                                        << a << " " << base << " " << m << " " << ior << " " << t << wo << wi;
                                    ASSERT_TRUE(std::isfinite(p) && p >= 0) << a << wo << wi;
                                }
                            for (int i = 0; i < 50; ++i) {
                                BSDFSample s;
                                if (!b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()},
                                              TransportMode::Radiance, &s))
                                    continue;
                                ++nSamples;
                                ASSERT_TRUE(s.f.isFinite() && std::isfinite(s.pdf) && std::isfinite(s.pdfRev))
                                    << a << " " << base << " " << m << " " << ior << " " << t << wo;
                                ASSERT_TRUE(std::isfinite(s.wi.x + s.wi.y + s.wi.z));
                            }
                        }
                    }
    EXPECT_GT(nSamples, 10000);
}
