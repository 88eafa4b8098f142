// G-MLT's shift with near-specular glossy vertices treated as specular
// (gradient-domain-mlt.md Sec. 5, Fig. 5a), on the glossy box (specular box
// with both spheres microfacet alpha 0.05, shiftthreshold 0.1).
// 1. Classes: the spheres' vertices are NearSpecular, the mirror's Dirac, the
//    walls' Rough; with the default threshold the spheres are Rough.
// 2. Jacobian against finite differences, in the measure the shift's
//    |d mu(y) / d mu(x)| is defined in: for paths whose moved vertices
//    x_1 .. x_last (the eye chain and the second chain) are all non-Dirac,
//    the determinant of d(y_1 .. y_last) / d(x_1 .. x_last) in tangent-plane
//    coordinates. Each x_j is moved by +-eps along its tangents (a ray along
//    the normal, so the move is exact in tangent coordinates), the moved path
//    shifted, the offsets' vertices projected on their tangent planes (central
//    differences, eps = 1e-4; a path counts when eps = 2e-4 agrees to 1e-4,
//    which drops differences straddling an edge of a facet or an occluder).
//    Cases: near-specular vertices in the eye chain (copied half vectors) and
//    in second chains (the walk keeps them), reflection and refraction.
#include <algorithm>
#include <cmath>

#include "gmlt/gmlt_test_util.h"

namespace gradus::pmlt_test {
namespace {

using pmlt::ShiftClass;

// Moves vertex j of x by e in its tangent plane (a ray along the normal from
// x_{j-1}'s side) and re-evaluates the path.
bool MoveVertex(const GMLTSetup &g, const pmlt::State &x, int j, const Vec3 &e, Arena &arena, pmlt::State *out) {
    *out = x;
    const PathVertex &v = x.x.v[size_t(j)];
    Vec3 n = Normalize(Vec3(v.ng));
    if (Dot(n, x.x.v[size_t(j - 1)].p - v.p) < 0) n = -n;
    Ray ray(v.p + e + n * Float(1e-2), -n, Float(2e-2));
    SurfaceInteraction si;
    if (g.ctx().scene->intersectSurface(&ray, &si) != Scene::SurfaceHit::Hit || si.geomId != v.geomId) return false;
    const BSDF b = si.material->getBSDF(si, arena, TransportMode::Radiance);
    if (!b) return false;
    PathVertex nv;
    MakeSurfaceVertex(g.ctx(), si, b, &nv);
    nv.flags = v.flags;
    out->x.v[size_t(j)] = nv;
    out->bsdf[size_t(j)] = b;
    for (int i = 1; i < out->x.size(); ++i)
        out->x.v[size_t(i)].wo = PackedVec3(pmlt::Dir(out->x.v[size_t(i)], out->x.v[size_t(i - 1)]));
    return pmlt::Evaluate(g.ctx(), g.film(), out->x, out->bsdf.data(), &out->e);
}

// Determinant by Gaussian elimination with partial pivoting (m <= 16).
double Determinant(std::vector<double> a, int m) {
    double det = 1;
    for (int c = 0; c < m; ++c) {
        int p = c;
        for (int r = c + 1; r < m; ++r)
            if (std::abs(a[size_t(r * m + c)]) > std::abs(a[size_t(p * m + c)])) p = r;
        if (a[size_t(p * m + c)] == 0) return 0;
        if (p != c) {
            for (int k = 0; k < m; ++k) std::swap(a[size_t(p * m + k)], a[size_t(c * m + k)]);
            det = -det;
        }
        det *= a[size_t(c * m + c)];
        for (int r = c + 1; r < m; ++r) {
            const double f = a[size_t(r * m + c)] / a[size_t(c * m + c)];
            for (int k = c; k < m; ++k) a[size_t(r * m + k)] -= f * a[size_t(c * m + k)];
        }
    }
    return det;
}

// |det d(y_1 .. y_last) / d(x_1 .. x_last)| by central differences of step eps
// (-1 when a moved path or its shift fails).
double FiniteDifferenceJacobian(const GMLTSetup &g, const pmlt::State &x, const pmlt::State &y, int dir, int last,
                                double eps, Arena &arena) {
    const pmlt::Mutator &mut = g.gm->mutator();
    const int m = 2 * last;
    std::vector<double> M(size_t(m * m));
    std::vector<Vec3> ty(static_cast<size_t>(m));
    for (int i = 1; i <= last; ++i) CoordinateSystem(Normalize(Vec3(y.x.v[size_t(i)].ng)), &ty[size_t(2 * i - 2)],
                                                     &ty[size_t(2 * i - 1)]);
    for (int j = 1; j <= last; ++j) {
        Vec3 t[2];
        CoordinateSystem(Normalize(Vec3(x.x.v[size_t(j)].ng)), &t[0], &t[1]);
        for (int a = 0; a < 2; ++a) {
            pmlt::State xp, xm, yp, ym;
            double Jp, Jm;
            if (!MoveVertex(g, x, j, t[a] * Float(eps), arena, &xp) ||
                !MoveVertex(g, x, j, t[a] * Float(-eps), arena, &xm) ||
                mut.shift(xp, Shifted(xp, dir), arena, &yp, &Jp) != ShiftStatus::Shifted ||
                mut.shift(xm, Shifted(xm, dir), arena, &ym, &Jm) != ShiftStatus::Shifted)
                return -1;
            const int col = 2 * (j - 1) + a;
            for (int i = 1; i <= last; ++i) {
                const Vec3 d = (yp.x.v[size_t(i)].p - ym.x.v[size_t(i)].p) / Float(2 * eps);
                for (int b = 0; b < 2; ++b) M[size_t((2 * i - 2 + b) * m + col)] = Dot(d, ty[size_t(2 * i - 2 + b)]);
            }
        }
    }
    return std::abs(Determinant(M, m));
}

// The shift's moved vertices: the eye chain and the second chain (x_1 .. x_last).
int LastMoved(const pmlt::State &x, const std::vector<ShiftClass> &cls) {
    const int n = x.x.size();
    int b = 1;
    while (b < n - 1 && cls[size_t(b)] != ShiftClass::Rough) ++b;
    int c = b + 1;
    while (c < n - 1 && cls[size_t(c)] != ShiftClass::Rough) ++c;
    return c == b + 1 ? b : c - 1;
}

TEST(GMLTNearSpecular, Classes) {
    GMLTSetup g(GlossyBox(), kGlossyBoxThreshold), d(GlossyBox());
    Arena arena;
    int counts[2][3] = {};
    ForEachStrategyPath(
        g, 400, 0xc1a55, arena,
        [&](const pmlt::State &x, const Spectrum &) {
            for (int j = 1; j + 1 < x.x.size(); ++j) {
                const PathVertex &v = x.x.v[size_t(j)];
                const Float r = x.bsdf[size_t(j)].roughness();
                const ShiftClass c = pmlt::ShiftClassOf(v, x.bsdf[size_t(j)], Float(kGlossyBoxThreshold));
                const ShiftClass c0 = pmlt::ShiftClassOf(v, x.bsdf[size_t(j)], Float(0.001));
                const ShiftClass want = v.delta() ? ShiftClass::Dirac
                                        : r == Float(0.05) ? ShiftClass::NearSpecular
                                                           : ShiftClass::Rough;
                EXPECT_EQ(int(c), int(want)) << "roughness " << r;
                EXPECT_EQ(int(c0), int(v.delta() ? ShiftClass::Dirac : ShiftClass::Rough)) << "roughness " << r;
                ++counts[0][int(c)];
                ++counts[1][int(c0)];
            }
        },
        [](int) {});
    EXPECT_GT(counts[0][int(ShiftClass::NearSpecular)], 100);
    EXPECT_GT(counts[0][int(ShiftClass::Dirac)], 10);
    EXPECT_EQ(counts[1][int(ShiftClass::NearSpecular)], 0);
    EXPECT_EQ(d.gm->gsettings().shiftThreshold, Float(0.001));
}

TEST(GMLTNearSpecular, JacobianMatchesFiniteDifferences) {
    GMLTSetup g(GlossyBox(), kGlossyBoxThreshold);
    const pmlt::Mutator &mut = g.gm->mutator();
    Arena arena, scratch;
    // [eye chain / second chain]: paths checked, largest |J / J_fd - 1|, largest |log J|.
    int checked[2] = {};
    double worst[2] = {}, spread[2] = {};
    int refractions = 0;
    std::vector<ShiftClass> cls;
    ForEachStrategyPath(
        g, 6000, 0xfd5, arena,
        [&](const pmlt::State &x, const Spectrum &) {
            const int n = x.x.size();
            cls.resize(size_t(n));
            for (int j = 0; j < n; ++j)
                cls[size_t(j)] = pmlt::ShiftClassOf(x.x.v[size_t(j)], x.bsdf[size_t(j)], Float(kGlossyBoxThreshold));
            const int last = LastMoved(x, cls);
            bool dirac = false, eyeGlossy = false, secondGlossy = false, refracts = false;
            int b = 1;
            while (b < n - 1 && cls[size_t(b)] != ShiftClass::Rough) ++b;
            for (int j = 1; j <= last; ++j) {
                dirac |= cls[size_t(j)] == ShiftClass::Dirac;
                (j < b ? eyeGlossy : secondGlossy) |= cls[size_t(j)] == ShiftClass::NearSpecular;
                refracts |= cls[size_t(j)] == ShiftClass::NearSpecular &&
                            Dot(Vec3(x.x.v[size_t(j)].ng), x.x.v[size_t(j - 1)].p - x.x.v[size_t(j)].p) *
                                    Dot(Vec3(x.x.v[size_t(j)].ng), x.x.v[size_t(j + 1)].p - x.x.v[size_t(j)].p) <
                                0;
            }
            const int kind = secondGlossy ? 1 : 0;
            if (dirac || !(eyeGlossy || secondGlossy) || last >= n - 1 || checked[kind] >= 150) return;
            for (int d = 0; d < kNumNeighbours; ++d) {
                pmlt::State y;
                double J = 0;
                if (mut.shift(x, Shifted(x, d), scratch, &y, &J) != ShiftStatus::Shifted) continue;
                const double fd = FiniteDifferenceJacobian(g, x, y, d, last, 1e-4, scratch);
                const double fd2 = FiniteDifferenceJacobian(g, x, y, d, last, 2e-4, scratch);
                if (!(fd > 0 && fd2 > 0) || std::abs(fd2 / fd - 1) > 1e-4) continue;
                ++checked[kind];
                refractions += refracts;
                worst[kind] = std::max(worst[kind], std::abs(J / fd - 1));
                spread[kind] = std::max(spread[kind], std::abs(std::log(J)));
                break;
            }
            scratch.reset();
        },
        [](int) {});
    for (int k = 0; k < 2; ++k)
        std::cout << "[ jacobian ] near-specular " << (k == 0 ? "eye chains" : "second chains") << ": " << checked[k]
                  << " shifts, largest |J / J_fd - 1| " << worst[k] << " (largest |log J| " << spread[k] << ")\n";
    std::cout << "[ jacobian ] " << refractions << " of them through a near-specular refraction\n";
    for (int k = 0; k < 2; ++k) {
        EXPECT_GE(checked[k], 50) << (k == 0 ? "eye chains" : "second chains");
        EXPECT_LT(worst[k], 1e-3) << (k == 0 ? "eye chains" : "second chains");
        // The Jacobians must differ from 1 by far more than the tolerance.
        EXPECT_GT(spread[k], 0.05) << (k == 0 ? "eye chains" : "second chains");
    }
    EXPECT_GT(refractions, 10);
}

}  // namespace
}  // namespace gradus::pmlt_test
