// Material factory and BSDF-frame tests: pbrt-v3 parameter handling (defaults,
// unknown/unsupported types, unused-parameter detection), texture lookups,
// mix and bump mapping, world-space BSDF queries.
#include <gtest/gtest.h>

#include "materials/bxdfs.h"
#include "materials/gltf_pbr.h"
#include "materials/material.h"
#include "parser/scene_desc.h"
#include "samplers/rng.h"
#include "material_test_util.h"

using namespace gradus;
using namespace gradus::mattest;

namespace {

std::shared_ptr<Material> Make(const MaterialDesc &d, const NamedTextures &t = {}) {
    return CreateMaterial(d, t, {});
}

Spectrum EvalNormal(const Material &m) {
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m.getBSDF(si, arena, TransportMode::Radiance);
    Vec3 wo = Normalize(Vec3(0.3, 0.2, 1)), wi = Normalize(Vec3(-0.2, 0.4, 1));
    return b.f(wo, wi);
}

}  // namespace

TEST(Material, DefaultMatteWithoutParameters) {
    MaterialDesc d;
    d.type = "matte";
    auto m = Make(d);
    Spectrum f = EvalNormal(*m);
    EXPECT_NEAR(f.r, 0.5 * InvPi, 1e-12);
    EXPECT_NEAR(f.b, 0.5 * InvPi, 1e-12);
    EXPECT_EQ(m->minRoughness(), 1);
    EXPECT_FALSE(m->hasTextures());
}

TEST(Material, MatteKdAndOrenNayar) {
    MaterialDesc d = ParseMaterial("Material \"matte\" \"rgb Kd\" [0.2 0.4 0.6]");
    auto m = Make(d);
    d.params.checkUnused("Material \"matte\"");
    Spectrum f = EvalNormal(*m);
    EXPECT_NEAR(f.g, 0.4 * InvPi, 1e-12);
    // sigma > 0: Oren-Nayar, which differs from Lambert away from normal incidence.
    MaterialDesc d2 = ParseMaterial("Material \"matte\" \"rgb Kd\" [0.2 0.4 0.6] \"float sigma\" [30]");
    auto m2 = Make(d2);
    d2.params.checkUnused("Material");
    Spectrum f2 = EvalNormal(*m2);
    EXPECT_GT(std::abs(f2.g - f.g), 1e-4);
}

TEST(Material, UnknownAndUnsupportedTypesAreLocatedErrors) {
    MaterialDesc d = ParseMaterial("Material \"mattte\"");
    try {
        Make(d);
        FAIL() << "no error";
    } catch (const UnsupportedError &) {
        FAIL() << "unknown type reported as unsupported";
    } catch (const Error &e) {
        std::string w = e.what();
        EXPECT_NE(w.find("test.pbrt:2:"), std::string::npos) << w;
        EXPECT_NE(w.find("mattte"), std::string::npos) << w;
    }
    // Every pbrt-v3 material is implemented now (hair was the last refused).
}

TEST(Material, MisspeltParameterStaysUnused) {
    MaterialDesc d = ParseMaterial("Material \"matte\" \"rgb Kdd\" [1 0 0]");
    auto m = Make(d);
    try {
        d.params.checkUnused("Material \"matte\"");
        FAIL() << "unused parameter not detected";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("Kdd"), std::string::npos);
    }
    // The default Kd was used, not the misspelt one.
    EXPECT_NEAR(EvalNormal(*m).r, 0.5 * InvPi, 1e-12);
}

// The parameter sets used by the shared scenes are all consumed.
TEST(Material, SceneParameterSetsFullyUsed) {
    const char *mats[] = {
        "MakeNamedMaterial \"a\" \"string type\" [ \"metal\" ] \"rgb eta\" [ 1.657460 0.880369 0.521229 ] "
        "\"rgb k\" [ 9.223869 6.269523 4.837001 ] \"bool remaproughness\" [ \"false\" ] "
        "\"float uroughness\" [ 0.25 ] \"float vroughness\" [ 0.25 ]",
        "MakeNamedMaterial \"b\" \"string type\" [ \"glass\" ] \"float index\" [ 1.5 ] \"bool remaproughness\" [ \"false\" ]",
        "Material \"glass\" \"float index\" [ 1.25 ]",
        "Material \"plastic\" \"color Kd\" [0.07 0.09 0.13] \"float roughness\" [0.005] \"color Ks\" [1 1 1] "
        "\"bool remaproughness\" [\"false\"]",
        "Material \"uber\" \"float roughness\" [ 0.0104 ] \"float index\" [ 1 ] \"rgb Kd\" [ 0.64 0.64 0.64 ] "
        "\"rgb Ks\" [ 0.1 0.1 0.1 ] \"rgb Kt\" [ 0 0 0 ] \"rgb opacity\" [ 1 1 1 ]",
        "Material \"substrate\" \"rgb Kd\" [0.5 0.5 0.5] \"rgb Ks\" [0.1 0.1 0.1] \"float uroughness\" [0.1] "
        "\"float vroughness\" [0.2]",
        "Material \"translucent\" \"rgb reflect\" [0.4 0.4 0.4] \"rgb transmit\" [0.5 0.5 0.5] \"float roughness\" [0.2]",
        "Material \"mirror\" \"rgb Kr\" [0.8 0.8 0.8]",
    };
    for (const char *text : mats) {
        MaterialDesc d = ParseMaterial(text);
        auto m = Make(d);
        ASSERT_TRUE(m) << text;
        EXPECT_NO_THROW(d.params.checkUnused("Material")) << text;
        SurfaceInteraction si = FlatHit();
        Arena arena;
        BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
        ASSERT_TRUE(bool(b)) << text;
        // Every material samples something for a direction above the surface.
        RNG rng(1);
        int ok = 0;
        for (int i = 0; i < 100; ++i) {
            BSDFSample s;
            if (b.sample(Normalize(Vec3(0.2, 0.1, 1)), rng.uniform(), {rng.uniform(), rng.uniform()},
                         TransportMode::Radiance, &s)) {
                ++ok;
                EXPECT_TRUE(s.f.isFinite());
            }
        }
        EXPECT_GT(ok, 50) << text;
    }
}

TEST(Material, MetalRoughnessAndFresnel) {
    MaterialDesc d = ParseMaterial(
        "Material \"metal\" \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1] \"bool remaproughness\" [\"false\"] "
        "\"float uroughness\" [0.1] \"float vroughness\" [0.3]");
    auto m = Make(d);
    EXPECT_NEAR(m->minRoughness(), 0.1, 1e-12);
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
    EXPECT_NEAR(b.roughness(), 0.1, 1e-12);
    // Mirror configuration at normal incidence: f = D(n) G F(1) / 4 with F from eta, k.
    Vec3 w(0, 0, 1);
    MicrofacetDistribution dist(MicrofacetDistribution::TrowbridgeReitz, 0.1, 0.3);
    Spectrum f = b.f(w, w);
    Float F = ((0.2 - 1) * (0.2 - 1) + 3.9 * 3.9) / ((0.2 + 1) * (0.2 + 1) + 3.9 * 3.9);
    EXPECT_NEAR(f.r, dist.D(w) * dist.G(w, w) * F / 4, 1e-9 * f.r);
    // Remapped roughness (default): alpha from pbrt-v3's mapping.
    MaterialDesc d2 = ParseMaterial("Material \"metal\" \"float roughness\" [0.3]");
    EXPECT_NEAR(Make(d2)->minRoughness(), MicrofacetDistribution::RoughnessToAlpha(0.3), 1e-12);
    // Default copper reflects red more than blue.
    MaterialDesc d3 = ParseMaterial("Material \"metal\"");
    Spectrum fc = EvalNormal(*Make(d3));
    EXPECT_GT(fc.r, fc.b);
}

TEST(Material, GlassSmoothAndRough) {
    MaterialDesc d = ParseMaterial("Material \"glass\" \"float index\" [1.5]");
    auto m = Make(d);
    EXPECT_EQ(m->minRoughness(), 0);
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
    EXPECT_TRUE(b.isSpecular());
    BSDFSample s;
    // uc close to 1 picks refraction (Fresnel reflectance at normal incidence is 0.04).
    ASSERT_TRUE(b.sample(Vec3(0, 0, 1), 0.9, {0.5, 0.5}, TransportMode::Radiance, &s));
    EXPECT_TRUE(s.isTransmission());
    EXPECT_NEAR(s.eta, 1.5, 1e-12);
    EXPECT_NEAR(s.wi.z, -1, 1e-12);
    EXPECT_NEAR(s.pdf, 0.96, 1e-12);
    // "eta" wins over "index" and roughness makes it glossy.
    MaterialDesc d2 =
        ParseMaterial("Material \"glass\" \"float eta\" [1.33] \"float uroughness\" [0.2] \"float vroughness\" [0.2]");
    auto m2 = Make(d2);
    EXPECT_NO_THROW(d2.params.checkUnused("Material"));
    BSDF b2 = m2->getBSDF(si, arena, TransportMode::Radiance);
    EXPECT_FALSE(b2.isSpecular());
    EXPECT_NEAR(b2.roughness(), MicrofacetDistribution::RoughnessToAlpha(0.2), 1e-12);
}

TEST(Material, TextureParameters) {
    NamedTextures tex;
    tex.spectra["wood"] = std::make_shared<ConstantTexture<Spectrum>>(Spectrum(0.1, 0.2, 0.3));
    tex.floats["bumps"] = std::make_shared<ConstantTexture<Float>>(0.0);
    MaterialDesc d = ParseMaterial("Material \"matte\" \"texture Kd\" \"wood\"");
    auto m = Make(d, tex);
    EXPECT_NEAR(EvalNormal(*m).b, 0.3 * InvPi, 1e-12);
    MaterialDesc bad = ParseMaterial("Material \"matte\" \"texture Kd\" \"nope\"");
    EXPECT_THROW(Make(bad, tex), Error);
    MaterialDesc wrongKind = ParseMaterial("Material \"matte\" \"texture Kd\" \"bumps\"");
    EXPECT_THROW(Make(wrongKind, tex), Error);
}

TEST(Material, MixWeightsComponents) {
    std::map<std::string, std::shared_ptr<Material>> named;
    named["white"] = Make(ParseMaterial("Material \"matte\" \"rgb Kd\" [1 1 1]"));
    named["black"] = Make(ParseMaterial("Material \"matte\" \"rgb Kd\" [0 0 0]"));
    MaterialDesc d = ParseMaterial("Material \"mix\" \"string materials\" [\"white\" \"black\"] \"rgb amount\" [0.25 0.25 0.25]");
    auto m = CreateMaterial(d, {}, named);
    EXPECT_NO_THROW(d.params.checkUnused("Material"));
    // pbrt-v3: the first material is weighted by amount.
    EXPECT_NEAR(EvalNormal(*m).r, 0.25 * InvPi, 1e-12);
    MaterialDesc missing = ParseMaterial("Material \"mix\" \"string materials\" [\"white\" \"grey\"]");
    EXPECT_THROW(CreateMaterial(missing, {}, named), Error);
}

namespace {
// Displacement a * u.
class RampU : public FloatTexture {
  public:
    explicit RampU(Float a) : a_(a) {}
    Float evaluate(const SurfaceInteraction &si) const override { return a_ * si.uv.x; }

  private:
    Float a_;
};
}  // namespace

TEST(Material, BumpMapTiltsShadingNormal) {
    NamedTextures tex;
    const Float a = 0.5;
    tex.floats["ramp"] = std::make_shared<RampU>(a);
    MaterialDesc d = ParseMaterial("Material \"matte\" \"texture bumpmap\" \"ramp\"");
    auto m = Make(d, tex);
    EXPECT_TRUE(m->hasTextures());
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
    // dp/du' = (1, 0, a): n' = normalize(cross((1,0,a), (0,1,0))) = normalize(-a, 0, 1).
    Vec3 expect = Normalize(Vec3(-a, 0, 1));
    EXPECT_NEAR(si.shading.n.x, expect.x, 1e-9);
    EXPECT_NEAR(si.shading.n.z, expect.z, 1e-9);
    EXPECT_NEAR(b.ns().x, expect.x, 1e-9);
    EXPECT_EQ(si.n, Normal3(0, 0, 1));  // geometric normal untouched
}

namespace {
// f of a material at FlatHit against a GltfPbrBxDF built directly, for several pairs.
void ExpectSameAsBxDF(const Material &m, const GltfPbrBxDF &ref, const std::string &what) {
    SurfaceInteraction si = FlatHit();
    Arena arena;
    BSDF b = m.getBSDF(si, arena, TransportMode::Radiance);
    ASSERT_TRUE(bool(b)) << what;
    EXPECT_EQ(b.flags(), ref.flags()) << what;
    EXPECT_EQ(b.roughness(), ref.roughness()) << what;
    const Vec3 pairs[][2] = {{Normalize(Vec3(0.3, 0.2, 1)), Normalize(Vec3(-0.2, 0.4, 1))},
                             {Normalize(Vec3(0.1, -0.5, 0.4)), Normalize(Vec3(-0.7, 0.1, 0.3))},
                             {Normalize(Vec3(0.2, 0.1, 1)), Normalize(Vec3(-0.1, -0.05, -1))}};
    for (auto &pr : pairs) {
        Spectrum f = b.f(pr[0], pr[1]), e = ref.f(pr[0], pr[1], TransportMode::Radiance);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(f[k], e[k], 1e-12 * (1 + e[k])) << what << " channel " << k;
    }
}
}  // namespace

TEST(Material, GltfPbrParameters) {
    MaterialDesc d = ParseMaterial(
        "Material \"gltfpbr\" \"rgb basecolor\" [0.8 0.4 0.2] \"float metallic\" [0.25] \"float roughness\" [0.5] "
        "\"float ior\" [1.33] \"float transmission\" [0.5]");
    auto m = Make(d);
    EXPECT_NO_THROW(d.params.checkUnused("Material \"gltfpbr\""));
    // alpha = roughness^2.
    ExpectSameAsBxDF(*m, GltfPbrBxDF(Spectrum(0.8, 0.4, 0.2), 0.25, 0.25, 1.33, 0.5), "explicit");
    EXPECT_NEAR(m->minRoughness(), 0.25, 1e-15);
    EXPECT_FALSE(m->hasTextures());
    // Defaults: basecolor 1, metallic 1, roughness 1, ior 1.5, transmission 0.
    MaterialDesc d0 = ParseMaterial("Material \"gltfpbr\"");
    auto m0 = Make(d0);
    ExpectSameAsBxDF(*m0, GltfPbrBxDF(Spectrum(1), 1, 1, 1.5, 0), "defaults");
    EXPECT_EQ(m0->minRoughness(), 1);
    // Clamping to the valid ranges (ior exactly 1 allowed: f0 = 0).
    MaterialDesc dc = ParseMaterial(
        "Material \"gltfpbr\" \"rgb basecolor\" [1.5 -0.2 0.5] \"float metallic\" [-1] \"float roughness\" [3] "
        "\"float ior\" [0.5] \"float transmission\" [2]");
    ExpectSameAsBxDF(*Make(dc), GltfPbrBxDF(Spectrum(1, 0, 0.5), 0, 1, 1, 1), "clamped");
    MaterialDesc d1 = ParseMaterial("Material \"gltfpbr\" \"float metallic\" [0] \"float ior\" [1]");
    ExpectSameAsBxDF(*Make(d1), GltfPbrBxDF(Spectrum(1), 0, 1, 1, 0), "ior 1");
}

TEST(Material, GltfPbrMisspeltParameterStaysUnused) {
    MaterialDesc d = ParseMaterial("Material \"gltfpbr\" \"float metalic\" [0] \"float roughness\" [0.5]");
    auto m = Make(d);
    try {
        d.params.checkUnused("Material \"gltfpbr\"");
        FAIL() << "unused parameter not detected";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("metalic"), std::string::npos) << e.what();
    }
    // The default metallic 1 was used.
    ExpectSameAsBxDF(*m, GltfPbrBxDF(Spectrum(1), 1, 0.25, 1.5, 0), "misspelt");
}

TEST(Material, GltfPbrMinRoughnessAndTextures) {
    NamedTextures tex;
    tex.floats["r"] = std::make_shared<RampU>(1.0);
    tex.spectra["c"] = std::make_shared<ConstantTexture<Spectrum>>(Spectrum(0.3));
    auto minR = [&](const std::string &params) {
        MaterialDesc d = ParseMaterial("Material \"gltfpbr\" " + params);
        auto m = Make(d, tex);
        d.params.checkUnused("Material");
        return m->minRoughness();
    };
    EXPECT_NEAR(minR("\"float roughness\" [0.3]"), 0.09, 1e-15);
    EXPECT_EQ(minR("\"texture roughness\" \"r\""), 0);        // textured: unknown
    EXPECT_EQ(minR("\"float roughness\" [0.01]"), 0);         // alpha 1e-4: smooth limit
    EXPECT_EQ(minR("\"float ior\" [1] \"float transmission\" [1]"), 0);  // straight-through delta
    EXPECT_EQ(minR("\"float ior\" [1]"), 1);                  // no transmission: alpha
    EXPECT_NEAR(minR("\"float transmission\" [0.5] \"float roughness\" [0.5]"), 0.25, 1e-15);
    MaterialDesc d = ParseMaterial("Material \"gltfpbr\" \"texture roughness\" \"r\" \"texture basecolor\" \"c\"");
    EXPECT_TRUE(Make(d, tex)->hasTextures());
    MaterialDesc dc = ParseMaterial("Material \"gltfpbr\" \"texture basecolor\" \"c\"");
    EXPECT_FALSE(Make(dc, tex)->hasTextures());  // a constant texture does not vary
}

TEST(Material, GltfPbrNormalMap) {
    auto shadingNormal = [](const std::string &params, SurfaceInteraction si) {
        MaterialDesc d = ParseMaterial("Material \"gltfpbr\" " + params);
        auto m = Make(d);
        EXPECT_NO_THROW(d.params.checkUnused("Material")) << params;
        Arena arena;
        BSDF b = m->getBSDF(si, arena, TransportMode::Radiance);
        EXPECT_NEAR((b.ns() - si.shading.n).length(), 0, 1e-12);
        EXPECT_NEAR(Dot(si.shading.n, si.shading.dpdu), 0, 1e-12);
        EXPECT_NEAR(Dot(si.shading.n, si.shading.dpdv), 0, 1e-12);
        EXPECT_EQ(si.n, Normal3(0, 0, 1));  // geometric normal untouched
        return si.shading.n;
    };
    auto near = [](const Vec3 &a, const Vec3 &b) { return (a - b).length() < 1e-12; };
    SurfaceInteraction flat = FlatHit();
    // rgb (0.75, 0.5, 1) -> n_ts = (0.5, 0, 1): tilted towards +T = +dpdu.
    EXPECT_TRUE(near(shadingNormal("\"rgb normalmap\" [0.75 0.5 1]", flat), Normalize(Vec3(0.5, 0, 1))));
    EXPECT_TRUE(near(shadingNormal("\"rgb normalmap\" [0.5 0.5 1]", flat), Vec3(0, 0, 1)));
    // normalscale multiplies x and y.
    EXPECT_TRUE(near(shadingNormal("\"rgb normalmap\" [0.75 0.5 1] \"float normalscale\" [2]", flat),
                     Normalize(Vec3(1, 0, 1))));
    // B follows dpdv (here -y, a mirrored uv layout) and T follows dpdu projected.
    SurfaceInteraction mirrored = FlatHit();
    mirrored.shading.dpdu = Vec3(1, 0, 0.5);
    mirrored.shading.dpdv = Vec3(0.3, -1, 0);
    EXPECT_TRUE(near(shadingNormal("\"rgb normalmap\" [0.5 0.75 1]", mirrored), Normalize(Vec3(0, -0.5, 1))));
    // A texel below the surface is mirrored to the side of the unperturbed normal.
    EXPECT_TRUE(near(shadingNormal("\"rgb normalmap\" [0.75 0.5 0]", flat), Normalize(Vec3(0.5, 0, 1))));
    // Without "normalmap" the shading frame is unchanged.
    EXPECT_TRUE(near(shadingNormal("\"float roughness\" [0.5]", flat), Vec3(0, 0, 1)));
}

TEST(BSDF, FrameAndWorldQueries) {
    SurfaceInteraction si = FlatHit();
    si.shading.n = Normalize(Vec3(0.1, 0.2, 1));
    si.shading.dpdu = Vec3(2, 0.5, 0.3);  // not orthogonal to the shading normal
    MicrofacetReflection bx(Spectrum(1), {MicrofacetDistribution::TrowbridgeReitz, 0.2, 0.5}, Fresnel::One());
    BSDF b(si, &bx);
    Vec3 x = b.toWorld(Vec3(1, 0, 0)), y = b.toWorld(Vec3(0, 1, 0)), z = b.toWorld(Vec3(0, 0, 1));
    EXPECT_NEAR(Dot(x, y), 0, 1e-12);
    EXPECT_NEAR(Dot(x, z), 0, 1e-12);
    EXPECT_NEAR(x.length(), 1, 1e-12);
    EXPECT_NEAR((z - si.shading.n).length(), 0, 1e-12);
    // The tangent follows dpdu (anisotropy aligned with u).
    EXPECT_GT(Dot(x, Normalize(si.shading.dpdu)), 0.9);
    RNG rng(4);
    Vec3 wo = Normalize(Vec3(0.4, -0.3, 0.8));
    for (int i = 0; i < 200; ++i) {
        BSDFSample s;
        if (!b.sample(wo, rng.uniform(), {rng.uniform(), rng.uniform()}, TransportMode::Radiance, &s)) continue;
        Spectrum f = b.f(wo, s.wi);
        Float fwd, rev;
        b.pdfs(wo, s.wi, TransportMode::Radiance, &fwd, &rev);
        EXPECT_NEAR(s.f.r, f.r, 1e-9 * (1 + f.r));
        EXPECT_NEAR(s.pdf, fwd, 1e-9 * (1 + fwd));
        EXPECT_NEAR(s.pdfRev, rev, 1e-9 * (1 + rev));
        EXPECT_NEAR(b.pdf(wo, s.wi), fwd, 1e-12);
    }
    EXPECT_EQ(b.roughnessClass(0.001), RoughnessClass::Rough);
    EXPECT_EQ(b.roughnessClass(0.3), RoughnessClass::NearSpecular);
    SpecularReflection mirror(Spectrum(1), Fresnel::One());
    EXPECT_EQ(BSDF(si, &mirror).roughnessClass(0.001), RoughnessClass::Smooth);
}
