// G-BDPT with participating media (gbdpt.h "Participating media"), fast tier:
//  - the camera-subpath shift through a medium vertex b reconnecting to the
//    base's next vertex c (medium or surface): the offset's throughput ratio
//    f(y)|T'|/f(x) divided by the independently evaluated camera-weight,
//    phase-function and transmittance ratios (homogeneous fog, exact) is the
//    Jacobian |T'|, compared with central differences of the re-run shift
//    under perturbations of the base's sampled direction at b and distance to c;
//  - Eq. 8 normalisation with medium vertices: for camera paths ending on the
//    light through fog and a smoke sphere (a medium interface), the combined
//    weights of all strategies (t >= 2 from the shifted camera subpath, t = 1
//    by the light-tracing shift) times (1 + rho) sum to one, and so do the
//    BDPT weights (the O(n) enumeration of test_shift.cpp);
//  - agreement with bdpt (gpt/gpt_media_check.h: Welch tests of the primal
//    and the hybrid, L1 and L2 reconstructions, 2% power checks, and a z-test
//    of the gradients against bdpt's neighbour differences) on the smoke wedge
//    (a material-less interface inside the scene, homogeneous) and its
//    density-grid variant (ratio tracking of T_y / T_x), and the wedge with a
//    glass sphere inside the smoke, a near-specular metal sphere and an
//    environment light (first chains through Dirac and near-specular vertices
//    between medium vertices, environment shifts out of the smoke, second
//    chains through specular vertices, which fall back with media: gbdpt.h);
//    fog-box is in the slow tier (test_media_slow.cpp).
// Planted faults caught (not committed): T_y / T_x dropped on the reconnection
// segment (Jacobian test, both wedges), on the first chain's lockstep
// segments (both wedges), on the light-tracing shift's b -> c segment (both
// wedges); the squared-distance ratio dropped from the reconnection
// (Jacobian test, both wedges); sigma_s(y) / sigma_s(x) dropped (grid wedge);
// the offset's pdfRev at medium vertices left at the base's, and the phase
// densities left out of rho at a medium b (weight normalisation); an offset
// connection at the reconnection vertex taken as "known visible" (the base's
// edge: with media that drops its transmittance; smoke wedge, Z 4.9).
#include <gtest/gtest.h>

#include <cmath>

#include "gbdpt_test_util.h"
#include "gpt/gpt_media_check.h"
#include "gpt/gpt_media_util.h"
#include "integrators/gbdpt/gbdpt.h"
#include "integrators/gradient/medium_shift.h"

using namespace gradus;
using namespace gradus::gbdpttest;

namespace {

// A box of matte walls (open towards the camera) filled with fog, the camera
// in the fog too, an area light under the ceiling; smoke: a material-less
// sphere of denser smoke inside (a medium interface between two media).
std::string FogRoomText(const std::string &integratorLine, int w, int h, bool smoke) {
    std::string s = "LookAt 0 1 -3.4  0 0.9 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\n"
                    "Film \"image\" \"integer xresolution\" [" + std::to_string(w) + "] \"integer yresolution\" [" +
                    std::to_string(h) + "] \"string filename\" \"m.exr\"\n"
                    "Sampler \"sobol\" \"integer pixelsamples\" [16]\nPixelFilter \"box\"\n" + integratorLine + "\n"
                    "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] "
                    "\"rgb sigma_s\" [0.5 0.45 0.4] \"float g\" [0.3]\n"
                    "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.3 0.3 0.3] "
                    "\"rgb sigma_s\" [1.5 1.5 1.5] \"float g\" [-0.2]\n"
                    "MediumInterface \"\" \"fog\"\nWorldBegin\n"
                    "AttributeBegin\n  MediumInterface \"fog\" \"fog\"\n"
                    "  AreaLightSource \"diffuse\" \"rgb L\" [6 6 6]\n  Material \"matte\" \"rgb Kd\" [0 0 0]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[-0.4 1.95 -0.1  0.4 1.95 -0.1  0.4 1.95 0.6  -0.4 1.95 0.6]\nAttributeEnd\n"
                    "AttributeBegin\n  MediumInterface \"fog\" \"fog\"\n  Material \"matte\" \"rgb Kd\" [0.65 0.6 0.55]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[-1.2 0 -1.5  1.2 0 -1.5  1.2 0 1.2  -1.2 0 1.2]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[-1.2 2 -1.5  -1.2 2 1.2  1.2 2 1.2  1.2 2 -1.5]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[-1.2 0 1.2  1.2 0 1.2  1.2 2 1.2  -1.2 2 1.2]\n"
                    "  Material \"matte\" \"rgb Kd\" [0.6 0.2 0.15]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[-1.2 0 -1.5  -1.2 0 1.2  -1.2 2 1.2  -1.2 2 -1.5]\n"
                    "  Material \"matte\" \"rgb Kd\" [0.15 0.5 0.2]\n"
                    "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
                    "[1.2 0 -1.5  1.2 2 -1.5  1.2 2 1.2  1.2 0 1.2]\nAttributeEnd\n";
    if (smoke)
        s += "AttributeBegin\n  MediumInterface \"smoke\" \"fog\"\n  Material \"\"\n  Translate 0.3 0.6 0.1\n"
             "  Shape \"sphere\" \"float radius\" [0.45]\nAttributeEnd\n";
    return s + "WorldEnd\n";
}

struct MediaFixture {
    RenderJob job;
    GBDPTIntegrator *g = nullptr;
    MediaFixture(const std::string &text) : job(MakeJob(text, 1, 0)) {
        job.integrator->preprocess(*job.scene, *job.film);
        g = dynamic_cast<GBDPTIntegrator *>(job.integrator.get());
    }
};

// Camera subpath with media (the distance-sampling factors recorded).
ShiftSubpath MediaSubpath(const BidirContext &bc, const Ray &ray, Sampler &sampler, Arena &arena, int maxV, RNG &rng) {
    ShiftSubpath x = ArenaSubpath(arena, maxV + 1);
    x.segFactor = static_cast<Spectrum *>(arena.alloc(sizeof(Spectrum) * (maxV + 1), alignof(Spectrum)));
    for (int i = 0; i <= maxV; ++i) new (&x.segFactor[i]) Spectrum(1);
    x.n = GenerateCameraSubpath(bc, ray, sampler, arena, maxV, x.v, x.b, &rng, x.segFactor);
    return x;
}

// Gnomonic coordinates (a, b) of unit w around unit axis c (frame c1, c2): a
// chart whose element da db is the solid angle at w = c.
void Gnomonic(const Vec3 &w, const Vec3 &c, const Vec3 &c1, const Vec3 &c2, double *a, double *b) {
    const double d = Dot(w, c);
    *a = Dot(w, c1) / d;
    *b = Dot(w, c2) / d;
}

double Det3(const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

}  // namespace

// The base x = (lens, b, c, ...) with b a medium vertex and c the next vertex
// (the reconnection vertex r = 2). Variables of c in the base: the direction
// w sampled at b and, for a medium c, the distance t (volume element
// t^2 dw dt); for a surface c the direction alone. The offset keeps y_c = x_c
// and reaches it from its own b (the copied distance), so |T'| is the
// Jacobian of (w, t) -> (w_y, t_y) (or w -> w_y). It is read from the shift's
// throughput: y_c's over x_c's is (camera weights) T_y/T_x (segment b->c;
// the camera segments have equal lengths) phase_y/phase_x |T'|.
TEST(GBDPTMedia, MediumVertexJacobianMatchesFiniteDifferences) {
    MediaFixture f(FogRoomText("Integrator \"gbdpt\"", 24, 18, false));
    const SubpathShiftContext &sc = f.g->shiftContext();
    const BidirContext &bc = f.g->bidirContext();
    const Scene &scene = *bc.scene;
    ASSERT_TRUE(sc.media);
    const Medium *fog = scene.cameraMedium;
    ASSERT_TRUE(fog && fog->homogeneous());
    const Spectrum sigmaT = fog->sigmaTAt(Point3(0, 0, 0));
    std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
    Arena arena;
    int tested[2] = {0, 0};
    double maxTrDev = 0;  // the transmittance ratios tested differ from 1 by up to this
    for (int trial = 0; trial < 4000 && (tested[0] < 40 || tested[1] < 40); ++trial) {
        Ray ray;
        const CameraSample cs = TrialSample(*sampler, *bc.camera, trial, &ray);
        RNG rng(trial);
        ShiftSubpath x = MediaSubpath(bc, ray, *sampler, arena, 4, rng);
        if (x.n < 3 || x.v[1].type != VertexType::Medium) continue;
        const bool mediumC = x.v[2].type == VertexType::Medium;
        if (!mediumC && x.v[2].type != VertexType::Surface) continue;
        if (tested[mediumC] >= 40) continue;
        PrepareSubpath(sc, &x);
        auto shift = [&](CameraShift *sh) {
            SubpathShiftStats st;
            RNG r2(1);
            ShiftCameraSubpath(sc, x, cs, {1, 0}, arena, sh, &st, &r2);
            return sh->r == 2 && sh->validUpTo >= 2;
        };
        CameraShift sh;
        if (!shift(&sh)) continue;
        const Point3 X1 = x.v[1].p, X2 = x.v[2].p, Y1 = sh.y.v[1].p;
        // Independent factors: camera weights, phase functions, transmittance of b -> c.
        Ray ry;
        CameraSample c2 = cs;
        c2.pFilm.x += 1;
        const double wRatio = bc.camera->generateRay(c2, &ry) / bc.camera->generateRay(cs, &ray);
        const Vec3 wX = Normalize(X2 - X1), wY = Normalize(X2 - Y1);
        const double phX = fog->phase.p(Normalize(ray.o - X1), wX), phY = fog->phase.p(Normalize(ry.o - Y1), wY);
        const double Tr = std::exp(-sigmaT.r * (Distance(Y1, X2) - Distance(X1, X2)));
        const double ratio = sh.y.v[2].throughput().r / x.v[2].throughput().r;
        const double Jshift = ratio / (wRatio * phY / phX * Tr);
        maxTrDev = std::max(maxTrDev, std::abs(Tr - 1));
        // Finite differences: perturb the base's (w, t) at b, re-run the shift.
        Vec3 a1, a2, b1, b2;
        CoordinateSystem(wX, &a1, &a2);
        CoordinateSystem(wY, &b1, &b2);
        const double t0 = Distance(X1, X2), h = 1e-5;
        const PathVertex keep = x.v[2];
        const int dims = mediumC ? 3 : 2;
        double J[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 1}};
        bool ok = true;
        for (int k = 0; k < dims && ok; ++k) {
            double out[2][3];
            for (int s = 0; s < 2 && ok; ++s) {
                const double e = s == 0 ? h : -h;
                const Vec3 w = Normalize(wX + a1 * (k == 0 ? e : 0) + a2 * (k == 1 ? e : 0));
                Point3 P = X1 + w * (t0 + (k == 2 ? e : 0));
                if (!mediumC) {
                    SurfaceInteraction si;
                    ok = scene.intersect(Ray(X1, w), &si) && si.geomId == keep.geomId;
                    P = si.p;
                }
                x.v[2].p = P;
                x.v[2].wo = -w;
                CameraShift sp;
                ok = ok && shift(&sp);
                const Vec3 d = sp.y.v[2].p - sp.y.v[1].p;
                Gnomonic(Normalize(d), wY, b1, b2, &out[s][0], &out[s][1]);
                out[s][2] = d.length();
            }
            for (int r = 0; r < 3; ++r) J[r][k] = (out[0][r] - out[1][r]) / (2 * h);
        }
        x.v[2] = keep;
        if (!ok) continue;
        const double Jfd = std::abs(Det3(J));
        EXPECT_NEAR(Jshift / Jfd, 1.0, 2e-3) << (mediumC ? "medium" : "surface") << " c, trial " << trial;
        ++tested[mediumC];
    }
    std::printf("medium b -> medium c: %d paths, medium b -> surface c: %d paths; |T_y/T_x - 1| up to %.3f\n",
                tested[1], tested[0], maxTrDev);
    EXPECT_GT(maxTrDev, 0.02);
    EXPECT_GE(tested[1], 40);
    EXPECT_GE(tested[0], 40);
}

// Eq. 8 normalisation with medium vertices and a medium interface (the
// smoke sphere): paths ending on the area light, every strategy enumerated.
TEST(GBDPTMedia, CombinedWeightsSumToOneWithMediumVertices) {
    MediaFixture f(FogRoomText("Integrator \"gbdpt\"", 24, 18, true));
    const SubpathShiftContext &sc = f.g->shiftContext();
    const BidirContext &bc = f.g->bidirContext();
    std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
    Arena arena;
    int paths = 0, withMedium = 0, withLT = 0, oneSided = 0, mediumB = 0;
    for (int trial = 0; trial < 200000 && paths < 200; ++trial) {
        Ray ray;
        const CameraSample cs = TrialSample(*sampler, *bc.camera, trial, &ray);
        RNG rng(trial);
        ShiftSubpath x = MediaSubpath(bc, ray, *sampler, arena, 5, rng);
        const int n = x.n;
        if (n < 3 || x.v[n - 1].type != VertexType::Surface || !EmitterOf(bc, x.v[n - 1])) continue;
        if (EmittedRadiance(bc, x.v[n - 1], x.v[n - 2]).isBlack()) continue;
        bool corner = false, medium = false;
        for (int k = 1; k + 1 < n; ++k) corner |= Distance(x.v[k].p, x.v[k + 1].p) < 1e-2;
        for (int k = 1; k < n; ++k) medium |= x.v[k].type == VertexType::Medium;
        if (corner || (!medium && paths >= 2 * withMedium)) continue;  // at least two thirds through media
        PrepareSubpath(sc, &x);
        CameraShift sh;
        SubpathShiftStats st;
        RNG r2(trial + 1);
        ShiftCameraSubpath(sc, x, cs, {1, 0}, arena, &sh, &st, &r2);
        if (sh.validUpTo != n - 1) continue;
        bool grazing = false;
        for (int k = 1; k < n; ++k) grazing |= !(sh.rho[k] > 1e-6 && sh.rho[k] < 1e6);
        if (grazing) continue;
        double sum = 0, sumx = 0;
        if (!SumStrategyWeights(sc, bc, x, sh, cs, true, arena, &st, &sum, &sumx, &withLT, &r2)) {
            ++oneSided;
            continue;
        }
        EXPECT_NEAR(sumx, 1.0, 1e-4) << "BDPT weights of the enumerated strategies, trial " << trial;
        EXPECT_NEAR(sum, 1.0, 2e-3) << "path of " << n << " vertices, medium vertices " << medium << ", trial "
                                    << trial;
        withMedium += medium;
        mediumB += x.v[1].type == VertexType::Medium;
        ++paths;
    }
    std::printf("%d paths (%d through media, %d with a medium b; %d light-tracing strategies; %d with only the "
                "light-tracing shift failed)\n",
                paths, withMedium, mediumB, withLT, oneSided);
    EXPECT_GE(paths, 100);
    EXPECT_GE(withMedium, 60);
    EXPECT_LE(oneSided, paths / 50);
}

namespace {
std::string GridWedgeText(const std::string &integratorLine) {
    std::ostringstream g;
    // Identity: the grid's space is the world's (the CTM holds the LookAt here).
    g << "Identity\nMakeNamedMedium \"smoke\" \"string type\" \"heterogeneous\" \"rgb sigma_a\" [0.4 0.4 0.4] "
         "\"rgb sigma_s\" [1.6 1.6 1.6] \"float g\" [0.2]\n"
         "    \"point p0\" [-1.5 0 0] \"point p1\" [1.5 2 1.05] \"integer nx\" [4] \"integer ny\" [3] "
         "\"integer nz\" [3]\n    \"float density\" [";
    for (int z = 0; z < 3; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x) g << " " << 0.25 + double((5 * x + 3 * y + 7 * z) % 6) / 4;
    g << "]\n";
    return gptmedia::ReplaceOnce(gptmedia::WedgeText(integratorLine),
                                 "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.4 0.4 "
                                 "0.4] \"rgb sigma_s\" [1.6 1.6 1.6] \"float g\" [0.2]\n",
                                 g.str());
}
}  // namespace

TEST(GBDPTMedia, AgreesWithBDPTOnSmokeWedge) {
    gptmedia::CheckAgainstPath("gbdpt smoke-wedge", gptmedia::WedgeText("Integrator \"gbdpt\" \"integer maxdepth\" [4]"),
                               16, 128, 150, 0.02, "gbdpt", "bdpt", true);
}

TEST(GBDPTMedia, AgreesWithBDPTOnGridSmokeWedge) {
    gptmedia::CheckAgainstPath("gbdpt grid-smoke-wedge", GridWedgeText("Integrator \"gbdpt\" \"integer maxdepth\" [4]"),
                               16, 128, 150, 0.02, "gbdpt", "bdpt", true);
}

TEST(GBDPTMedia, AgreesWithBDPTOnSmokeWedgeWithSpecularSpheres) {
    gptmedia::CheckAgainstPath("gbdpt smoke-wedge-specular",
                               gptmedia::WedgeSpecularText("Integrator \"gbdpt\" \"integer maxdepth\" [4]"), 16, 128, 150,
                               0.02, "gbdpt", "bdpt", true);
}
