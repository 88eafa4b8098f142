// Shift mappings of src/integrators/gradient: Jacobians against finite
// differences of the shifts themselves, invertibility, gradient-MIS partition.
#include <gtest/gtest.h>

#include <random>

#include "integrators/gradient/shift.h"
#include "materials/bxdfs.h"
#include "materials/bxdf_util.h"

using namespace gradus;

namespace {

Vec3 RandomDir(std::mt19937_64 &rng) {
    std::normal_distribution<double> n;
    Vec3 v(n(rng), n(rng), n(rng));
    return Normalize(v);
}
Vec3 RandomUpper(std::mt19937_64 &rng, double minZ = 0.15) {
    for (;;) {
        Vec3 v = RandomDir(rng);
        if (std::abs(v.z) >= minZ) return v.z > 0 ? v : Vec3(v.x, v.y, -v.z);
    }
}
// Two unit tangents of the sphere at w.
void Tangents(const Vec3 &w, Vec3 *t1, Vec3 *t2) { CoordinateSystem(w, t1, t2); }

// Solid-angle Jacobian |d w'/d w| of a map of directions, by central differences
// in the tangent plane of w (the map gets w(a,b) = normalize(w + a t1 + b t2),
// whose solid-angle element at (0,0) is da db).
template <typename Map>
bool FiniteDifferenceJacobian(const Vec3 &w, Map map, double *J, double h = 1e-6) {
    Vec3 t1, t2;
    Tangents(w, &t1, &t2);
    Vec3 p[4];
    const double da[4] = {h, -h, 0, 0}, db[4] = {0, 0, h, -h};
    for (int i = 0; i < 4; ++i)
        if (!map(Normalize(w + t1 * da[i] + t2 * db[i]), &p[i])) return false;
    Vec3 du = (p[0] - p[1]) / (2 * h), dv = (p[2] - p[3]) / (2 * h);
    *J = Cross(du, dv).length();
    return true;
}

constexpr double kTol = 1e-4;

}  // namespace

TEST(GradientShift, ReconnectionJacobianMatchesFiniteDifferences) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(-1, 1);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        // Target on the plane through c with normal n; base and offset vertices in front of it.
        Point3 c(U(rng), U(rng), U(rng));
        Vec3 n = RandomDir(rng);
        Point3 xPrev = c + n * (1 + U(rng) * 0.5) + RandomDir(rng) * 0.7;
        Point3 yPrev = xPrev + RandomDir(rng) * 0.1;
        if (Dot(xPrev - c, n) < 0.2 || Dot(yPrev - c, n) < 0.2) continue;
        Point3 target = c + Normalize(Cross(n, RandomDir(rng))) * (0.5 * U(rng));
        ShiftVertex tv{target, n, nullptr, false};
        ReconnectionShift rc;
        ASSERT_TRUE(ShiftReconnect(xPrev, yPrev, tv, &rc));
        Vec3 w = Normalize(target - xPrev);
        auto map = [&](const Vec3 &wx, Vec3 *wy) {
            double t = Dot(c - xPrev, n) / Dot(wx, n);  // base ray hits the plane
            ShiftVertex tt{xPrev + wx * t, n, nullptr, false};
            ReconnectionShift r;
            if (!ShiftReconnect(xPrev, yPrev, tt, &r)) return false;
            *wy = r.wi;
            return true;
        };
        double J;
        ASSERT_TRUE(FiniteDifferenceJacobian(w, map, &J));
        EXPECT_NEAR(rc.jacobian / J, 1, kTol) << "trial " << trial;
        ++checked;
    }
    EXPECT_GT(checked, 100);
}

TEST(GradientShift, EnvironmentShiftKeepsDirection) {
    ShiftVertex inf{Normalize(Vec3(0.3, -0.2, 1)), Normal3(0, 0, 0), nullptr, true};
    ReconnectionShift rc;
    ASSERT_TRUE(ShiftReconnect(Point3(0, 0, 0), Point3(1, 2, 3), inf, &rc));
    EXPECT_DOUBLE_EQ(rc.jacobian, 1);
    EXPECT_NEAR((rc.wi - inf.p).length(), 0, 1e-15);
}

TEST(GradientShift, HalfVectorReflectionJacobianMatchesFiniteDifferences) {
    std::mt19937_64 rng(2);
    int checked = 0;
    for (int trial = 0; trial < 300; ++trial) {
        Vec3 woX = RandomUpper(rng), wiX = RandomUpper(rng);
        Vec3 woY = Normalize(woX + RandomDir(rng) * 0.2);
        if (woY.z < 0.15) continue;
        HalfVectorShift hv;
        if (!ShiftHalfVector(woX, wiX, woY, 1, &hv)) continue;
        auto map = [&](const Vec3 &wx, Vec3 *wy) {
            HalfVectorShift s;
            if (!ShiftHalfVector(woX, wx, woY, 1, &s)) return false;
            *wy = s.wi;
            return true;
        };
        double J;
        if (!FiniteDifferenceJacobian(wiX, map, &J)) continue;
        EXPECT_FALSE(hv.refraction);
        EXPECT_NEAR(hv.jacobian / J, 1, kTol) << "trial " << trial;
        ++checked;
    }
    EXPECT_GT(checked, 200);
}

TEST(GradientShift, HalfVectorRefractionJacobianMatchesFiniteDifferences) {
    std::mt19937_64 rng(3);
    int checked = 0;
    for (int trial = 0; trial < 400; ++trial) {
        double eta = trial % 2 ? 1.5 : 1 / 1.33;  // from outside into glass, or out of water
        Vec3 woX = RandomUpper(rng, 0.3);
        Vec3 h = RandomUpper(rng, 0.7);
        if (Dot(woX, h) <= 0) continue;
        Vec3 wiX;
        if (!bxdfutil::Refract(woX, h, eta, &wiX) || wiX.z >= 0) continue;
        wiX = Normalize(wiX);
        Vec3 woY = Normalize(woX + RandomDir(rng) * 0.1);
        if (woY.z < 0.2) continue;
        HalfVectorShift hv;
        if (!ShiftHalfVector(woX, wiX, woY, eta, &hv)) continue;
        auto map = [&](const Vec3 &wx, Vec3 *wy) {
            HalfVectorShift s;
            if (!ShiftHalfVector(woX, wx, woY, eta, &s)) return false;
            *wy = s.wi;
            return true;
        };
        double J;
        if (!FiniteDifferenceJacobian(wiX, map, &J)) continue;
        EXPECT_TRUE(hv.refraction);
        EXPECT_NEAR(hv.jacobian / J, 1, kTol) << "trial " << trial << " eta " << eta;
        ++checked;
    }
    EXPECT_GT(checked, 100);
}

TEST(GradientShift, HalfVectorRefusesIndexRatioOne) {
    HalfVectorShift hv;
    EXPECT_FALSE(ShiftHalfVector(Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(0.1, 0, 0.995), 1, &hv));
}

namespace {
// BSDF on a flat surface with the local frame = world frame.
BSDF FlatBSDF(const BxDF *bxdf) {
    SurfaceInteraction si;
    si.p = Point3(0, 0, 0);
    si.n = Normal3(0, 0, 1);
    si.shading.n = si.n;
    si.shading.dpdu = Vec3(1, 0, 0);
    return BSDF(si, bxdf);
}
}  // namespace

TEST(GradientShift, ReplayJacobianMatchesFiniteDifferences) {
    // The replay map w_x(u) -> w_y(u): |dw_y/dw_x| = |dw_y/du| / |dw_x/du|.
    LambertianReflection lambert(Spectrum(0.5));
    MicrofacetDistribution ggx(MicrofacetDistribution::TrowbridgeReitz, 0.3, 0.3);
    MicrofacetReflection glossy(Spectrum(1), ggx, Fresnel::One());
    const BxDF *bxdfs[2] = {&lambert, &glossy};
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> U(0.05, 0.95);
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        BSDF bsdf = FlatBSDF(bxdfs[trial % 2]);
        Vec3 woX = RandomUpper(rng, 0.3), woY = Normalize(woX + RandomDir(rng) * 0.2);
        if (woY.z < 0.3) continue;
        Point2 u(U(rng), U(rng));
        BSDFSample sx;
        if (!bsdf.sample(woX, 0.5, u, TransportMode::Radiance, &sx)) continue;
        ReplayShift rp;
        if (!ShiftReplay(bsdf, woY, 0.5, u, sx.pdf, TransportMode::Radiance, &rp)) continue;
        const double h = 1e-6;
        auto area = [&](const Vec3 &wo, double *a) {
            BSDFSample s[4];
            Point2 us[4] = {{u.x + h, u.y}, {u.x - h, u.y}, {u.x, u.y + h}, {u.x, u.y - h}};
            for (int i = 0; i < 4; ++i)
                if (!bsdf.sample(wo, 0.5, us[i], TransportMode::Radiance, &s[i])) return false;
            *a = Cross((s[0].wi - s[1].wi) / (2 * h), (s[2].wi - s[3].wi) / (2 * h)).length();
            return true;
        };
        double ax, ay;
        if (!area(woX, &ax) || !area(woY, &ay)) continue;
        EXPECT_NEAR(rp.jacobian / (ay / ax), 1, kTol) << "trial " << trial;
        ++checked;
    }
    EXPECT_GT(checked, 150);
}

TEST(GradientShift, ShiftsAreInvertible) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> U(-1, 1);
    // Reconnection: the inverse reconnects back to the same vertex; Jacobians multiply to 1.
    for (int trial = 0; trial < 100; ++trial) {
        Point3 xPrev(U(rng), U(rng), 1 + U(rng) * 0.2), yPrev = xPrev + RandomDir(rng) * 0.1;
        ShiftVertex t{Point3(U(rng), U(rng), 0), Normal3(0, 0, 1), nullptr, false};
        ReconnectionShift f, b;
        ASSERT_TRUE(ShiftReconnect(xPrev, yPrev, t, &f));
        ASSERT_TRUE(ShiftReconnect(yPrev, xPrev, t, &b));
        EXPECT_NEAR((b.wi - Normalize(t.p - xPrev)).length(), 0, 1e-12);
        EXPECT_NEAR(f.jacobian * b.jacobian, 1, 1e-12);
    }
    // Half-vector copy (reflection and refraction): T_ji(T_ij(x)) = x.
    int refl = 0, refr = 0;
    for (int trial = 0; trial < 400; ++trial) {
        Vec3 woX = RandomUpper(rng, 0.3), wiX;
        double eta = 1;
        if (trial % 2) {
            eta = 1.5;
            Vec3 h = RandomUpper(rng, 0.7);
            if (Dot(woX, h) <= 0 || !bxdfutil::Refract(woX, h, eta, &wiX) || wiX.z >= 0) continue;
            wiX = Normalize(wiX);
        } else {
            wiX = RandomUpper(rng);
        }
        Vec3 woY = Normalize(woX + RandomDir(rng) * 0.1);
        if (woY.z < 0.2) continue;
        HalfVectorShift f, b;
        if (!ShiftHalfVector(woX, wiX, woY, eta, &f)) continue;
        ASSERT_TRUE(ShiftHalfVector(woY, f.wi, woX, eta, &b)) << "trial " << trial << " eta " << eta;
        EXPECT_NEAR((b.wi - wiX).length(), 0, 1e-10);
        EXPECT_NEAR(f.jacobian * b.jacobian, 1, 1e-10);
        (trial % 2 ? refr : refl)++;
    }
    EXPECT_GT(refl, 100);
    EXPECT_GT(refr, 50);
    // Replay: the same random numbers give back the base sample.
    LambertianReflection lambert(Spectrum(0.5));
    BSDF bsdf = FlatBSDF(&lambert);
    Vec3 woX = Normalize(Vec3(0.2, 0.1, 1)), woY = Normalize(Vec3(-0.3, 0.1, 1));
    Point2 u(0.3, 0.7);
    BSDFSample sx;
    ASSERT_TRUE(bsdf.sample(woX, 0.5, u, TransportMode::Radiance, &sx));
    ReplayShift f, b;
    ASSERT_TRUE(ShiftReplay(bsdf, woY, 0.5, u, sx.pdf, TransportMode::Radiance, &f));
    ASSERT_TRUE(ShiftReplay(bsdf, woX, 0.5, u, f.sample.pdf, TransportMode::Radiance, &b));
    EXPECT_NEAR((b.sample.wi - sx.wi).length(), 0, 1e-12);
    EXPECT_NEAR(f.jacobian * b.jacobian, 1, 1e-12);
}

TEST(GradientShift, GradientMISWeightsPartitionUnity) {
    // w_ij(x) + w_ji(T_ij x) = 1 summed over the techniques (G-BDPT Eq. 8):
    // from y's side the pdfs swap roles and the ratio inverts.
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> U(0.01, 3);
    for (int i = 0; i < 1000; ++i) {
        double bx = U(rng), nx = U(rng), by = U(rng), ny = U(rng), prefixX = U(rng), prefixY = U(rng), J = U(rng);
        // Full path pdfs: p_t(x) = prefixX * t_x, p_t(y)|T'| = prefixY * J * t_y.
        double ratio = prefixY * J / prefixX;
        double wx = GradientMISWeight(bx, nx, by, ny, ratio) + GradientMISWeight(nx, bx, ny, by, ratio);
        double wy = GradientMISWeight(by, ny, bx, nx, 1 / ratio) + GradientMISWeight(ny, by, nx, bx, 1 / ratio);
        EXPECT_NEAR(wx + wy, 1, 1e-12);
    }
    // A failed shift (ratio 0) gives the base's own power-heuristic weight.
    EXPECT_NEAR(GradientMISWeight(2, 1, 5, 5, 0), 4.0 / 5.0, 1e-15);
}
