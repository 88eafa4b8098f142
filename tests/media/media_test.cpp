// Media core: the HG phase function, homogeneous and grid media against
// closed forms, Scene::transmittance through interfaces, and the located
// errors of bad medium descriptions.
//
// Statistical checks are two-sided z-tests with a fixed seed at |z| < 4.4
// (false-positive rate 1e-5 per check); each also shows that a 2% bias of
// the expected value would be detected (|z| of the biased value > 4.4).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.h"
#include "media/medium.h"
#include "parser/scene_desc.h"
#include "scene/scene.h"
#include "job/job.h"
#include "common/chi2_test.h"

using namespace gradus;

namespace {

struct Moments {
    double n = 0, s = 0, s2 = 0;
    void add(double v) {
        n += 1;
        s += v;
        s2 += v * v;
    }
    double mean() const { return s / n; }
    double se() const { return std::sqrt(std::max(0.0, s2 / n - mean() * mean()) / (n - 1)); }
};

// Passes when `m` agrees with `expected` and would not agree with expected * 1.02.
void ExpectUnbiased(const Moments &m, double expected, const std::string &what) {
    const double se = std::max(m.se(), 1e-12);
    EXPECT_LT(std::abs(m.mean() - expected) / se, 4.4)
        << what << ": mean " << m.mean() << " expected " << expected << " se " << se;
    EXPECT_GT(std::abs(m.mean() - 1.02 * expected) / se, 4.4) << what << ": too few samples to see a 2% bias";
}

}  // namespace

TEST(HGPhase, SamplingMatchesDensityChiSquare) {
    const double gs[] = {-0.7, 0.0, 0.3, 0.9};
    for (double g : gs) {
        HGPhase ph;
        ph.g = g;
        const Vec3 wo = Normalize(Vec3(0.3, -0.2, 0.9));
        chi2::Options o;
        o.alpha = chi2::SidakAlpha(0.01, 4);
        o.xBins = 20;
        o.yBins = 20;
        auto r = chi2::SphericalTest(
            [&](RNG &rng, Vec3 *w) {
                const Float pdf = ph.sample(wo, Point2(rng.uniform(), rng.uniform()), w);
                return pdf > 0 && std::abs(pdf - ph.p(wo, *w)) <= 1e-9 * pdf;
            },
            [&](const Vec3 &w) { return ph.p(wo, w); }, o);
        EXPECT_TRUE(r.pass) << "g " << g << ": " << r.message;
    }
}

TEST(HGPhase, NormalisedAndForwardPeaked) {
    for (double g : {-0.5, 0.0, 0.4, 0.95}) {
        // Integral over the sphere of HG(cos): 2 pi int_{-1}^{1} HG(c) dc (midpoint rule).
        const int n = 200000;
        double sum = 0;
        for (int i = 0; i < n; ++i) sum += HenyeyGreenstein(-1 + (i + 0.5) * 2.0 / n, g) * 2.0 / n;
        EXPECT_NEAR(2 * Pi * sum, 1.0, 2e-4) << "g " << g;
    }
    // Forward scattering (g > 0): wi along the propagation direction -wo is the peak.
    HGPhase ph;
    ph.g = 0.6;
    const Vec3 wo(0, 0, 1);
    EXPECT_GT(ph.p(wo, Vec3(0, 0, -1)), ph.p(wo, Vec3(0, 0, 1)) * 10);
}

TEST(HomogeneousMedium, TransmittanceIsExponential) {
    HomogeneousMedium m(Spectrum(0.1, 0.5, 2.0), Spectrum(0.4, 0.0, 1.0), 0.2);
    RNG rng(1);
    // d not unit: tMax is in units of |d|.
    const Ray r(Point3(0, 0, 0), Vec3(0, 0, 2), 1.5);
    const Spectrum tr = m.Tr(r, rng);
    EXPECT_NEAR(tr.r, std::exp(-0.5 * 3), 1e-12);
    EXPECT_NEAR(tr.g, std::exp(-0.5 * 3), 1e-12);
    EXPECT_NEAR(tr.b, std::exp(-3.0 * 3), 1e-12);
    EXPECT_EQ(m.Tr(Ray(Point3(0, 0, 0), Vec3(1, 0, 0), Infinity), rng).maxComponent(), 0);
}

// Medium::sample's throughput factors integrate the transport along the ray:
// E[f 1_pass] = Tr(D) and E[f 1_scatter] = sigma_s / sigma_t (1 - Tr(D)), per
// channel, with a chromatic sigma_t (the spectral MIS of the channel choice).
TEST(HomogeneousMedium, DistanceSamplingIsUnbiased) {
    const Spectrum sa(0.2, 0.6, 1.5), ss(0.8, 0.3, 0.5);
    HomogeneousMedium m(sa, ss, 0.0);
    const double D = 1.3;
    const Ray r(Point3(0, 0, 0), Vec3(0, 1, 0), D);
    RNG rng(7);
    Moments pass[3], scat[3];
    for (int i = 0; i < 400000; ++i) {
        MediumInteraction mi;
        const Spectrum f = m.sample(r, rng, &mi);
        for (int c = 0; c < 3; ++c) {
            pass[c].add(mi.valid() ? 0 : f[c]);
            scat[c].add(mi.valid() ? f[c] : 0);
        }
        if (mi.valid()) {
            ASSERT_TRUE(mi.p.y >= 0 && mi.p.y < D);
        }
    }
    for (int c = 0; c < 3; ++c) {
        const double st = sa[c] + ss[c];
        ExpectUnbiased(pass[c], std::exp(-st * D), "pass channel " + std::to_string(c));
        ExpectUnbiased(scat[c], ss[c] / st * (1 - std::exp(-st * D)), "scatter channel " + std::to_string(c));
    }
}

namespace {
// A grid varying along x only (ny = nz = 1), seen along the x axis through the
// centre of y and z, where the trilinear interpolation is exactly the 1-D
// piecewise-linear one through the voxel centres; beyond the outer centres it
// blends with the zero outside the grid, reaching d/2 at the faces. Optical
// depth over the unit grid: trapezoids between the centres plus the two
// half-voxel ramps (d/2 to d over h/2: 3/8 h d).
double OpticalDepthAlongX(const std::vector<Float> &d, double sigmaT, double worldLength) {
    const int n = int(d.size());
    const double h = 1.0 / n;
    double tau = 0.375 * h * (d.front() + d.back());
    for (int i = 0; i + 1 < n; ++i) tau += h * 0.5 * (d[i] + d[i + 1]);
    return tau * sigmaT * worldLength;
}
}  // namespace

TEST(GridMedium, RatioAndDeltaTrackingMatchAnalyticTransmittance) {
    const std::vector<Float> dens = {0.2, 1.0, 0.0, 0.5, 2.0, 0.7};
    // Medium space [p0, p1] = [-1, 2] x [0, 1] x [0, 1], placed by a transform (x scaled by 2 in world).
    const Transform worldFromMedium = Translate(Vec3(0.5, 0, 0)) * Scale(2, 1, 1);
    const Spectrum sa(0.1), ss(0.2);
    GridMedium m(sa, ss, 0.0, worldFromMedium, Point3(-1, 0, 0), Point3(2, 0, 0) + Vec3(0, 1, 1), int(dens.size()), 1,
                 1, dens);
    // World extent along x: medium x in [-1, 2] -> world [-1.5, 4.5] (length 6).
    const double tau = OpticalDepthAlongX(dens, 0.3, 6.0);
    const Ray r(Point3(-3, 0.5, 0.5), Vec3(10, 0, 0), 1.0);  // from x = -3 to x = 7: through the whole grid
    RNG rng(11);
    Moments tr, pass, albedo;
    for (int i = 0; i < 300000; ++i) {
        tr.add(m.Tr(r, rng).r);
        MediumInteraction mi;
        const Spectrum f = m.sample(r, rng, &mi);
        pass.add(mi.valid() ? 0.0 : 1.0);
        if (mi.valid()) {
            ASSERT_NEAR(f.r, 0.2 / 0.3, 1e-12);
            ASSERT_TRUE(mi.p.x >= -1.5 && mi.p.x <= 4.5);
        } else {
            ASSERT_EQ(f.r, 1.0);
        }
    }
    ExpectUnbiased(tr, std::exp(-tau), "ratio tracking");
    ExpectUnbiased(pass, std::exp(-tau), "delta tracking: no collision");
    // Outside the grid the medium is empty.
    RNG rng2(3);
    EXPECT_EQ(m.Tr(Ray(Point3(-3, 5, 0.5), Vec3(10, 0, 0), 1.0), rng2).r, 1.0);
}

// Oblique rays (all signs of direction) through an irregular grid: the
// majorant-cell traversal against the optical depth integrated numerically
// along the ray (midpoint rule, 20000 steps, through GridMedium::density).
TEST(GridMedium, ObliqueRaysThroughMajorantCells) {
    const int nx = 19, ny = 7, nz = 23;
    std::vector<Float> dens(size_t(nx) * ny * nz);
    RNG g(99);
    for (Float &v : dens) v = g.uniform() < 0.7 ? 0.0 : 3 * g.uniform();  // mostly empty, like smoke
    const Transform worldFromMedium = Translate(Vec3(0.2, -0.1, 0.3)) * Scale(1.5, 0.8, 1.2);
    GridMedium m(Spectrum(0.3), Spectrum(0.5), 0.0, worldFromMedium, Point3(-1, -1, -1), Point3(1, 1, 1), nx, ny, nz,
                 dens);
    const Transform gridFromWorld =
        (worldFromMedium * Translate(Vec3(-1, -1, -1)) * Scale(2, 2, 2)).inverse();
    const Ray rays[] = {Ray(Point3(-3, -1.5, -2), Vec3(6, 3.1, 4.3), 1.0), Ray(Point3(2.5, 1.2, -2), Vec3(-5, -2.1, 4.9), 1.0),
                        Ray(Point3(0.1, 2, 3), Vec3(0.2, -4, -6.2), 1.0)};
    for (const Ray &r : rays) {
        const int steps = 20000;
        double tau = 0;
        const double len = r.d.length();
        for (int i = 0; i < steps; ++i) {
            const Point3 pw = r((i + 0.5) / steps);
            const Point3 pg = gridFromWorld.applyPoint(pw);
            if (pg.x < 0 || pg.y < 0 || pg.z < 0 || pg.x > 1 || pg.y > 1 || pg.z > 1) continue;
            tau += m.density(pg) * 0.8 * len / steps;
        }
        ASSERT_GT(tau, 0.3);
        RNG rng(17);
        Moments tr, pass;
        for (int i = 0; i < 200000; ++i) {
            tr.add(m.Tr(r, rng).r);
            MediumInteraction mi;
            m.sample(r, rng, &mi);
            pass.add(mi.valid() ? 0.0 : 1.0);
        }
        ExpectUnbiased(tr, std::exp(-tau), "ratio tracking, oblique");
        ExpectUnbiased(pass, std::exp(-tau), "delta tracking, oblique");
    }
}

namespace {
std::string Header(const std::string &extra = "") {
    return "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [30]\n"
           "Film \"image\" \"integer xresolution\" [8] \"integer yresolution\" [8]\n" +
           extra;
}
// The error text of building a scene, or "" when it builds.
std::string BuildError(const std::string &text) {
    try {
        SceneDesc d = ParseString(text, "test.pbrt", ".");
        BuildScene(d, Point2i{8, 8});
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}
const char *kBox =
    "Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  2 3 7 2 7 6  1 2 6 1 6 5  "
    "0 4 7 0 7 3]\n  \"point P\" [-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1]\n";
}  // namespace

TEST(MediumErrors, BadDescriptionsAreLocated) {
    struct Case {
        std::string medium, where, words;
    };
    const Case cases[] = {
        {"MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n  \"rgb sigma_a\" [-1 0 0]\n", "test.pbrt:5:3",
         "sigma_a"},
        {"MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n  \"string preset\" \"Ketchupp\"\n", "test.pbrt:5:3",
         "unknown preset"},
        {"MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n  \"float g\" [1]\n", "test.pbrt:5:3", "\"g\""},
        {"MakeNamedMedium \"m\" \"string type\" \"fog\"\n", "test.pbrt:4:1", "unknown medium type"},
        {"MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"integer nx\" [2]\n  \"float density\" [1 2 3]\n",
         "test.pbrt:5:3", "nx*ny*nz = 2"},
        {"MakeNamedMedium \"m\" \"string type\" \"heterogeneous\"\n  \"rgb sigma_a\" [1 2 3] \"float density\" [1]\n",
         "test.pbrt:5:3", "spectrally uniform"},
        {"MakeNamedMedium \"m\" \"string type\" \"heterogeneous\" \"float density\"\n  [-1]\n", "test.pbrt:4:",
         "non-negative"},
        {"MakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n  \"float sigma\" [1]\n", "test.pbrt:5:3",
         "not used"},
    };
    for (const Case &c : cases) {
        const std::string text = Header(c.medium) + "WorldBegin\nAttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"\"\n" +
                                 kBox + "AttributeEnd\nWorldEnd\n";
        const std::string err = BuildError(text);
        EXPECT_NE(err.find(c.where), std::string::npos) << c.medium << " -> " << err;
        EXPECT_NE(err.find(c.words), std::string::npos) << c.medium << " -> " << err;
    }
    // An unknown medium name at its use.
    const std::string err = BuildError(Header() + "WorldBegin\nMediumInterface \"nope\" \"\"\nMaterial \"\"\n" +
                                       std::string(kBox) + "WorldEnd\n");
    EXPECT_NE(err.find("test.pbrt:"), std::string::npos) << err;
    EXPECT_NE(err.find("nope"), std::string::npos) << err;
}

// Scene::transmittance crosses interfaces (product of the segments' Tr, the
// medium switching at transitions) and stops at surfaces with a material.
TEST(SceneTransmittance, CrossesInterfacesAndStopsAtSurfaces) {
    const std::string text =
        Header("MakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.3 0.3 0.3] "
               "\"rgb sigma_s\" [0.2 0.2 0.2]\n") +
        "WorldBegin\nAttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"\"\n" + kBox +
        "AttributeEnd\nAttributeBegin\nMaterial \"matte\"\nTranslate 0 5 0\nShape \"sphere\" \"float radius\" [0.5]\n"
        "AttributeEnd\nWorldEnd\n";
    SceneDesc d = ParseString(text, "test.pbrt", ".");
    auto scene = BuildScene(d, Point2i{8, 8});
    ASSERT_TRUE(scene->features.media);
    RNG rng(5);
    auto at = [](Point3 p) { return Interaction(p, Normal3(0, 0, 0), Vec3(0, 0, 1)); };
    // Through the box along x: a chord of length 2 in the medium (sigma_t 0.5).
    Spectrum tr = scene->transmittance(at(Point3(-3, 0.2, 0.1)), nullptr, at(Point3(3, 0.2, 0.1)), rng);
    EXPECT_NEAR(tr.g, std::exp(-0.5 * 2), 1e-6);
    // From inside the box to outside: 1 unit of medium.
    tr = scene->transmittance(at(Point3(0, 0.2, 0.1)), scene->media[0].get(), at(Point3(3, 0.2, 0.1)), rng);
    EXPECT_NEAR(tr.g, std::exp(-0.5 * 1), 1e-6);
    // Blocked by the sphere.
    tr = scene->transmittance(at(Point3(0, 3, 0)), nullptr, at(Point3(0, 7, 0)), rng);
    EXPECT_EQ(tr.maxComponent(), 0);
}

TEST(MediumPresets, KnownNamesAndUnits) {
    Spectrum sa, ss;
    ASSERT_TRUE(MediumPreset("Ketchup", &sa, &ss));
    EXPECT_DOUBLE_EQ(ss.r, 0.18);
    EXPECT_DOUBLE_EQ(sa.b, 1.45);
    EXPECT_FALSE(MediumPreset("ketchup", &sa, &ss));  // names are case-sensitive, as in pbrt-v3
    EXPECT_EQ(MediumPresetNames().size(), 47u);
}
