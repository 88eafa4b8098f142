// "fourier" material (Jakob et al. 2014 tables as pbrt-v3 reads them). The tests write
// .bsdf files from analytic BSDFs whose Fourier series and cosine dependence the
// Catmull-Rom interpolation reproduces exactly (coefficients linear in |mu_i| and
// |mu_o| on each side, nodes with the +-0 pair), then compare the material against
// the analytic BSDF: values, sampling (chi-square against the analytic density),
// albedo (white furnace, eta scaling by a z-test), and corrupt files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "common/render_test_util.h"
#include "core/error.h"
#include "materials/fourier.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"

using namespace gradus;
namespace fs = std::filesystem;

namespace {

// ---- an independent writer of the layerlab/pbrt-v3 .bsdf layout ------------------

struct TableSpec {
    std::vector<float> mu;
    int nChannels = 1;
    float eta = 1;
    // Coefficients of the entry (mu_o, mu_i): nChannels * len values, channel-major.
    std::function<std::vector<float>(float muO, float muI, int *len)> series;
};

void PutU32(std::string *s, uint32_t v) {
    for (int k = 0; k < 4; ++k) s->push_back(char((v >> (8 * k)) & 0xff));
}
void PutI32(std::string *s, int32_t v) { PutU32(s, uint32_t(v)); }
void PutF32(std::string *s, float v) {
    uint32_t u;
    std::memcpy(&u, &v, 4);
    PutU32(s, u);
}

std::string Serialize(const TableSpec &t) {
    const int n = int(t.mu.size());
    std::vector<float> coeffs, cdf(size_t(n) * n, 0.f);
    std::vector<int32_t> table;
    int mMax = 0;
    for (int o = 0; o < n; ++o)
        for (int i = 0; i < n; ++i) {
            int len = 0;
            std::vector<float> c = t.series(t.mu[o], t.mu[i], &len);
            EXPECT_EQ(c.size(), size_t(len) * t.nChannels);
            table.push_back(int32_t(coeffs.size()));
            table.push_back(len);
            mMax = std::max(mMax, len);
            coeffs.insert(coeffs.end(), c.begin(), c.end());
        }
    // A trapezoidal cdf per row (the reader only checks it for finiteness).
    for (int o = 0; o < n; ++o)
        for (int i = 1; i < n; ++i) {
            auto a0 = [&](int j) {
                size_t e = size_t(o) * n + j;
                return table[2 * e + 1] > 0 ? coeffs[table[2 * e]] : 0.f;
            };
            cdf[size_t(o) * n + i] = cdf[size_t(o) * n + i - 1] + 0.5f * (a0(i) + a0(i - 1)) * (t.mu[i] - t.mu[i - 1]);
        }
    const std::string meta = "analytic test table";
    std::string s("SCATFUN\x01", 8);
    for (int32_t v : {1, n, int(coeffs.size()), mMax, t.nChannels, 1, int(meta.size()), 0, 0}) PutI32(&s, v);
    PutF32(&s, t.eta);
    for (int k = 0; k < 4; ++k) PutI32(&s, 0);
    for (float m : t.mu) PutF32(&s, m);
    for (float c : cdf) PutF32(&s, c);
    for (int32_t v : table) PutI32(&s, v);
    for (float c : coeffs) PutF32(&s, c);
    return s + meta;
}

// Per test process directory, removed at exit.
struct TempDir {
    fs::path dir;
    TempDir() {
        dir = fs::temp_directory_path() / ("gradus_fourier_test_" + std::to_string(::getpid()));
        fs::create_directories(dir);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(dir, ec);
    }
};
const fs::path &Dir() {
    static TempDir d;
    return d.dir;
}

std::string WriteFile(const std::string &name, const std::string &bytes) {
    fs::path p = Dir() / name;
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p.string();
}

// Nodes: -x_k ... -x_1, -0, +0, x_1 ... x_k with x_k = sin(pi/2 k/K) (non-uniform).
std::vector<float> Nodes(int K) {
    std::vector<float> pos;
    for (int k = 0; k <= K; ++k) pos.push_back(k == 0 ? 0.f : float(std::sin(Pi / 2 * k / K)));
    std::vector<float> mu;
    for (int k = K; k >= 1; --k) mu.push_back(-pos[k]);
    mu.push_back(-0.f);
    for (float p : pos) mu.push_back(p);
    return mu;
}
constexpr int kK = 20;

// Even count without a zero node, as layerlab's Gauss-Lobatto rules give:
// +-sin(pi/2 (j - 1/2) / (K - 1/2)), j = 1..K.
std::vector<float> NodesWithoutZero(int K) {
    std::vector<float> mu;
    for (int j = K; j >= 1; --j) mu.push_back(-float(std::sin(Pi / 2 * (j - 0.5) / (K - 0.5))));
    for (int j = 1; j <= K; ++j) mu.push_back(float(std::sin(Pi / 2 * (j - 0.5) / (K - 0.5))));
    return mu;
}

bool Reflection(float muO, float muI) { return std::signbit(muO) != std::signbit(muI); }

// ---- analytic BSDFs -------------------------------------------------------------

// Lambertian reflector of albedo rho: f |mu_i| = rho / pi |mu_i| on the reflection side.
TableSpec LambertSpec(float rho, std::vector<float> mu = Nodes(kK)) {
    TableSpec t;
    t.mu = std::move(mu);
    t.series = [rho](float muO, float muI, int *len) {
        *len = 0;
        if (!Reflection(muO, muI) || muI == 0) return std::vector<float>();
        *len = 1;
        return std::vector<float>{float(rho * InvPi * std::abs(muI))};
    };
    return t;
}

// Reflection and transmission with azimuthal structure, 3 channels (luminance, red,
// blue). f |mu_i| = |mu_i| G(|mu_o|) (1 + sum_k g_k cos(k phi)) times a channel factor,
// G and g per side. Positive for all phi: 1 + 0.5 c + 0.25 (2c^2 - 1) >= 0.625.
struct Analytic {
    Float aR = 0.1, bR = 0.1, aT = 0.08, bT = 0.02;
    std::vector<Float> gR{0.5, 0.25}, gT{-0.3};
    Float red = 0.8, blue = 0.5, eta = 1.5;

    Float G(bool refl, Float muO) const { return refl ? aR + bR * std::abs(muO) : aT + bT * std::abs(muO); }
    const std::vector<Float> &g(bool refl) const { return refl ? gR : gT; }
    TableSpec spec(std::vector<float> mu = Nodes(kK)) const {
        TableSpec t;
        t.mu = std::move(mu);
        t.nChannels = 3;
        t.eta = float(eta);
        t.series = [this](float muO, float muI, int *len) {
            bool refl = Reflection(muO, muI);
            *len = 0;
            if (muI == 0) return std::vector<float>();
            std::vector<Float> y{std::abs(muI) * G(refl, muO)};
            for (Float gk : g(refl)) y.push_back(y[0] * gk);
            *len = int(y.size());
            std::vector<float> out;
            for (Float scale : {1.0, red, blue})
                for (Float v : y) out.push_back(float(v * scale));
            return out;
        };
        return t;
    }
    // Luminance f |mu_i| as a function of the azimuth difference.
    Float Y(const Vec3 &wo, const Vec3 &wi) const {
        Float muI = -wi.z, muO = wo.z;
        bool refl = muI * muO < 0;
        Float dphi = std::atan2(-wi.y, -wi.x) - std::atan2(wo.y, wo.x);
        Float s = 1;
        for (size_t k = 0; k < g(refl).size(); ++k) s += g(refl)[k] * std::cos((k + 1) * dphi);
        return std::abs(muI) * G(refl, muO) * s;
    }
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
        Float muI = -wi.z, muO = wo.z;
        Float y = Y(wo, wi) / std::abs(muI);
        if (mode == TransportMode::Radiance && muI * muO > 0) {
            Float e = muI > 0 ? 1 / eta : eta;
            y *= e * e;
        }
        // Green from the luminance Y = 0.212671 R + 0.715160 G + 0.072169 B.
        Float green = (1 - 0.212671 * red - 0.072169 * blue) / 0.715160;
        return Spectrum(y * red, y * green, y * blue);
    }
    // Density proportional to the luminance f |mu_i| over (mu_i, phi): Y / (2 pi
    // integral over mu_i of a_0); a_0 integrates to (G_R + G_T) / 2.
    Float pdf(const Vec3 &wo, const Vec3 &wi) const {
        return Y(wo, wi) / (2 * Pi * 0.5 * (G(true, wo.z) + G(false, wo.z)));
    }
};

std::shared_ptr<const FourierTable> Load(const std::string &name, const TableSpec &spec) {
    return FourierTable::Read(WriteFile(name, Serialize(spec)), FileLoc());
}

Vec3 RandomDir(RNG &rng) {
    Float z = 1 - 2 * rng.uniform(), phi = 2 * Pi * rng.uniform();
    return SphericalDirection(SafeSqrt(1 - z * z), z, phi);
}

std::vector<Vec3> TestWos() {
    std::vector<Vec3> w;
    for (Float c : {0.93, 0.5, 0.12, -0.7, 0.03, -0.02}) w.push_back(SphericalDirection(std::sqrt(1 - c * c), c, 0.9));
    return w;
}

}  // namespace

TEST(Fourier, LambertTableMatchesAnalyticValues) {
    auto t = Load("lambert.bsdf", LambertSpec(0.7f));
    FourierBxDF b(t.get());
    EXPECT_EQ(b.flags(), unsigned(BSDF_REFLECTION | BSDF_GLOSSY));
    EXPECT_EQ(b.roughness(), 1);
    EXPECT_EQ(b.eta(), 1);
    RNG rng(7);
    int checked = 0;
    for (int k = 0; k < 4000; ++k) {
        Vec3 wo = RandomDir(rng), wi = RandomDir(rng);
        if (std::abs(wo.z) < 1e-3 || std::abs(wi.z) < 1e-3) continue;
        Float expect = wo.z * wi.z > 0 ? 0.7 * InvPi : 0;
        for (auto mode : {TransportMode::Radiance, TransportMode::Importance}) {
            Spectrum f = b.f(wo, wi, mode);
            ASSERT_NEAR(f.r, expect, 2e-6) << wo << " " << wi;
            ASSERT_EQ(f.r, f.g);
            ASSERT_EQ(f.r, f.b);
        }
        ++checked;
    }
    EXPECT_GT(checked, 3000);
}

TEST(Fourier, ThreeChannelTableMatchesAnalyticValues) {
    Analytic an;
    auto t = Load("analytic.bsdf", an.spec());
    FourierBxDF b(t.get());
    EXPECT_EQ(b.flags(), unsigned(BSDF_REFLECTION | BSDF_TRANSMISSION | BSDF_GLOSSY));
    EXPECT_NEAR(b.eta(), 1.5, 1e-7);
    EXPECT_EQ(t->mMax, 3);
    RNG rng(11);
    Float maxRel = 0;
    for (int k = 0; k < 4000; ++k) {
        Vec3 wo = RandomDir(rng), wi = RandomDir(rng);
        if (std::abs(wo.z) < 1e-3 || std::abs(wi.z) < 1e-3) continue;
        for (auto mode : {TransportMode::Radiance, TransportMode::Importance}) {
            Spectrum f = b.f(wo, wi, mode), e = an.f(wo, wi, mode);
            for (int c = 0; c < 3; ++c) {
                ASSERT_NEAR(f[c], e[c], 1e-5 * (1 + e[c])) << "channel " << c << " wo " << wo << " wi " << wi;
                maxRel = std::max(maxRel, std::abs(f[c] - e[c]) / e[c]);
            }
        }
        // pdf against the analytic density, and the transported quantity's symmetry:
        // the radiance/importance ratio is the (eta_o/eta_i)^2 of the side.
        ASSERT_NEAR(b.pdf(wo, wi, TransportMode::Radiance), an.pdf(wo, wi), 1e-5 * (1 + an.pdf(wo, wi)));
    }
    std::printf("max relative error of f: %.3g\n", maxRel);
}

TEST(Fourier, SamplingMatchesAnalyticDensity) {
    Analytic an;
    auto t3 = Load("analytic-chi2.bsdf", an.spec());
    auto tl = Load("lambert-chi2.bsdf", LambertSpec(1));
    FourierBxDF b3(t3.get()), bl(tl.get());
    const auto wos = TestWos();
    const double alpha = chi2::SidakAlpha(0.01, int(2 * wos.size()));
    chi2::Options o;
    o.xBins = 10;
    o.yBins = 24;
    o.samples = 100000;
    o.alpha = alpha;
    for (const Vec3 &wo : wos) {
        for (int which = 0; which < 2; ++which) {
            const FourierBxDF &b = which ? bl : b3;
            auto sample = [&](RNG &rng, Vec3 *w) {
                BSDFSample s;
                if (!b.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &s))
                    return false;
                // The sample's own pdf and value agree with pdf() and f().
                EXPECT_NEAR(s.pdf, b.pdf(wo, s.wi, TransportMode::Radiance), 1e-9 * (1 + s.pdf));
                EXPECT_NEAR(s.pdfRev, b.pdf(s.wi, wo, TransportMode::Importance), 1e-9 * (1 + s.pdfRev));
                *w = s.wi;
                return true;
            };
            // Against the analytic density (the implementation's pdf() is compared
            // pointwise elsewhere): Lambert's is |cos| / pi on the reflection side.
            auto pdf = [&](const Vec3 &wi) -> Float {
                if (which) return wi.z * wo.z > 0 ? std::abs(wi.z) * InvPi : 0;
                return an.pdf(wo, wi);
            };
            auto r = chi2::SphericalTest(sample, pdf, o);
            EXPECT_TRUE(r.pass) << (which ? "lambert" : "analytic") << " wo " << wo << ": " << r.message;
            std::printf("%s wo.z %.2f: %s\n", which ? "lambert" : "analytic", wo.z, r.message.c_str());
        }
    }
    // Power: the same test rejects a density whose first azimuthal term is off by 0.1.
    Analytic wrong = an;
    wrong.gR[0] += 0.1;
    wrong.gT[0] += 0.1;
    Vec3 wo = wos[1];
    auto sample = [&](RNG &rng, Vec3 *w) {
        BSDFSample s;
        if (!b3.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &s))
            return false;
        *w = s.wi;
        return true;
    };
    auto r = chi2::SphericalTest(sample, [&](const Vec3 &wi) { return wrong.pdf(wo, wi); }, o);
    EXPECT_FALSE(r.pass) << "a wrong azimuthal density passed: " << r.message;
}

TEST(Fourier, SamplingMatchesPdfWithoutZeroNode) {
    // Without the +-0 pair the splines cross the kink at mu_i = 0 (and the jump at
    // mu_o = 0 is avoided by the per-hemisphere mu_o stencil): not exact any more, but
    // sample() must still follow pdf(), also for |mu_o| below the first node.
    Analytic an;
    auto t3 = Load("analytic-nozero.bsdf", an.spec(NodesWithoutZero(kK)));
    auto tl = Load("lambert-nozero.bsdf", LambertSpec(1, NodesWithoutZero(kK)));
    FourierBxDF b3(t3.get()), bl(tl.get());
    std::vector<Float> cs{0.7, 0.01, -0.3};
    chi2::Options o;
    o.xBins = 10;
    o.yBins = 24;
    o.samples = 100000;
    o.alpha = chi2::SidakAlpha(0.01, int(2 * cs.size()));
    for (Float c : cs) {
        Vec3 wo = SphericalDirection(std::sqrt(1 - c * c), c, 1.3);
        for (int which = 0; which < 2; ++which) {
            const FourierBxDF &b = which ? bl : b3;
            auto sample = [&](RNG &rng, Vec3 *w) {
                BSDFSample s;
                if (!b.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &s))
                    return false;
                *w = s.wi;
                return true;
            };
            auto r = chi2::SphericalTest(sample, [&](const Vec3 &wi) { return b.pdf(wo, wi, TransportMode::Radiance); },
                                         o);
            EXPECT_TRUE(r.pass) << (which ? "lambert" : "analytic") << " wo " << wo << ": " << r.message;
            std::printf("no zero node, %s wo.z %.2f: %s\n", which ? "lambert" : "analytic", wo.z, r.message.c_str());
        }
    }
}

TEST(Fourier, WhiteFurnaceAndEtaScaling) {
    // Lambert with albedo 1: every sample's weight f |cos| / pdf is the albedo.
    auto tl = Load("lambert-furnace.bsdf", LambertSpec(1));
    FourierBxDF bl(tl.get());
    for (Float c : {0.95, 0.5, 0.1, 0.02, -0.3}) {
        Vec3 wo = SphericalDirection(std::sqrt(1 - c * c), c, 2.0);
        RNG rng(3);
        double sum = 0, maxW = 0;
        const int n = 20000;
        for (int k = 0; k < n; ++k) {
            BSDFSample s;
            if (!bl.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &s))
                continue;
            double w = s.f.r * std::abs(s.wi.z) / s.pdf;
            sum += w;
            maxW = std::max(maxW, w);
        }
        EXPECT_NEAR(sum / n, 1, 1e-4) << "cos " << c;
        EXPECT_LE(maxW, 1 + 1e-4) << "cos " << c;
    }
    // Three-channel table, radiance transport: reflected albedo pi G_R plus transmitted
    // pi G_T (eta_o/eta_i)^2 in red. z-test at 5 sigma (two-sided false positive rate
    // 6e-7); power: omitting the eta scaling moves the mean by more than 10 sigma.
    Analytic an;
    auto t3 = Load("analytic-furnace.bsdf", an.spec());
    FourierBxDF b3(t3.get());
    for (Float c : {0.8, 0.3, 0.03, -0.6}) {
        Vec3 wo = SphericalDirection(std::sqrt(1 - c * c), c, 0.4);
        Float e = c > 0 ? 1 / an.eta : an.eta;  // transmitted light arrives from the other side
        Float expect = an.red * Pi * (an.G(true, c) + an.G(false, c) * e * e);
        Float unscaled = an.red * Pi * (an.G(true, c) + an.G(false, c));
        RNG rng(5);
        const int n = 40000;
        double sum = 0, sum2 = 0;
        for (int k = 0; k < n; ++k) {
            BSDFSample s;
            double w = 0;
            if (b3.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &s))
                w = s.f.r * std::abs(s.wi.z) / s.pdf;
            sum += w;
            sum2 += w * w;
        }
        double mean = sum / n, sigma = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
        EXPECT_LT(std::abs(mean - expect), 5 * sigma + 1e-9) << "cos " << c << " mean " << mean << " expect " << expect;
        EXPECT_GT(std::abs(unscaled - expect), 10 * sigma) << "test without power at cos " << c;
    }
}

// ---- the material and its errors ------------------------------------------------

namespace {

MaterialDesc ParseMaterial(const std::string &text, SceneDesc *scene = nullptr,
                           const std::string &dir = ".") {
    SceneDesc s = ParseString("WorldBegin\n" + text + "\nWorldEnd\n", "test.pbrt", dir);
    EXPECT_FALSE(s.materials.empty());
    MaterialDesc d = s.materials.at(0);
    if (scene) *scene = std::move(s);
    return d;
}

std::string Quote(const std::string &path) { return "\"" + path + "\""; }

// Creating a fourier material on `path` fails with a located error mentioning `what`.
void ExpectFileError(const std::string &path, const std::string &what) {
    MaterialDesc d = ParseMaterial("Material \"fourier\" \"string bsdffile\" " + Quote(path));
    try {
        CreateMaterial(d, {}, {});
        FAIL() << "no error for " << path;
    } catch (const Error &e) {
        std::string m = e.what();
        EXPECT_NE(m.find("test.pbrt:2:"), std::string::npos) << m;
        EXPECT_NE(m.find(what), std::string::npos) << m;
    }
}

}  // namespace

TEST(FourierMaterial, ResolvesAgainstSceneDirectoryAndBuildsBSDF) {
    WriteFile("rel-lambert.bsdf", Serialize(LambertSpec(0.5f)));
    SceneDesc scene;
    MaterialDesc d =
        ParseMaterial("Material \"fourier\" \"string bsdffile\" \"rel-lambert.bsdf\"", &scene, Dir().string());
    auto m = CreateMaterial(d, {}, {}, &scene);
    d.params.checkUnused("Material \"fourier\"");
    EXPECT_EQ(m->minRoughness(), 1);
    EXPECT_FALSE(m->hasTextures());
    SurfaceInteraction si;
    si.n = si.shading.n = Normal3(0, 0, 1);
    si.dpdu = si.shading.dpdu = Vec3(1, 0, 0);
    si.dpdv = si.shading.dpdv = Vec3(0, 1, 0);
    Arena arena;
    BSDF bsdf = m->getBSDF(si, arena, TransportMode::Radiance);
    ASSERT_TRUE(bsdf);
    EXPECT_EQ(bsdf.roughnessClass(kDefaultShiftThreshold), RoughnessClass::Rough);
    Vec3 wo = Normalize(Vec3(0.3, 0.1, 0.9)), wi = Normalize(Vec3(-0.5, 0.2, 0.6));
    EXPECT_NEAR(bsdf.f(wo, wi).g, 0.5 * InvPi, 1e-6);
    EXPECT_EQ(bsdf.f(wo, -wi).g, 0);
    // Without the scene directory the relative name does not resolve.
    EXPECT_THROW(CreateMaterial(d, {}, {}), Error);
}

TEST(FourierMaterial, BadInputIsLocatedError) {
    const std::string good = Serialize(LambertSpec(0.5f));
    // Parameters: missing file name, missing file, misspelt parameter left unused.
    {
        MaterialDesc d = ParseMaterial("Material \"fourier\"");
        try {
            CreateMaterial(d, {}, {});
            FAIL() << "no error without bsdffile";
        } catch (const Error &e) {
            EXPECT_NE(std::string(e.what()).find("test.pbrt:2:"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("bsdffile"), std::string::npos) << e.what();
        }
    }
    ExpectFileError((Dir() / "no-such-file.bsdf").string(), "cannot open");
    // Header defects.
    std::string s = good;
    s[3] = 'X';
    ExpectFileError(WriteFile("magic.bsdf", s), "SCATFUN");
    s = good;
    s[7] = 2;
    ExpectFileError(WriteFile("version.bsdf", s), "version");
    ExpectFileError(WriteFile("short-header.bsdf", good.substr(0, 40)), "too short");
    ExpectFileError(WriteFile("truncated.bsdf", good.substr(0, good.size() - 30)), "truncated");
    ExpectFileError(WriteFile("longer.bsdf", good + "xxxx"), "describes");
    auto patch32 = [&](size_t at, uint32_t v) {
        std::string t = good;
        for (int k = 0; k < 4; ++k) t[at + k] = char((v >> (8 * k)) & 0xff);
        return t;
    };
    ExpectFileError(WriteFile("nmu.bsdf", patch32(12, 41)), "describes");               // nMu
    ExpectFileError(WriteFile("nmu-neg.bsdf", patch32(12, uint32_t(-5))), "nMu");       // nMu < 2
    ExpectFileError(WriteFile("channels.bsdf", patch32(24, 2)), "nChannels");
    ExpectFileError(WriteFile("bases.bsdf", patch32(28, 3)), "nBases");
    ExpectFileError(WriteFile("flags.bsdf", patch32(8, 3)), "harmonic");
    ExpectFileError(WriteFile("eta.bsdf", patch32(44, 0x7fc00000u)), "eta");            // NaN
    // Body defects: node order, offsets outside the coefficients, non-finite values.
    const size_t nMu = 2 * kK + 2, muAt = 64, cdfAt = muAt + 4 * nMu, tabAt = cdfAt + 4 * nMu * nMu,
                 coefAt = tabAt + 8 * nMu * nMu;
    ExpectFileError(WriteFile("order.bsdf", patch32(muAt + 4 * 5, 0x3f000000u)), "not increasing");  // 0.5
    ExpectFileError(WriteFile("range.bsdf", patch32(muAt, 0xc0000000u)), "[-1, 1]");                 // -2
    {
        std::string z = good;  // +0 before -0: the hemispheres' node ranges would interleave
        for (int k = 0; k < 4; ++k) z[muAt + 4 * kK + k] = k == 3 ? char(0x00) : z[muAt + 4 * kK + k];
        for (int k = 0; k < 4; ++k) z[muAt + 4 * (kK + 1) + k] = k == 3 ? char(0x80) : 0;
        ExpectFileError(WriteFile("zero-order.bsdf", z), "follows +0");
    }
    ExpectFileError(WriteFile("cdf.bsdf", patch32(cdfAt + 4 * 7, 0x7f800000u)), "cdf");
    ExpectFileError(WriteFile("offset.bsdf", patch32(tabAt + 8 * 3, 1u << 20)), "outside");
    ExpectFileError(WriteFile("length.bsdf", patch32(tabAt + 8 * 3 + 4, 9)), "mMax");
    ExpectFileError(WriteFile("coef.bsdf", patch32(coefAt + 4 * 2, 0xff800000u)), "not finite");
}

TEST(FourierMaterial, RandomCorruptionNeverCrashes) {
    // Random byte damage anywhere in a valid three-channel file: each variant either
    // loads (and then evaluates and samples to finite values) or raises Error.
    Analytic an;
    const std::string good = Serialize(an.spec());
    RNG rng(2024);
    int loaded = 0, rejected = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::string s = good;
        int nFlips = 1 + int(rng.uniform() * 4);
        for (int k = 0; k < nFlips; ++k) {
            size_t at = size_t(rng.uniform() * s.size());
            s[at] = char(rng.uniformU32() & 0xff);
        }
        if (trial % 10 == 0) s.resize(size_t(rng.uniform() * s.size()));
        std::shared_ptr<const FourierTable> t;
        try {
            t = FourierTable::Read(WriteFile("fuzz.bsdf", s), FileLoc());
        } catch (const Error &) {
            ++rejected;
            continue;
        }
        ++loaded;
        FourierBxDF b(t.get());
        for (int k = 0; k < 20; ++k) {
            Vec3 wo = RandomDir(rng), wi = RandomDir(rng);
            ASSERT_TRUE(b.f(wo, wi, TransportMode::Radiance).isFinite());
            ASSERT_TRUE(std::isfinite(b.pdf(wo, wi, TransportMode::Radiance)));
            BSDFSample smp;
            if (b.sample(wo, rng.uniform(), Point2(rng.uniform(), rng.uniform()), TransportMode::Radiance, &smp)) {
                ASSERT_TRUE(smp.f.isFinite());
                ASSERT_TRUE(std::isfinite(smp.pdf) && smp.pdf > 0);
                ASSERT_TRUE(smp.wi.isFinite());
            }
        }
    }
    std::printf("corrupt variants: %d loaded, %d rejected\n", loaded, rejected);
    EXPECT_GT(rejected, 0);
}

TEST(FourierMaterial, ConvexFurnaceSceneRendersAlbedo) {
    // A sphere filling the view under uniform light L = 1: a convex surface sees only
    // the sky, so every pixel is the albedo. The three-channel Lambert table's albedo
    // (0.6, 0.5, 0.4) comes back through the scene builder (bsdffile resolved against
    // the scene directory), path and bdpt. z-test at 5 sigma per channel; power: a 2%
    // albedo error lies more than 8 standard errors away.
    const Spectrum rho(0.6, 0.5, 0.4);
    TableSpec t = LambertSpec(1);
    t.nChannels = 3;
    t.series = [rho](float muO, float muI, int *len) {
        *len = 0;
        if (!Reflection(muO, muI) || muI == 0) return std::vector<float>();
        *len = 1;
        Float a = std::abs(muI) * InvPi;
        return std::vector<float>{float(rho.y() * a), float(rho.r * a), float(rho.b * a)};
    };
    WriteFile("scene-lambert.bsdf", Serialize(t));
    const std::string scene = test::TestSceneHeader("0 0 5  0 0 0  0 1 0", 20, 32, 32, "Integrator \"path\"") +
                              "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                              "Material \"fourier\" \"string bsdffile\" \"scene-lambert.bsdf\"\n"
                              "Shape \"sphere\" \"float radius\" [1]\nWorldEnd\n";
    for (const char *integrator : {"path", "bdpt"}) {
        SceneDesc desc = ParseString(scene, "test.pbrt", Dir().string());
        test::TestRender r = test::RenderTestDesc(desc, 128, 1, 0, integrator);
        for (int c = 0; c < 3; ++c) {
            double s1 = 0, s2 = 0;
            int n = 0;
            for (int y = 4; y < 28; ++y)
                for (int x = 4; x < 28; ++x, ++n) {
                    double v = r.image.at(x, y, c);
                    s1 += v;
                    s2 += v * v;
                }
            double mean = s1 / n, se = std::sqrt(std::max(0.0, s2 / n - mean * mean) / (n - 1));
            EXPECT_LT(std::abs(mean - rho[c]), 5 * se + 1e-6)
                << integrator << " channel " << c << ": " << mean << " vs " << rho[c] << " (se " << se << ")";
            EXPECT_LT(8 * se, 0.02 * rho[c]) << integrator << " channel " << c << ": no power";
            std::printf("%s channel %d: mean %.5f expect %.2f se %.2g\n", integrator, c, mean, rho[c], se);
        }
    }
    // A corrupt file reached through the scene builder is a located error.
    WriteFile("scene-lambert.bsdf", Serialize(t).substr(0, 100));
    try {
        test::RenderTestDesc(ParseString(scene, "test.pbrt", Dir().string()), 1, 1, 0, "path");
        FAIL() << "corrupt bsdffile accepted";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("test.pbrt:10:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    }
}
