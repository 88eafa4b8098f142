// G-MLT's shift with near-specular glossy vertices treated as specular
// (gradient-domain-mlt.md Sec. 5, Fig. 5a). Tests 1 and 2 on the glossy box
// of gmlt_test_util.h (specular box with both spheres microfacet alpha 0.05,
// shiftthreshold 0.1), test 3 on the shipped scenes/glossy-box.pbrt.
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
// 3. The chain keeps its target f (Eq. 11) where near-specular second chains
//    are walked (below).
#include <algorithm>
#include <array>
#include <cmath>

#include "conformance/conformance_util.h"
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

// One step of gmlt's chain from its target: states z = (x, d) are drawn with
// weights proportional to f(z) (every bdpt strategy path x of independent
// samples weighted by its MIS-weighted contribution C / I(x) times f(x, d), all
// four d), and from each a proposal of the bidirectional mutation and of the
// lens perturbation with a uniform new direction, accepted with gmlt's
// probability min(1, pmlt's ratio I(x) / I(y) f(y) / f(x) times the selection
// ratio). A kernel that keeps f gives every statistic g the same mean before
// and after the step: per sample k, D_k = sum w a (g(y) - g(x)) has mean 0.
// Statistics: g = [the shift of z walks a second chain with a near-specular
// vertex] and g = I / f (the coarse primal per state). Scene: the shipped
// glossy box (spheres of roughness 0.0005, near-specular at the default
// threshold) at maxdepth 2. Student's t, two-sided, alpha 1e-3 over the four
// tests (Bonferroni). Power: the same proposals accepted for pmlt's target I
// (min(1, ratio times the selection ratio)), a kernel that keeps I and not f,
// must be rejected on the first statistic. Measured before the light vertices
// of bidirectional samples were put on the emitter's surface (the walks of
// such second chains failed where the same paths hit from the camera walked):
// t = 13.9 for the bidirectional mutation on the first statistic (the test
// fails), a chain that drifted into those states and a coarse primal 3.7% too
// bright on the full scene.
TEST(GMLTNearSpecular, ChainKeepsItsTargetOnSecondChains) {
    GMLTSetup g(ReadFile(std::string(GRADUS_SOURCE_DIR) + "/scenes/glossy-box.pbrt"), -1, 2);
    const pmlt::Mutator &mut = g.gm->mutator();
    const Float thr = g.gm->gsettings().shiftThreshold;
    const std::array<Float, pmlt::kMutationTypes> weights = {1, 1, 1, 1, 1};
    Arena arena, scratch;
    RNG rng(11);
    const int N = 40000;
    // [mutation][statistic][kernel: gmlt, pmlt's]: sums over samples of D_k and D_k^2.
    double s1[2][2][2] = {}, s2[2][2][2] = {}, cur[2][2][2] = {};
    double mass = 0;
    auto secondChain = [&](const pmlt::State &x, const GMLTIntegrator::Target &t) {
        if (t.status != ShiftStatus::Shifted) return 0.0;
        int b = 1;
        while (b < x.x.size() - 1 && pmlt::ShiftClassOf(x.x.v[size_t(b)], x.bsdf[size_t(b)], thr) != pmlt::ShiftClass::Rough)
            ++b;
        for (int j = b + 1; j < x.x.size() - 1; ++j) {
            const pmlt::ShiftClass c = pmlt::ShiftClassOf(x.x.v[size_t(j)], x.bsdf[size_t(j)], thr);
            if (c == pmlt::ShiftClass::Rough) break;
            if (c == pmlt::ShiftClass::NearSpecular) return 1.0;
        }
        return 0.0;
    };
    ForEachStrategyPath(
        g, N, 0x57a, arena,
        [&](const pmlt::State &x, const Spectrum &C) {
            for (int d = 0; d < kNumNeighbours; ++d) {
                const GMLTIntegrator::Target tx = g.gm->evaluate(x, d, scratch);
                const double w = C.y() / x.e.I * tx.f;
                const double gx[2] = {secondChain(x, tx), x.e.I / tx.f};
                mass += w * gx[0];
                for (int type = 0; type < 2; ++type) {
                    RNGSampler u(rng);
                    pmlt::State y;
                    double ratio = 0;
                    const pmlt::MutationType mt = pmlt::MutationType(type);
                    if (mut.propose(mt, x, u, scratch, &y, &ratio) != pmlt::ProposalResult::Proposed) continue;
                    const int dy = std::min(int(rng.uniform() * 4), 3);
                    const GMLTIntegrator::Target ty = g.gm->evaluate(y, dy, scratch);
                    const double sel =
                        mut.selectionProbability(mt, y.x, weights.data()) / mut.selectionProbability(mt, x.x, weights.data());
                    const double r[2] = {ratio * (double(x.e.I) / double(y.e.I)) * (ty.f / tx.f) * sel, ratio * sel};
                    const double gy[2] = {secondChain(y, ty), y.e.I / ty.f};
                    for (int k = 0; k < 2; ++k) {
                        const double a = std::isfinite(r[k]) ? std::min(1.0, r[k]) : 0;
                        for (int st = 0; st < 2; ++st) cur[type][st][k] += w * a * (gy[st] - gx[st]);
                    }
                }
            }
            scratch.reset();
        },
        [&](int) {
            for (int t = 0; t < 2; ++t)
                for (int st = 0; st < 2; ++st)
                    for (int k = 0; k < 2; ++k) {
                        s1[t][st][k] += cur[t][st][k];
                        s2[t][st][k] += cur[t][st][k] * cur[t][st][k];
                        cur[t][st][k] = 0;
                    }
        });
    EXPECT_GT(mass / N, 1e-5) << "too few states walk near-specular second chains";
    const double crit = conformance::StudentCritical(1e-3 / 4, N - 1);
    double power = 0;
    for (int t = 0; t < 2; ++t)
        for (int st = 0; st < 2; ++st)
            for (int k = 0; k < 2; ++k) {
                const double m = s1[t][st][k] / N, se = std::sqrt((s2[t][st][k] / N - m * m) / (N - 1));
                const double tv = se > 0 ? m / se : 0;
                std::cout << "[ stationarity ] " << (t == 0 ? "bidirectional" : "lens") << ", "
                          << (st == 0 ? "near-specular second chains" : "coarse primal") << ", "
                          << (k == 0 ? "gmlt's kernel" : "pmlt's kernel (power)") << ": drift " << m << " +- " << se
                          << " (t " << tv << ", critical " << crit << ")\n";
                if (k == 0) {
                    EXPECT_LT(std::abs(tv), crit);
                } else if (st == 0) {
                    power = std::max(power, std::abs(tv));
                }
            }
    std::cout << "[ stationarity ] f-mass of near-specular second-chain states per sample: " << mass / N << "\n";
    EXPECT_GT(power, crit) << "a kernel that keeps I instead of f is not detected";
}

}  // namespace
}  // namespace gradus::pmlt_test
