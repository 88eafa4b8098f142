// Hair (Chiang et al. 2016 as pbrt-v3 implements it): energy by quadrature over
// the sphere (white furnace; with absorption the integral equals the sum of the
// A_p), the pdf's normalisation, sample() against pdf() by chi-square, sample
// weights f cos / pdf (exactly 1 without absorption), the mirror symmetry the
// model has (reciprocity it does not have), the R lobe's peak at a curve hit
// where pbrt-v3's h puts it, the adjoint, bdpt against path, A_p against a 3-D
// trace through a smooth cylinder, sigma_a from melanin and colour against
// pbrt-v3's coefficients and Chiang Eq. 9, the parameter precedence and its
// notes, and the material's located errors.
#include <gtest/gtest.h>

#include <cmath>

#include "common/render_test_util.h"
#include "core/error.h"
#include "material_test_util.h"
#include "materials/hair.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"
#include "shapes/curve.h"

namespace gradus {
namespace {

using mattest::FresnelFromIndices;

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

// ---------------------------------------------------------------- A_p from first principles
// Chiang et al. 2016 Eq. 3-4 state A_p for a smooth dielectric cylinder: Fresnel at
// the entry, p internal chords with transmittance exp(-sigma_a l) each, p - 1
// internal reflections. Here the cylinder (unit radius, axis x) is traced in 3-D:
// Snell's law in vector form, exact unpolarised Fresnel at every interface (from
// inside too), chord lengths by ray-cylinder intersection, the orders p >= 3
// summed term by term. Nothing of the code under test (not even fresnel.h) is used.

struct V3 {
    double x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
double Dot3(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// A_0..A_3 (A_3 = all orders p >= 3) of the ray arriving along -(sin theta_o, 0,
// cos theta_o) at offset h (the point (0, h, sqrt(1 - h^2)) of the fibre).
std::array<Spectrum, 4> TracedAp(double sinThetaO, double h, double eta, const Spectrum &sigmaA) {
    std::array<Spectrum, 4> a{Spectrum(0), Spectrum(0), Spectrum(0), Spectrum(0)};
    const double cosThetaO = std::sqrt(1 - sinThetaO * sinThetaO);
    V3 d{-sinThetaO, 0, -cosThetaO}, p{0, h, std::sqrt(1 - h * h)}, n = p;
    double cosI = -Dot3(d, n);
    const double f0 = FresnelFromIndices(cosI, 1, eta);
    a[0] = Spectrum(f0);
    // Refraction into the fibre: t = d / eta + (cosI / eta - cosT) n.
    const double k = 1 / eta, cosT = std::sqrt(1 - k * k * (1 - cosI * cosI));
    d = k * d + (k * cosI - cosT) * n;
    Spectrum w(1 - f0);
    for (int order = 1; order < 100000 && std::max({w.r, w.g, w.b}) > 1e-18; ++order) {
        // Next wall: p + s d on y^2 + z^2 = 1 with p on it: s = -2 (p . d)_yz / |d_yz|^2.
        const double s = -2 * (p.y * d.y + p.z * d.z) / (d.y * d.y + d.z * d.z);
        p = p + s * d;
        w = w * Spectrum(std::exp(-sigmaA.r * s), std::exp(-sigmaA.g * s), std::exp(-sigmaA.b * s));
        n = V3{0, p.y, p.z};
        cosI = Dot3(d, n);
        const double f = FresnelFromIndices(cosI, eta, 1);
        a[std::min(order, 3)] += w * (1 - f);
        w = w * f;
        d = d + (-2 * cosI) * n;  // internal reflection
    }
    return a;
}

// Measured largest difference 1.2e-12 over 270 cases: tolerance 1e-10.
TEST(Hair, AttenuationMatchesTracedCylinder) {
    const Spectrum sigmas[] = {Spectrum(0), Spectrum(0.419, 0.697, 1.37) * 1.3, Spectrum(5, 0.05, 0.5)};
    double worst = 0;
    int n = 0;
    for (double eta : {1.55, 1.3, 2.1})
        for (double sinThetaO : {0.0, -0.35, 0.6, 0.9, 0.99})
            for (double h : {0.0, -0.5, 0.3, 0.8, -0.97, 0.999})
                for (const Spectrum &sigma : sigmas) {
                    HairBxDF hair(h, eta, sigma, 0.3, 0.3, 2);
                    const auto ap = hair.attenuation(std::sqrt(1 - sinThetaO * sinThetaO));
                    const auto ref = TracedAp(sinThetaO, h, eta, sigma);
                    Spectrum total(0);
                    for (int p = 0; p <= 3; ++p) {
                        total += ref[p];
                        for (int c = 0; c < 3; ++c) {
                            EXPECT_NEAR(ap[p][c], ref[p][c], 1e-10)
                                << "p " << p << " channel " << c << " eta " << eta << " sin theta_o " << sinThetaO
                                << " h " << h;
                            worst = std::max(worst, std::abs(ap[p][c] - ref[p][c]));
                        }
                    }
                    if (sigma.isBlack()) {
                        EXPECT_NEAR(total.g, 1, 1e-12);  // the trace conserves energy
                    }
                    ++n;
                }
    std::printf("%d cases, largest |A_p - traced|: %.2e\n", n, worst);
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

// ---------------------------------------------------------------- sigma_a and precedence
// pbrt-v3's absorption coefficients of eumelanin and pheomelanin (RGB, per unit
// concentration; hair.cpp's SigmaAFromConcentration) and Chiang Eq. 9's map from
// sigma_a to the multiple-scattering colour, written here as published.
const Spectrum kEumelanin(0.419, 0.697, 1.37), kPheomelanin(0.187, 0.4, 1.05);
double ChiangEq9Factor(double bn) {
    return 5.969 - 0.215 * bn + 2.532 * bn * bn - 10.73 * std::pow(bn, 3) + 5.574 * std::pow(bn, 4) +
           0.245 * std::pow(bn, 5);
}

TEST(Hair, SigmaAFromConcentrationAndReflectance) {
    for (auto [ce, cp] : {std::pair{1.3, 0.0}, {0.0, 1.0}, {0.7, 0.4}, {8.0, 2.5}}) {
        const Spectrum s = HairBxDF::SigmaAFromConcentration(ce, cp), e = kEumelanin * ce + kPheomelanin * cp;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s[c], e[c], 1e-12) << ce << " " << cp << " channel " << c;
    }
    // The colour is what Eq. 9 gives back: c = exp(-sqrt(sigma_a) f(beta_n)).
    for (double bn : {0.0, 0.3, 0.55, 0.9, 1.0})
        for (const Spectrum &col : {Spectrum(0.5, 0.4, 0.3), Spectrum(0.05, 0.2, 0.95), Spectrum(1)}) {
            const Spectrum s = HairBxDF::SigmaAFromReflectance(col, bn);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(std::exp(-std::sqrt(s[c]) * ChiangEq9Factor(bn)), col[c], 1e-12) << "beta_n " << bn;
                EXPECT_NEAR(s[c], Sqr(std::log(col[c]) / ChiangEq9Factor(bn)), 1e-12 * (1 + s[c]));
            }
        }
}

// pbrt-v3's CreateHairMaterial: sigma_a wins over color, color over the melanins
// (a missing melanin counts 0); none given: eumelanin 1.3. Every parameter the
// precedence ignores gets a note at its own place naming the winner. Each case's
// material is compared, at hits on a tube and for several direction pairs, with
// one given only the expected sigma_a (computed here from the published formulas).
TEST(Hair, ParameterPrecedenceAndNotes) {
    const std::string shape = "\nShape \"curve\" \"string type\" \"cylinder\" "
                              "\"point P\" [-1 0 0 -0.3 0 0 0.3 0 0 1 0 0] \"float width\" 0.4";
    const Spectrum col(0.5, 0.4, 0.3);
    auto fromColor = [&](double bn) {
        Spectrum s;
        for (int c = 0; c < 3; ++c) s[c] = Sqr(std::log(col[c]) / ChiangEq9Factor(bn));
        return s;
    };
    struct Case {
        std::string params;       // one parameter a line (lines 5, 6, ... of test.pbrt)
        Spectrum expect;
        std::vector<std::string> notes;  // "line: ignored <- winner"
    } cases[] = {
        {"\"rgb sigma_a\" [0.3 0.5 0.9]\n\"rgb color\" [0.5 0.4 0.3]\n\"float eumelanin\" 2\n\"float pheomelanin\" 0.5",
         Spectrum(0.3, 0.5, 0.9),
         {"test.pbrt:6:1: material \"hair\": \"color\" is ignored since \"sigma_a\"",
          "test.pbrt:7:1: material \"hair\": \"eumelanin\" is ignored since \"sigma_a\"",
          "test.pbrt:8:1: material \"hair\": \"pheomelanin\" is ignored since \"sigma_a\""}},
        {"\"float pheomelanin\" 0.5\n\"rgb sigma_a\" [0.3 0.5 0.9]",
         Spectrum(0.3, 0.5, 0.9),
         {"test.pbrt:5:1: material \"hair\": \"pheomelanin\" is ignored since \"sigma_a\""}},
        {"\"rgb color\" [0.5 0.4 0.3]\n\"float eumelanin\" 2", fromColor(0.3),
         {"test.pbrt:6:1: material \"hair\": \"eumelanin\" is ignored since \"color\""}},
        {"\"rgb color\" [0.5 0.4 0.3]\n\"float beta_n\" 0.6", fromColor(0.6), {}},
        {"\"float eumelanin\" 0.7\n\"float pheomelanin\" 0.4", kEumelanin * 0.7 + kPheomelanin * 0.4, {}},
        {"\"float pheomelanin\" 0.4", kPheomelanin * 0.4, {}},
        {"", kEumelanin * 1.3, {}},
    };
    auto betaN = [](const std::string &params) {
        return params.find("beta_n") != std::string::npos ? std::string("\"float beta_n\" 0.6") : std::string();
    };
    RNG rng(21);
    for (const Case &c : cases) {
        auto s = Build("Material \"hair\"\n" + c.params + shape);
        char buf[200];
        std::snprintf(buf, sizeof buf, "Material \"hair\" \"rgb sigma_a\" [%.17g %.17g %.17g] ", c.expect.r, c.expect.g,
                      c.expect.b);
        auto ref = Build(buf + betaN(c.params) + shape);
        // Notes: exactly the expected ones, in parameter order.
        ASSERT_EQ(s->notes.size(), c.notes.size()) << c.params;
        for (size_t i = 0; i < c.notes.size(); ++i)
            EXPECT_EQ(s->notes[i].rfind(c.notes[i], 0), 0u) << s->notes[i] << " / expected " << c.notes[i];
        EXPECT_TRUE(ref->notes.empty());
        Arena arena;
        int compared = 0;
        double differsFromDefault = 0;
        for (int i = 0; i < 40; ++i) {
            const Ray ray(Point3(0.4 * rng.uniform() - 0.2, 0.36 * rng.uniform() - 0.18, 3), Vec3(0, 0, -1));
            SurfaceInteraction a, b;
            if (!s->intersect(ray, &a) || !ref->intersect(ray, &b)) continue;
            const BSDF fa = a.material->getBSDF(a, arena, TransportMode::Radiance);
            const BSDF fb = b.material->getBSDF(b, arena, TransportMode::Radiance);
            const Vec3 wi = Normalize(Vec3(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1));
            const Spectrum va = fa.f(a.wo, wi), vb = fb.f(b.wo, wi);
            const Spectrum vd = HairBxDF(-1 + 2 * a.uv.y, 1.55, kEumelanin * 1.3, 0.3, 0.3, 2).f(
                fa.toLocal(a.wo), fa.toLocal(wi), TransportMode::Radiance);
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_NEAR(va[ch], vb[ch], 1e-12 * (1 + vb[ch])) << c.params << " channel " << ch;
                differsFromDefault = std::max(differsFromDefault, std::abs(vb[ch] - vd[ch]) / (vd[ch] + 1e-3));
            }
            ++compared;
            arena.reset();
        }
        EXPECT_GT(compared, 20) << c.params;
        // The comparison sees sigma_a: the cases other than the default differ from it.
        if (!c.params.empty()) {
            EXPECT_GT(differsFromDefault, 0.05) << c.params;
        }
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
