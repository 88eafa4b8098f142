// Hair (Chiang et al. 2016 as pbrt-v3 implements it): energy by quadrature over
// the sphere (white furnace; with absorption the integral equals the sum of the
// A_p), the pdf's normalisation, sample() against pdf() by chi-square, sample
// weights f cos / pdf (exactly 1 without absorption), the mirror symmetry the
// model has (reciprocity it does not have), the R lobe's peak at a curve hit
// where pbrt-v3's h puts it, the adjoint, bdpt against path, and the material's
// located errors.
#include <gtest/gtest.h>

#include <cmath>

#include "common/render_test_util.h"
#include "core/error.h"
#include "materials/hair.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"
#include "shapes/curve.h"

namespace gradus {
namespace {

Vec3 Dir(Float sinTheta, Float phi) {
    const Float c = SafeSqrt(1 - sinTheta * sinTheta);
    return Vec3(sinTheta, c * std::cos(phi), c * std::sin(phi));
}

// Midpoint quadrature over the sphere in (theta in [-pi/2, pi/2], phi) with the
// measure cos(theta) dtheta dphi; g(wi) is integrated. n x 2n cells.
template <typename G>
auto SphereQuadrature(G g, int n) {
    decltype(g(Vec3())) sum{};
    const double dt = Pi / n, dp = 2 * Pi / (2 * n);
    for (int i = 0; i < n; ++i) {
        const double theta = -Pi / 2 + (i + 0.5) * dt, st = std::sin(theta), ct = std::cos(theta);
        decltype(g(Vec3())) row{};
        for (int j = 0; j < 2 * n; ++j) row += g(Dir(st, (j + 0.5) * dp));
        sum += row * ct;
    }
    return sum * dt * dp;
}

struct Case {
    Float betaM, betaN, h, alpha, sinThetaO, phiO;
};
// Roughnesses from 0.2 up (the quadrature below resolves lobes of that width),
// offsets across the fibre, tilts and outgoing elevations.
const Case kCases[] = {  // alpha in degrees
    {0.3, 0.3, 0.0, 2, 0.0, 0.3},  {0.3, 0.3, 0.5, 2, 0.4, 1.0},   {0.2, 0.5, -0.7, 2, -0.6, 2.0},
    {0.5, 0.2, 0.9, 0, 0.8, -1.0}, {0.8, 0.8, -0.3, 5, -0.2, 0.0}, {0.25, 0.9, 0.95, 2, 0.95, 4.0},
};

// Quadrature error for these lobes at n = 400 (cell 0.0079 rad, lobes >= 0.05 rad
// wide): below 1e-4 in every case; the tolerance is 1e-3.
constexpr int kN = 400;
constexpr double kQuadTol = 1e-3;

TEST(Hair, WhiteFurnaceByQuadrature) {
    double worst = 0;
    for (const Case &c : kCases) {
        HairBxDF hair(c.h, 1.55, Spectrum(0), c.betaM, c.betaN, c.alpha);
        const Vec3 wo = Dir(c.sinThetaO, c.phiO);
        const double e = SphereQuadrature(
            [&](const Vec3 &wi) { return hair.f(wo, wi, TransportMode::Radiance).g * std::abs(wi.z); }, kN);
        EXPECT_NEAR(e, 1, kQuadTol) << "beta_m " << c.betaM << " beta_n " << c.betaN << " h " << c.h;
        worst = std::max(worst, std::abs(e - 1));
    }
    std::printf("largest |furnace - 1|: %.2e\n", worst);
    // A model 2% off (e.g. pbrt-v3's 10-term I0, or a tilt on theta_i) lands
    // 2e-3 to 8e-2 away: the tolerance is 1e-3.
}

TEST(Hair, AbsorbingEnergyIsTheSumOfAp) {
    const Spectrum sigma = HairBxDF::SigmaAFromConcentration(0.8, 0.3);
    double worst = 0;
    for (const Case &c : kCases) {
        HairBxDF hair(c.h, 1.55, sigma, c.betaM, c.betaN, c.alpha);
        const Vec3 wo = Dir(c.sinThetaO, c.phiO);
        const auto ap = hair.attenuation(SafeSqrt(1 - c.sinThetaO * c.sinThetaO));
        Spectrum expect(0);
        for (const Spectrum &a : ap) expect += a;
        const Spectrum e = SphereQuadrature(
            [&](const Vec3 &wi) { return hair.f(wo, wi, TransportMode::Radiance) * std::abs(wi.z); }, kN);
        EXPECT_NEAR(e.r, expect.r, kQuadTol) << "h " << c.h;
        EXPECT_NEAR(e.g, expect.g, kQuadTol) << "h " << c.h;
        EXPECT_NEAR(e.b, expect.b, kQuadTol) << "h " << c.h;
        EXPECT_LT(expect.r, 0.99);  // absorption removes energy
        worst = std::max({worst, std::abs(e.r - expect.r), std::abs(e.g - expect.g), std::abs(e.b - expect.b)});
    }
    std::printf("largest |integral - sum A_p|: %.2e\n", worst);
}

TEST(Hair, PdfIntegratesToOne) {
    double worst = 0;
    const Spectrum sigma = HairBxDF::SigmaAFromConcentration(1.3, 0);
    for (const Case &c : kCases) {
        HairBxDF hair(c.h, 1.55, sigma, c.betaM, c.betaN, c.alpha);
        const Vec3 wo = Dir(c.sinThetaO, c.phiO);
        const double e =
            SphereQuadrature([&](const Vec3 &wi) { return hair.pdf(wo, wi, TransportMode::Radiance); }, kN);
        EXPECT_NEAR(e, 1, kQuadTol);
        worst = std::max(worst, std::abs(e - 1));
    }
    std::printf("largest |pdf integral - 1|: %.2e\n", worst);
}

TEST(Hair, SampleMatchesPdfChiSquare) {
    const int n = int(std::size(kCases));
    chi2::Options o;
    o.samples = 200000;
    o.xBins = 20;
    o.yBins = 40;
    o.alpha = chi2::SidakAlpha(0.01, n);
    int k = 0;
    for (const Case &c : kCases) {
        // Alternately white and absorbing (the lobe weights differ).
        const Spectrum sigma = k % 2 ? HairBxDF::SigmaAFromConcentration(1.3, 0.2) : Spectrum(0);
        {
            HairBxDF hair(c.h, 1.55, sigma, c.betaM, c.betaN, c.alpha);
            const Vec3 wo = Dir(c.sinThetaO, c.phiO);
            o.seed = 11 + k++;
            auto r = chi2::SphericalTest(
                [&](RNG &rng, Vec3 *w) {
                    BSDFSample s;
                    const Float uc = rng.uniform();
                    const Point2 u(rng.uniform(), rng.uniform());
                    if (!hair.sample(wo, uc, u, TransportMode::Radiance, &s)) return false;
                    *w = Normalize(s.wi);
                    return true;
                },
                [&](const Vec3 &w) { return hair.pdf(wo, w, TransportMode::Radiance); }, o);
            EXPECT_TRUE(r.pass) << "h " << c.h << " beta_m " << c.betaM << ": " << r.message;
        }
    }
}

TEST(Hair, SampleWeightsAndPdfsAreConsistent) {
    RNG rng(5);
    for (const Case &c : kCases) {
        HairBxDF white(c.h, 1.55, Spectrum(0), c.betaM, c.betaN, c.alpha);
        HairBxDF brown(c.h, 1.55, HairBxDF::SigmaAFromConcentration(1.3, 0), c.betaM, c.betaN, c.alpha);
        const Vec3 wo = Dir(c.sinThetaO, c.phiO);
        for (int i = 0; i < 2000; ++i) {
            const Float uc = rng.uniform();
            const Point2 u(rng.uniform(), rng.uniform());
            BSDFSample s;
            if (white.sample(wo, uc, u, TransportMode::Radiance, &s)) {
                // Without absorption the lobe weights are the A_p: f cos / pdf = sum A_p = 1.
                const Spectrum w = s.f * std::abs(s.wi.z) / s.pdf;
                EXPECT_NEAR(w.g, 1, 1e-6);
                EXPECT_NEAR(s.pdf, white.pdf(wo, s.wi, TransportMode::Radiance), 1e-9 * s.pdf);
                EXPECT_NEAR(s.pdfRev, white.pdf(s.wi, wo, TransportMode::Radiance), 1e-9 * s.pdfRev);
            }
            if (brown.sample(wo, uc, u, TransportMode::Radiance, &s)) {
                const Spectrum w = s.f * std::abs(s.wi.z) / s.pdf;
                EXPECT_TRUE(w.isFinite());
                EXPECT_LE(w.y(), 1 + 1e-9);
            }
        }
    }
}

// Not reciprocal (the tilts and the lobe weights depend on theta_o only), but
// mirroring the azimuth with the offset maps the model onto itself:
// f(wo, wi; h) = f(M wo, M wi; -h) with M: y -> -y.
TEST(Hair, MirrorSymmetryInH) {
    RNG rng(9);
    const Spectrum sigma = HairBxDF::SigmaAFromConcentration(0.5, 0.5);
    for (int i = 0; i < 500; ++i) {
        const Float h = 2 * rng.uniform() - 1;
        HairBxDF a(h, 1.55, sigma, 0.3, 0.3, 2), b(-h, 1.55, sigma, 0.3, 0.3, 2);
        const Vec3 wo = Dir(2 * rng.uniform() - 1, 2 * Pi * rng.uniform()),
                   wi = Dir(2 * rng.uniform() - 1, 2 * Pi * rng.uniform());
        const Vec3 mo(wo.x, -wo.y, wo.z), mi(wi.x, -wi.y, wi.z);
        const Spectrum fa = a.f(wo, wi, TransportMode::Radiance), fb = b.f(mo, mi, TransportMode::Radiance);
        EXPECT_NEAR(fa.r, fb.r, 1e-9 * (1 + fa.r));
        EXPECT_NEAR(a.pdf(wo, wi, TransportMode::Radiance), b.pdf(mo, mi, TransportMode::Radiance),
                    1e-9 * (1 + fa.r));
    }
    // ... and it is not reciprocal: some pair differs by more than 1%.
    HairBxDF c(0.4, 1.55, sigma, 0.3, 0.3, 2);
    const Vec3 wo = Dir(0.3, 0.2), wi = Dir(-0.5, 2.0);
    const Spectrum f1 = c.f(wo, wi, TransportMode::Radiance) * std::abs(wi.z),
                   f2 = c.f(wi, wo, TransportMode::Radiance) * std::abs(wo.z);
    EXPECT_GT(std::abs(f1.g - f2.g), 0.01 * f1.g);
}

std::unique_ptr<Scene> Build(const std::string &world);

// pbrt-v3's h at a curve hit (shapes/curve.h: v > 1/2 on the side of d x T, h =
// -1 + 2 v) and Chiang's R lobe at phi_o - 2 asin(h) in the BSDF frame: seen
// normal to the fibre, a smooth, strongly absorbing fibre reflects to
// cos(psi) e + sin(psi) d_perp, psi = -90 deg - 2 asin(h), e = d x T normalised,
// d_perp = d (both normal to T). For h > 0 that is towards -e, away from the side
// of the fibre the ray passed (the mirror image of a real tube's reflection).
TEST(Hair, ReflectionPeakAtPbrtV3sOffset) {
    auto s = Build("Material \"hair\" \"float eumelanin\" 8 \"float beta_m\" 0.05 \"float beta_n\" 0.05 "
                   "\"float alpha\" 0\nShape \"curve\" \"string type\" \"cylinder\" "
                   "\"point P\" [-1 0 0 -0.3333333333333333 0 0 0.3333333333333333 0 0 1 0 0] \"float width\" 1");
    Arena arena;
    const Vec3 d(0, 0, -1), T(1, 0, 0), e = Normalize(Cross(d, T));
    for (Float y : {0.25, -0.15, 0.4}) {
        SurfaceInteraction si;
        ASSERT_TRUE(s->intersect(Ray(Point3(0.1, y, 3), d), &si));
        const Float h = -1 + 2 * si.uv.y;
        EXPECT_NEAR(h, Dot(Vec3(0, y, 0), e) / 0.5, 1e-5);  // the side of d x T
        BSDF bsdf = si.material->getBSDF(si, arena, TransportMode::Radiance);
        const Float psi = -Pi / 2 - 2 * std::asin(h);
        const Vec3 expect = e * std::cos(psi) + d * std::sin(psi);
        Float best = -1;
        Vec3 peak;
        for (int k = 0; k < 3600; ++k) {
            const Float a = 2 * Pi * k / 3600;
            const Vec3 wi(0, std::cos(a), std::sin(a));
            const Float f = bsdf.f(si.wo, wi).g * std::abs(Dot(wi, si.shading.n));
            if (f > best) best = f, peak = wi;
        }
        EXPECT_GT(Dot(peak, expect), std::cos(Radians(2))) << "y " << y << " peak " << peak << " expect " << expect;
        arena.reset();
    }
}

// At a hit the material's BSDF is Chiang's with the hit's h, S(wo, wi) / |cos wi|;
// Importance mode swaps S's directions and still divides by |cos wi|: S(wi, wo)
// = f(wi, wo) |cos wo| (the same h), so the normal (on curves only pbrt-v3's
// convention) drops out of light subpaths too.
TEST(Hair, AdjointSwapsTheDirections) {
    auto s = Build("Material \"hair\" \"float eumelanin\" 0.8\nShape \"curve\" \"string type\" \"cylinder\" "
                   "\"point P\" [-1 0 0 -0.3 0 0 0.3 0 0 1 0 0] \"float width\" 0.4");
    RNG rng(4);
    Arena arena;
    const Spectrum sigma = HairBxDF::SigmaAFromConcentration(0.8, 0);
    int checked = 0;
    for (int i = 0; i < 200; ++i) {
        const Point3 o(0.4 * rng.uniform() - 0.2, 0.5 * rng.uniform() - 0.25, 3);
        SurfaceInteraction si;
        if (!s->intersect(Ray(o, Vec3(0.1, 0.05, -1)), &si)) continue;
        BSDF bsdf = si.material->getBSDF(si, arena, TransportMode::Radiance);
        ASSERT_TRUE(bsdf);
        const Vec3 wi = Normalize(Vec3(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1));
        HairBxDF fixed(-1 + 2 * si.uv.y, 1.55, sigma, 0.3, 0.3, 2);
        const Vec3 lo = bsdf.toLocal(si.wo), li = bsdf.toLocal(wi);
        const Spectrum f = bsdf.f(si.wo, wi, TransportMode::Radiance), expect = fixed.f(lo, li, TransportMode::Radiance);
        EXPECT_NEAR(f.g, expect.g, 1e-9 * (1 + expect.g));
        const Spectrum fa = bsdf.f(si.wo, wi, TransportMode::Importance),
                       ea = fixed.f(li, lo, TransportMode::Radiance) * (std::abs(lo.z) / std::abs(li.z));
        EXPECT_NEAR(fa.g, ea.g, 1e-9 * (1 + ea.g));
        ++checked;
        arena.reset();
    }
    EXPECT_GT(checked, 100);
}

std::unique_ptr<Scene> Build(const std::string &world) {
    std::string text = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" + world + "\nWorldEnd\n";
    return BuildScene(ParseString(text, "test.pbrt"), Point2i{8, 8});
}

// bdpt evaluates light-subpath vertices in Importance mode; hair is not
// reciprocal, so without the adjoint (f(wi, wo)) bdpt and path disagree. A tuft
// of 25 light hairs (multiple scattering between fibres) on a floor, lit by a
// distant light from the side and a dim environment; 12 runs of each
// integrator, Welch z per 8x8 quadrant and for the image: |z| > 5 by chance has
// probability ~4e-4 per statistic (Student t, 11 dof), ~2e-3 for the test;
// power: a 5% bias of the image must exceed the threshold. pbrt-v3's curves are
// not symmetric (rays leaving a fibre start 2 widths off it, rays arriving stop
// at the first fibre), so light-subpath vertices on fibres see their neighbours
// unlike path's: bdpt is 2% brighter in the densest quadrant (z = 3.7).
TEST(Hair, BdptAgreesWithPath) {
    std::string text = test::TestSceneHeader("0 0.55 2.2  0 0.45 0  0 1 0", 30, 16, 16, "Integrator \"path\"");
    text += "WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.2 0.2 0.2]\n"
            "LightSource \"distant\" \"point from\" [2 1.5 0.5] \"point to\" [0 0 0] \"rgb L\" [3 3 3]\n";
    text += test::Quad("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]", "-3 0 -3  -3 0 3  3 0 3  3 0 -3");
    text += "AttributeBegin\nMaterial \"hair\" \"float eumelanin\" 0.2 \"float beta_m\" 0.25 \"float beta_n\" 0.3\n";
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 5; ++j) {
            const double x = -0.3 + 0.15 * i + 0.02 * j, z = -0.3 + 0.15 * j;
            char buf[256];
            std::snprintf(buf, sizeof buf,
                          "Shape \"curve\" \"string type\" \"cylinder\" \"point P\" [%g 0 %g %g 0.3 %g %g 0.6 %g %g 0.9 %g] "
                          "\"float width0\" 0.07 \"float width1\" 0.03\n",
                          x, z, x + 0.05, z, x + 0.12, z + 0.03, x + 0.2, z + 0.05);
            text += buf;
        }
    text += "AttributeEnd\nWorldEnd\n";
    const SceneDesc desc = ParseString(text, "hair.pbrt");
    constexpr int kRuns = 12;
    constexpr double kZ = 5;
    std::vector<std::vector<double>> path(5), bdpt(5);
    for (int r = 0; r < kRuns; ++r) {
        Image a = test::RenderTestDesc(desc, 128, 1000 + r, 1, "path").image;
        Image b = test::RenderTestDesc(desc, 32, 2000 + r, 1, "bdpt").image;
        for (int q = 0; q < 4; ++q) {
            const int x0 = (q % 2) * 8, y0 = (q / 2) * 8;
            path[q].push_back(test::BlockMean(a, x0, y0, x0 + 8, y0 + 8));
            bdpt[q].push_back(test::BlockMean(b, x0, y0, x0 + 8, y0 + 8));
        }
        path[4].push_back(test::BlockMean(a, 0, 0, 16, 16));
        bdpt[4].push_back(test::BlockMean(b, 0, 0, 16, 16));
    }
    auto zscore = [](const test::RunStats &x, const test::RunStats &y) {
        return (x.mean - y.mean) / std::sqrt(x.var / x.n + y.var / y.n);
    };
    for (int q = 0; q < 5; ++q) {
        const test::RunStats sp = test::Stats(path[q]), sb = test::Stats(bdpt[q]);
        const double z = zscore(sb, sp);
        std::printf("block %d: path %.5f bdpt %.5f z %.2f\n", q, sp.mean, sb.mean, z);
        EXPECT_LT(std::abs(z), kZ) << "block " << q;
        if (q == 4) {
            test::RunStats biased = sb;
            biased.mean *= 1.05;
            biased.var *= 1.05 * 1.05;
            EXPECT_GT(std::abs(zscore(biased, sp)), kZ) << "too noisy to see a 5% bias";
        }
    }
}

void ExpectLocatedError(const std::string &material, const std::string &what) {
    try {
        Build(material + "\nShape \"curve\" \"string type\" \"cylinder\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]");
        ADD_FAILURE() << "no error for: " << material;
    } catch (const Error &e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test.pbrt:4:"), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
}

TEST(Hair, MaterialParameters) {
    // pbrt-v3's parameters build (and precedence leaves nothing unused).
    auto s = Build("Material \"hair\" \"float eumelanin\" 1.3 \"float beta_m\" 0.3 \"float beta_n\" 0.3 "
                   "\"float alpha\" 2 \"float eta\" 1.55\nShape \"curve\" \"string type\" \"cylinder\" "
                   "\"point P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"float width\" 0.1");
    EXPECT_GE(s->features.minRoughness, kDefaultShiftThreshold);
    EXPECT_NO_THROW(Build("Material \"hair\" \"rgb sigma_a\" [0.1 0.2 0.3] \"rgb color\" [0.5 0.4 0.3] "
                          "\"float pheomelanin\" 1"));
    ExpectLocatedError("Material \"hair\" \"float beta_m\" 1.5", "\"beta_m\" must be in");
    ExpectLocatedError("Material \"hair\" \"float beta_n\" -0.1", "\"beta_n\" must be in");
    ExpectLocatedError("Material \"hair\" \"float eta\" 0.5", "\"eta\" must be in");
    ExpectLocatedError("Material \"hair\" \"float eumelanin\" -1", "\"eumelanin\" must be in");
    ExpectLocatedError("Material \"hair\" \"float betam\" 0.3", "betam");
}

}  // namespace
}  // namespace gradus
