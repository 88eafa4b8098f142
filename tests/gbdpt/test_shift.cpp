// Tests of the subpath shifts (gradient/camera_shift.h, lighttracing_shift.h)
// as G-BDPT sets them up: Jacobians against finite differences, invertibility of
// the camera-subpath shift and the Eq. 8 weight identity on random paths.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "gbdpt_test_util.h"
#include "integrators/gbdpt/gbdpt.h"
#include "integrators/gradient/camera_shift.h"
#include "integrators/gradient/lighttracing_shift.h"
#include "integrators/manifold/manifold.h"
#include "integrators/manifold/manifold_scene.h"
#include "lights/light.h"

using namespace gradus;
using namespace gradus::gbdpttest;

namespace {

struct Fixture {
    RenderJob job;
    GBDPTIntegrator *g = nullptr;
    explicit Fixture(const std::string &line = "Integrator \"gbdpt\"", int w = 24, int h = 18, bool env = false,
                     bool roughGlass = false, bool glossyMirror = false)
        : job(MakeJob(env ? EnvScene(line, w, h) : BoxScene(line, w, h, glossyMirror, roughGlass), 1, 0)) {
        job.integrator->preprocess(*job.scene, *job.film);
        g = dynamic_cast<GBDPTIntegrator *>(job.integrator.get());
    }
};

Vec3 Perturb(const Vec3 &w, const Vec3 &t, Float eps) { return Normalize(w + t * eps); }

// Traces from `p` along `d` through ideal specular glass (refraction) until a
// non-specular surface; returns the chain points (start, interior..., end).
bool TraceGlassChain(const Scene &scene, const EmbreeManifoldScene &ms, const Point3 &p, const Vec3 &n, Vec3 d,
                     Arena &arena, std::vector<ManifoldSurfacePoint> *pts, std::vector<bool> *reflect) {
    ManifoldSurfacePoint s0;
    s0.p = p;
    s0.n = n;
    CoordinateSystem(n, &s0.dpdu, &s0.dpdv);
    pts->push_back(s0);
    Point3 o = p;
    for (int k = 0; k < 6; ++k) {
        SurfaceInteraction si;
        if (!scene.intersect(Ray(o + d * 1e-5, d), &si) || !si.material) return false;
        BSDF b = si.material->getBSDF(si, arena, TransportMode::Radiance);
        ManifoldSurfacePoint sp = ms.fromInteraction(si);
        if (!b.isSpecular()) {
            sp.n = si.n;
            sp.dndu = sp.dndv = Vec3(0, 0, 0);
            pts->push_back(sp);
            return pts->size() >= 3;
        }
        BSDFSample bs;
        if (!b.sample(si.wo, 1 - 1e-9, Point2(0.5, 0.5), TransportMode::Radiance, &bs) || !bs.isTransmission())
            return false;
        ms.recordEta(si.geomId, 1.5);  // the walk's re-traced hits look the index up
        sp.etaInterior = 1.5;
        sp.etaExterior = 1;
        pts->push_back(sp);
        reflect->push_back(false);
        o = si.p;
        d = bs.wi;
    }
    return false;
}

}  // namespace

// J_b of the second chain (G-BDPT Eq. 5 via LKL13): the solid angle per area
// through a specular chain, d omega_0 / dA_end, against central differences of
// the re-traced chain's end point.
TEST(GBDPTShift, ChainSolidAngleMatchesFiniteDifferences) {
    Fixture f;
    const Scene &scene = *f.job.scene;
    EmbreeManifoldScene ms(scene);
    Arena arena;
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> U(-1, 1);
    int tested = 0;
    for (int trial = 0; trial < 200 && tested < 20; ++trial) {
        // Floor point near the glass sphere (centre (0.35, 0.4, 0.1), r 0.4), aiming through it.
        Point3 p(0.35 + 0.6 * U(rng), 0, 0.1 + 0.6 * U(rng) - 0.7);
        Point3 aim(0.35 + 0.3 * U(rng), 0.4 + 0.3 * U(rng), 0.1 + 0.3 * U(rng));
        Vec3 d = Normalize(aim - p);
        std::vector<ManifoldSurfacePoint> pts;
        std::vector<bool> refl;
        if (!TraceGlassChain(scene, ms, p, Vec3(0, 1, 0), d, arena, &pts, &refl)) continue;
        ManifoldChain chain;
        bool rf[kMaxManifoldVertices], sp[kMaxManifoldVertices];
        for (size_t i = 0; i < refl.size(); ++i) {
            rf[i] = refl[i];
            sp[i] = true;
        }
        if (!MakeChain(pts.data(), int(pts.size()), rf, sp, &chain)) continue;
        Float analytic = ChainSolidAnglePerArea(chain);
        if (!(analytic > 0)) continue;
        Vec3 t1, t2;
        CoordinateSystem(d, &t1, &t2);
        const Float eps = 1e-3;  // Embree hits are single precision: smaller steps measure their noise
        Point3 e[2];
        bool ok = true;
        for (int a = 0; a < 2 && ok; ++a) {
            Vec3 t = a == 0 ? t1 : t2;
            ManifoldChain cp, cm;
            ok = TraceChain(ms, chain.front().sp, Perturb(d, t, eps), chain, &cp) == ManifoldStatus::Success &&
                 TraceChain(ms, chain.front().sp, Perturb(d, t, -eps), chain, &cm) == ManifoldStatus::Success;
            if (ok) e[a] = (cp.back().sp.p - cm.back().sp.p) / (2 * eps);
        }
        if (!ok) continue;
        Float dAdw = AbsDot(Cross(e[0], e[1]), Vec3(chain.back().sp.n));
        EXPECT_NEAR(analytic * dAdw, 1.0, 2e-3) << "chain of " << pts.size() << " vertices";
        ++tested;
    }
    EXPECT_GE(tested, 10);
}

// Phi of a second chain with near-specular glossy vertices (ChainDirectionsPerArea:
// the sampled directions at b and at every glossy vertex per unit area at c and
// per unit of the glossy half-vectors) against finite differences of the inverse
// map: perturb the directions, trace, and measure c's tangent coordinates and
// the projected half-vectors in the base's frames. Chains b -> glossy metal
// sphere -> c and b -> rough glass -> rough glass -> c of the glossy box's
// camera subpaths; det(d(A_c, O_g)/d(omega_b, omega_g)) * Phi = 1.
TEST(GBDPTShift, GlossyChainDirectionsPerAreaMatchFiniteDifferences) {
    Fixture f("Integrator \"gbdpt\"", 24, 18, false, true, true);
    const SubpathShiftContext &sc = f.g->shiftContext();
    const BidirContext &bc = f.g->bidirContext();
    const Scene &scene = *bc.scene;
    std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
    Arena arena;
    int tested[3] = {0, 0, 0};  // by glossy vertex count 1, 2, 3+
    for (int trial = 0; trial < 20000 && tested[0] + tested[1] < 40; ++trial) {
        Ray ray;
        TrialSample(*sampler, *bc.camera, trial, &ray);
        ShiftSubpath x = ArenaSubpath(arena, 7);
        x.n = GenerateCameraSubpath(bc, ray, *sampler, arena, 6, x.v, x.b);
        PrepareSubpath(sc, &x);
        // b: the first diffuse vertex; c: the next; only glossy (no ideal specular) between.
        int b = -1, c = -1;
        for (int i = 1; i < x.n; ++i)
            if (IsDiffuseVertex(sc, x.v[i], &x.b[i])) {
                if (b < 0) b = i;
                else { c = i; break; }
            }
        const int k = c - b - 1;
        if (b < 0 || c < 0 || k < 1 || x.v[c].type != VertexType::Surface || x.v[b].type != VertexType::Surface) continue;
        bool onlyGlossy = true;
        for (int j = b + 1; j < c; ++j) onlyGlossy &= !x.deltaSample[j];
        if (!onlyGlossy) continue;
        ChainInterior in;
        bool ok = true;
        for (int j = 0; ok && j < k; ++j) {
            const PathVertex &xv = x.v[b + 1 + j];
            ok = VertexInteraction(scene, xv, x.v[b + j].p, &in.si[j]);
            in.bsdf[j] = &x.b[b + 1 + j];
            in.wo[j] = xv.wo;
            in.wi[j] = Normalize(x.v[b + 2 + j].p - xv.p);
            in.transmit[j] = Transmits(in.wo[j], in.wi[j], Vec3(x.b[b + 1 + j].ns()));
            in.specular[j] = false;
            in.geomId[j] = xv.geomId;
        }
        const PathVertex &xb = x.v[b], &xc = x.v[c];
        ManifoldChain chain;
        if (!ok || !BuildChain(sc, EndpointSP(xb.p, xb.ng, xb.geomId), in, k, EndpointSP(xc.p, xc.ng, xc.geomId), &chain))
            continue;
        const Float phi = ChainDirectionsPerArea(chain);
        if (!(phi > 0)) continue;
        // Inverse map: directions (omega_b, omega_g...) -> (c's tangent coordinates, O_g...).
        const int n = 2 * (k + 1);
        std::vector<Vec3> dirs(k + 1), t1(k + 1), t2(k + 1);
        for (int j = 0; j <= k; ++j) {
            dirs[j] = Normalize(chain.v[j + 1].sp.p - chain.v[j].sp.p);
            CoordinateSystem(dirs[j], &t1[j], &t2[j]);
        }
        const ManifoldVertex &cv = chain.back();
        auto forward = [&](const std::vector<Vec3> &d, Eigen::VectorXd *out) {
            ManifoldChain y = chain;
            Point3 o = chain.front().sp.p;
            for (int j = 0; j <= k; ++j) {
                SurfaceInteraction si;
                Float len = Distance(chain.v[j + 1].sp.p, chain.v[j].sp.p);
                if (!scene.intersect(Ray(o + d[j] * (1e-5 * len), d[j]), &si) || si.geomId != chain.v[j + 1].sp.primitiveId)
                    return false;
                ManifoldSurfacePoint sp = j < k ? sc.mscene->fromInteraction(si) : EndpointSP(si.p, si.n, si.geomId);
                sp.etaInterior = chain.v[j + 1].sp.etaInterior;
                sp.etaExterior = chain.v[j + 1].sp.etaExterior;
                SetupManifoldVertex(&y.v[j + 1], sp, &chain.v[j + 1].frameRef);
                o = si.p;
            }
            out->resize(n);
            (*out)(0) = Dot(y.back().sp.p - cv.sp.p, cv.s);
            (*out)(1) = Dot(y.back().sp.p - cv.sp.p, cv.t);
            for (int j = 1; j <= k; ++j) {
                bool good = false;
                Vec2 h = ProjectedHalfVector(y, j, &good);
                if (!good) return false;
                (*out)(2 * j) = h.x;
                (*out)(2 * j + 1) = h.y;
            }
            return true;
        };
        const Float eps = 2e-4;  // single-precision hits: smaller steps measure their noise
        Eigen::MatrixXd D(n, n);
        for (int col = 0; col < n && ok; ++col) {
            std::vector<Vec3> dp = dirs, dm = dirs;
            const int j = col / 2;
            const Vec3 &t = col % 2 ? t2[j] : t1[j];
            dp[j] = Perturb(dirs[j], t, eps);
            dm[j] = Perturb(dirs[j], t, -eps);
            Eigen::VectorXd vp, vm;
            ok = forward(dp, &vp) && forward(dm, &vm);
            if (ok) D.col(col) = (vp - vm) / (2 * eps);
        }
        if (!ok) continue;
        const double det = std::abs(D.determinant());
        EXPECT_NEAR(det * phi, 1.0, 1e-2) << k << " glossy vertices, trial " << trial;
        ++tested[std::min(k, 3) - 1];
    }
    std::printf("glossy second chains checked: %d with 1 glossy vertex, %d with 2, %d with more\n", tested[0],
                tested[1], tested[2]);
    EXPECT_GE(tested[0], 10) << "chains through the near-specular metal sphere";
    EXPECT_GE(tested[1], 5) << "chains through the rough glass sphere";
}

// Empty second chain: the same quantity reduces to |cos_end| / d^2 (the
// reconnection Jacobian's ingredients).
TEST(GBDPTShift, DirectSolidAngleIsCosOverDistanceSquared) {
    ManifoldSurfacePoint a, b;
    a.p = Point3(0, 0, 0);
    a.n = Vec3(0, 1, 0);
    CoordinateSystem(a.n, &a.dpdu, &a.dpdv);
    b.p = Point3(0.3, 2, 0.5);
    b.n = Normalize(Vec3(0.2, -1, 0.1));
    CoordinateSystem(b.n, &b.dpdu, &b.dpdv);
    ManifoldSurfacePoint pts[2] = {a, b};
    ManifoldChain c;
    ASSERT_TRUE(MakeChain(pts, 2, nullptr, nullptr, &c));
    Vec3 d = b.p - a.p;
    Float expect = AbsDot(Normalize(d), Vec3(b.n)) / d.lengthSquared();
    EXPECT_NEAR(ChainSolidAnglePerArea(c) / expect, 1.0, 1e-9);
}

// Image-plane factor dA_b/ds (light-tracing shift, |T'| of the eye part):
// ratio between two raster positions against finite differences of camera-ray hits.
TEST(GBDPTShift, EyeAreaFactorMatchesFiniteDifferences) {
    Fixture f;
    const Scene &scene = *f.job.scene;
    const Camera &cam = *scene.camera;
    auto hitArea = [&](Point2 r, Point3 *p, Vec3 *n) {
        const Float h = 1e-3;
        Point3 q[4];
        Point2 o[4] = {{h, 0}, {-h, 0}, {0, h}, {0, -h}};
        for (int i = 0; i < 4; ++i) {
            Ray ray;
            cam.generateRay(CameraSample{Point2(r.x + o[i].x, r.y + o[i].y), Point2(0.5, 0.5)}, &ray);
            SurfaceInteraction si;
            if (!scene.intersect(ray, &si)) return Float(-1);
            q[i] = si.p;
        }
        Ray ray;
        cam.generateRay(CameraSample{r, Point2(0.5, 0.5)}, &ray);
        SurfaceInteraction si;
        if (!scene.intersect(ray, &si)) return Float(-1);
        *p = si.p;
        *n = si.n;
        Vec3 ex = (q[0] - q[1]) / (2 * h), ey = (q[2] - q[3]) / (2 * h);
        return Cross(ex, ey).length();
    };
    Ray r0;
    cam.generateRay(CameraSample{Point2(12, 9), Point2(0.5, 0.5)}, &r0);
    Vec3 n0 = cam.lensNormal();
    // Floor and back-wall pixels (the spheres' silhouettes are avoided by the check below).
    const Point2 pairs[][2] = {{{3.5, 16.5}, {20.5, 15.5}}, {{4.5, 3.5}, {19.5, 5.5}}, {{2.5, 9.5}, {12.5, 15.5}}};
    for (const auto &pr : pairs) {
        Point3 p1, p2;
        Vec3 n1, n2;
        Float a1 = hitArea(pr[0], &p1, &n1), a2 = hitArea(pr[1], &p2, &n2);
        ASSERT_GT(a1, 0);
        ASSERT_GT(a2, 0);
        Float f1 = EyeAreaFactor(r0.o, n0, p1, n1), f2 = EyeAreaFactor(r0.o, n0, p2, n2);
        EXPECT_NEAR((f1 / f2) / (a1 / a2), 1.0, 1e-3);
    }
}

// Eq. 8 normalisation over a whole path: for a camera path ending on the light,
// every strategy (s, t) of the same full path (t >= 2 from the shifted camera
// subpath, t = 1 by the light-tracing shift) gives w_ij,st(x) (1 + rho_st) =
// (p_st(x) + |T'| p_st(y)) / D; their sum over st must be 1, i.e.
// sum_st [w_ij,st(x) + w_ji,st(T_ij x)] = 1.
// With "lighttracing false" the t = 1 strategies are out of play (the
// integrator's StrategySet): the remaining strategies' weights sum to one alone.
// Env scene: the camera paths end on the environment (escaped) or, appended,
// at the point light after a diffuse vertex; both need every strategy shifted
// the same way (environment shift, reconnection to the point).
// Glossy box: the mirror sphere is near-specular metal and the glass sphere
// near-specular rough glass, so second chains hold glossy vertices (walked
// with their half-vectors kept).
bool HasGlossySecondChain(const SubpathShiftContext &sc, const ShiftSubpath &x) {
    int diffuse = 0;
    for (int i = 1; i < x.n; ++i) {
        if (IsDiffuseVertex(sc, x.v[i], &x.b[i])) {
            if (++diffuse == 2) return false;
        } else if (diffuse == 1 && !x.deltaSample[i]) {
            for (int j = i + 1; j < x.n; ++j)
                if (IsDiffuseVertex(sc, x.v[j], &x.b[j])) return true;
            return false;
        }
    }
    return false;
}

// Point-light paths: cuts camera subpath x after vertex `cut` and appends the
// point light, as next-event estimation would reach it.
void EndAtPointLight(const BidirContext &bc, const Light *point, int cut, ShiftSubpath &x) {
    x.n = cut + 1;
    PathVertex &v = x.v[x.n];
    v = PathVertex();
    v.type = VertexType::Light;
    v.light = point;
    v.flags = VERTEX_DELTA_LIGHT;
    LightLiSample ls;
    point->sampleLi(AsInteraction(x.v[x.n - 1]), Point2(0.5, 0.5), &ls);
    v.p = ls.pLight.p;
    x.b[x.n] = BSDF();
    ++x.n;
    // The density of the vertex before the diffuse one as generated from
    // the light side (stored by the walk for the direction it sampled).
    if (x.n >= 3)
        x.v[x.n - 3].pdfRev = PdfArea(bc, x.v[x.n - 2], &x.b[x.n - 2], &x.v[x.n - 1], x.v[x.n - 3],
                                      TransportMode::Importance);
}

// Paths checked and what they went through.
struct CombinedCounts {
    int paths = 0, withLT = 0, withChain = 0, withGlossy = 0, toEnv = 0, toPoint = 0, oneSided = 0;
};

// Whether camera path x ends as the check needs (env: on the environment or
// the point light, 100 of each; else on a surface emitter) with no vertices
// nearly coinciding.
bool EndsAsChecked(const BidirContext &bc, const ShiftSubpath &x, bool env, const CombinedCounts &c) {
    const int n = x.n;
    const PathVertex &e = x.v[n - 1];
    const bool pointEnd = e.isDeltaLight() && !e.isInfiniteLight();
    if (env) {
        if (n < 3 || !(e.isInfiniteLight() || pointEnd)) return false;
        if ((pointEnd ? c.toPoint : c.toEnv) >= 100) return false;  // 100 of each kind
    } else {
        if (n < 3 || !EmitterOf(bc, e) || e.type != VertexType::Surface) return false;
        if (EmittedRadiance(bc, x.v[n - 1], x.v[n - 2]).isBlack()) return false;
    }
    bool corner = false;
    for (int k = 1; k + 1 < n; ++k) corner |= Distance(x.v[k].p, x.v[k + 1].p) < 1e-2;
    return !corner;
}

void CheckCombinedWeightsSumToOne(const std::string &line, bool lightTracing, bool env = false, bool glossy = false) {
    Fixture f(line, 24, 18, env, glossy, glossy);
    const SubpathShiftContext &sc = f.g->shiftContext();
    const BidirContext &bc = f.g->bidirContext();
    std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
    Arena arena;
    CombinedCounts c;
    const Light *point = nullptr;
    for (const auto &l : f.job.scene->lights)
        if (l->flags & LIGHT_DELTA_POSITION) point = l.get();
    for (int trial = 0; trial < (env || glossy ? 200000 : 20000) && c.paths < 200; ++trial) {
        Ray ray;
        const CameraSample cs = TrialSample(*sampler, *bc.camera, trial, &ray);
        const int maxV = 6;
        ShiftSubpath x = ArenaSubpath(arena, maxV);
        x.n = GenerateCameraSubpath(bc, ray, *sampler, arena, maxV - 1, x.v, x.b);
        // Point-light paths: cut after the k-th vertex (k drawn from the trial
        // index) if that one is diffuse.
        const int cut = 1 + (trial / 2) % 4;
        if (env && point && trial % 2 && cut < x.n && x.v[cut].type == VertexType::Surface &&
            IsDiffuseVertex(sc, x.v[cut], &x.b[cut]))
            EndAtPointLight(bc, point, cut, x);
        if (!EndsAsChecked(bc, x, env, c)) continue;
        const int n = x.n;
        const PathVertex &e = x.v[n - 1];
        const bool pointEnd = e.isDeltaLight() && !e.isInfiniteLight();
        PrepareSubpath(sc, &x);
        const bool glossyChain = HasGlossySecondChain(sc, x);
        if (glossy && !glossyChain && c.paths >= 2 * c.withGlossy) continue;  // at least a third through glossy chains
        CameraShift sh;
        SubpathShiftStats st;
        ShiftCameraSubpath(sc, x, cs, {1, 0}, arena, &sh, &st);
        if (sh.validUpTo != n - 1) continue;  // a failed path falls back as a whole
        // An offset that reconnects along a grazing edge (rho ~ 0, e.g. across the
        // box's corner) has degenerate Jacobians; with light tracing its
        // light-tracing shift fails and the path is skipped below.
        bool grazing = false;
        for (int k = 1; k < n; ++k) grazing |= !(sh.rho[k] > 1e-6 && sh.rho[k] < 1e6);
        if (grazing) continue;
        double sum = 0, sumx = 0;
        // The camera-subpath shift succeeded but the light-tracing shift did
        // not: the integrator then falls back for one strategy only, and the
        // path's weights no longer sum to one. Rare numerical cases only.
        if (!SumStrategyWeights(sc, bc, x, sh, cs, lightTracing, arena, &st, &sum, &sumx, &c.withLT)) {
            ++c.oneSided;
            continue;
        }
        bool chain = false;
        for (int k = 1; k < n; ++k) chain |= x.deltaSample[k] != 0;
        c.withChain += chain;
        c.withGlossy += glossyChain;
        c.toEnv += e.isInfiniteLight();
        c.toPoint += pointEnd;
        EXPECT_NEAR(sumx, 1.0, 1e-4) << "BDPT weights of the enumerated strategies";
        EXPECT_NEAR(sum, 1.0, 2e-3) << "path of " << n << " vertices, chain " << chain << ", glossy chain " << glossyChain
                                    << ", trial " << trial
                                    << (e.isInfiniteLight() ? ", to the environment" : pointEnd ? ", to a point" : "");
        ++c.paths;
    }
    EXPECT_GE(c.paths, 100);
    EXPECT_LE(c.oneSided, c.paths / 50) << "paths whose light-tracing strategy alone failed to shift";
    if (env) {
        EXPECT_EQ(c.toEnv, 100);
        EXPECT_EQ(c.toPoint, 100);
    }
    if (glossy) {
        EXPECT_GE(c.withGlossy, 60) << "paths whose second chain holds glossy vertices";
    }
    std::printf("%s%s: %d paths (%d light-tracing strategies, %d with specular chains, %d with glossy second chains; "
                "%d to the environment, %d to the point light; %d with only the light-tracing shift failed)\n",
                line.c_str(), glossy ? " (glossy box)" : "", c.paths, c.withLT, c.withChain, c.withGlossy, c.toEnv,
                c.toPoint, c.oneSided);
}

TEST(GBDPTShift, CombinedWeightsOfAllStrategiesSumToOne) {
    CheckCombinedWeightsSumToOne("Integrator \"gbdpt\"", true);
}
TEST(GBDPTShift, CombinedWeightsSumToOneWithEnvironmentAndPointLight) {
    CheckCombinedWeightsSumToOne("Integrator \"gbdpt\"", true, true);
}
TEST(GBDPTShift, CombinedWeightsSumToOneThroughGlossySecondChains) {
    CheckCombinedWeightsSumToOne("Integrator \"gbdpt\"", true, false, true);
}
TEST(GBDPTShift, CombinedWeightsSumToOneWithoutLightTracing) {
    CheckCombinedWeightsSumToOne("Integrator \"gbdpt\" \"bool lighttracing\" \"false\"", false);
}

// Camera-subpath shift: T_ji(T_ij(x)) = x on the shifted vertices, rho_ij(x)
// rho_ji(y) = 1, and the Eq. 8 weights satisfy w_ji,st(y) = rho w_ij,st(x)
// (so w_ij,st(x) + w_ji,st(y) = (p_st(x) + |T'| p_st(y)) / sum_k [...], which
// sums to one over the strategies of a path).
TEST(GBDPTShift, CameraShiftIsInvertibleAndWeightsPair) {
    // Third run: near-specular rough glass (half-vector refraction in the first
    // chain); fourth: also a near-specular metal sphere (glossy second chains).
    for (int config = 0; config < 4; ++config) {
        const char *line = config == 1 ? "Integrator \"gbdpt\" \"string shift\" \"halfvector\"" : "Integrator \"gbdpt\"";
        const bool roughGlass = config >= 2, glossyMirror = config == 3;
        Fixture f(line, 24, 18, false, roughGlass, glossyMirror);
        const SubpathShiftContext &sc = f.g->shiftContext();
        const BidirContext &bc = f.g->bidirContext();
        std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
        Arena arena;
        int pairs = 0, chains = 0, weights = 0, asymmetric = 0, glossyRefractions = 0, glossyChains = 0;
        for (int trial = 0; trial < 3000; ++trial) {
            Ray ray;
            const CameraSample cs = TrialSample(*sampler, *bc.camera, trial, &ray);
            const int maxV = 7;
            ShiftSubpath x = ArenaSubpath(arena, maxV);
            x.n = GenerateCameraSubpath(bc, ray, *sampler, arena, maxV, x.v, x.b);
            PrepareSubpath(sc, &x);
            CameraShift fwd, back;
            SubpathShiftStats st;
            ShiftCameraSubpath(sc, x, cs, {1, 0}, arena, &fwd, &st);
            if (fwd.r < 0 || fwd.validUpTo != x.n - 1) continue;
            // Paths through the box's corners (vertices within 1e-2 of each other)
            // have reconnection Jacobians dominated by single-precision hit noise.
            bool corner = false;
            for (int k = 1; k + 1 < x.n; ++k) corner |= Distance(x.v[k].p, x.v[k + 1].p) < 1e-2;
            if (corner) continue;
            CameraSample cs2 = cs;
            cs2.pFilm.x += 1;
            SubpathShiftStats stb;
            ShiftCameraSubpath(sc, fwd.y, cs2, {-1, 0}, arena, &back, &stb);
            // The inverse must succeed where the forward shift did (else the
            // fallback would be one-sided); single-precision hits make rare
            // reconnections fail on one side only: at most 1% tolerated.
            if (back.r != fwd.r || back.validUpTo != x.n - 1) {
                ++asymmetric;
                continue;
            }
            for (int k = 1; k < x.n; ++k) {
                Float scale = std::max<Float>(1, Vec3(x.v[k].p).length());
                EXPECT_LT(Distance(back.y.v[k].p, x.v[k].p), 1e-3 * scale) << line << " vertex " << k;
                Float prod = fwd.rho[k] * back.rho[k];
                EXPECT_NEAR(prod, 1.0, 5e-3) << line << " vertex " << k;
            }
            for (int j = fwd.r + 1; j < x.n; ++j) EXPECT_EQ(fwd.y.v[j].p, x.v[j].p);
            for (int k = 1; k + 1 < fwd.r; ++k)
                glossyRefractions += !x.deltaSample[k] && x.b[k] && !IsDiffuseVertex(f.g->shiftContext(), x.v[k], &x.b[k]) &&
                                     Transmits(x.v[k].wo, Normalize(x.v[k + 1].p - x.v[k].p), Vec3(x.b[k].ns()));
            bool chain = false;
            for (int k = 1; k < fwd.r; ++k) chain |= x.deltaSample[k] != 0;
            chains += chain;
            glossyChains += HasGlossySecondChain(sc, x);
            ++pairs;
            // Eq. 8 pairing for the emitter-hit strategy (s = 0) and the BDPT weights of both paths.
            int t = x.n;
            if (x.v[t - 1].type == VertexType::Surface) {
                SubpathView none{nullptr, nullptr, 0};
                Float wx = MISWeight(bc, none, x.view(), 0, t, nullptr);
                Float wy = MISWeight(bc, none, fwd.y.view(), 0, t, nullptr);
                Float wxb = MISWeight(bc, none, back.y.view(), 0, t, nullptr);
                Float rho = fwd.rho[t - 1], rhoB = back.rho[t - 1];
                if (wx > 0 && wy > 0) {
                    EXPECT_NEAR(wxb / wx, 1.0, 5e-3);
                    Float wij = CombinedWeight(wx, wy, rho), wji = CombinedWeight(wy, wxb, rhoB);
                    EXPECT_NEAR(wji / (rho * wij), 1.0, 5e-3) << line;
                    ++weights;
                }
            }
        }
        EXPECT_GT(pairs, 300) << line;
        EXPECT_LE(asymmetric, pairs / 100) << line;
        EXPECT_GT(weights, 300) << line;
        if (config == 0) {
            EXPECT_GT(chains, 5) << "paths with specular chains";
        }
        if (roughGlass) {
            EXPECT_GT(glossyRefractions, 5) << "pairs through the rough glass's half-vector refraction";
        }
        if (glossyMirror) {
            EXPECT_GT(glossyChains, 20) << "pairs through glossy second chains";
        }
        std::printf("%s%s: %d shifted pairs (%d with specular chains, %d glossy refractions, %d glossy second chains), "
                    "%d weight pairs, %d one-sided\n",
                    line, glossyMirror ? " (glossy box)" : roughGlass ? " (rough glass)" : "", pairs, chains,
                    glossyRefractions, glossyChains, weights, asymmetric);
    }
}

// Russian roulette (rrdepth): the offset reuses the base's decisions, so the
// offset's throughput carries the base's 1/q factors and f(y)/f(x) and rho do
// not depend on them. Base subpaths generated with roulette from the first
// bounce are shifted as they are and again with the factors taken out (rrScale
// 1, throughputs divided by the product so far): the offset/base throughput
// ratios and rho must agree at every shifted vertex. Dropping a 1/q factor in
// the shift changes the ratio by that factor.
TEST(GBDPTShift, RouletteFactorsCancelInTheShiftRatio) {
    Fixture f;
    const SubpathShiftContext &sc = f.g->shiftContext();
    BidirContext rr = f.g->bidirContext();
    rr.rrDepth = 0;
    std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
    Arena arena;
    const int maxV = 7;
    int compared = 0, withRoulette = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        Ray ray;
        const CameraSample cs = TrialSample(*sampler, *rr.camera, trial, &ray);
        ShiftSubpath x = ArenaSubpath(arena, maxV), xs = ArenaSubpath(arena, maxV);
        x.n = GenerateCameraSubpath(rr, ray, *sampler, arena, maxV, x.v, x.b);
        PrepareSubpath(sc, &x);
        xs.n = x.n;
        double C = 1;
        bool any = false;
        for (int j = 0; j < x.n; ++j) {
            xs.v[j] = x.v[j];
            xs.b[j] = x.b[j];
            xs.deltaSample[j] = x.deltaSample[j];
            xs.v[j].setThroughput(x.v[j].throughput() / C);
            xs.v[j].rrScale = 1;
            any |= x.v[j].rrScale != 1;
            C *= x.v[j].rrScale;
        }
        CameraShift a, b;
        SubpathShiftStats st;
        ShiftCameraSubpath(sc, x, cs, {1, 0}, arena, &a, &st);
        ShiftCameraSubpath(sc, xs, cs, {1, 0}, arena, &b, &st);
        ASSERT_EQ(a.validUpTo, b.validUpTo);
        if (!any || a.validUpTo < 2) continue;
        ++withRoulette;
        for (int j = 1; j <= a.validUpTo; ++j) {
            Spectrum ra = SafeDiv(a.y.v[j].throughput(), x.v[j].throughput());
            Spectrum rb = SafeDiv(b.y.v[j].throughput(), xs.v[j].throughput());
            for (int c = 0; c < 3; ++c)
                if (rb[c] > 0) {
                    EXPECT_NEAR(ra[c] / rb[c], 1.0, 1e-4) << "vertex " << j << " of " << x.n;
                    ++compared;
                }
            EXPECT_EQ(a.rho[j], b.rho[j]);  // densities only: the same arithmetic
        }
    }
    EXPECT_GT(withRoulette, 200);
    EXPECT_GT(compared, 1000);
    std::printf("%d shifted subpaths with roulette factors, %d throughput ratios compared\n", withRoulette, compared);
}

// Incremental offset weights (bidir.h MISSplit): for strategies whose camera
// endpoint lies at least 3 vertices past the reconnection r, the offset's BDPT
// weight from the base's split parts at r + 1 and the offset's prefix sum
// equals the full O(n) MISWeight of the offset, for every light subpath
// length, with and without light tracing, and with merging terms (G-VCM: a
// constant eta, merges at every mergeable vertex in the sums).
TEST(GBDPTShift, IncrementalOffsetWeightsEqualFullWeights) {
    for (int config = 0; config < 3; ++config) {
        const bool lightTracing = config != 1, merging = config == 2;
        Fixture f(lightTracing ? "Integrator \"gbdpt\" \"integer maxdepth\" [12]"
                               : "Integrator \"gbdpt\" \"integer maxdepth\" [12] \"bool lighttracing\" \"false\"");
        const SubpathShiftContext &sc = f.g->shiftContext();
        const BidirContext &bc = f.g->bidirContext();
        StrategySet set = bc.strategies;
        if (merging) {
            set.merging = true;
            set.mergeRoughOnly = true;
            set.kernel = nullptr;
            set.mergeFactor = 0.37;  // eta = pi r^2 N, of the order of the box's area densities
        }
        int mergeMatters = 0;
        std::unique_ptr<Sampler> sampler = f.job.sampler->clone();
        Arena arena;
        const int maxV = 12;
        int compared = 0;
        for (int trial = 0; trial < 3000; ++trial) {
            Ray ray;
            const CameraSample cs = TrialSample(*sampler, *bc.camera, trial, &ray);
            ShiftSubpath x = ArenaSubpath(arena, maxV), L = ArenaSubpath(arena, maxV);
            x.n = GenerateCameraSubpath(bc, ray, *sampler, arena, maxV, x.v, x.b);
            L.n = GenerateLightSubpath(bc, *sampler, arena, maxV - 1, L.v, L.b);
            PrepareSubpath(sc, &x);
            PrepareSubpath(sc, &L);
            CameraShift sh;
            SubpathShiftStats st;
            ShiftCameraSubpath(sc, x, cs, {0, 1}, arena, &sh, &st);
            const int m = sh.r + 1;
            if (sh.r < 0 || m + 2 > sh.validUpTo) continue;
            const Float Q = CameraPrefixSum(bc, set, sh.y.view(), m);
            for (int t = m + 3; t <= sh.validUpTo + 1; ++t)
                for (int s = 0; s <= L.n; ++s) {
                    if (s >= 1 && (!IsDiffuseVertex(sc, x.v[t - 1], &x.b[t - 1]) || x.v[t - 1].type != VertexType::Surface))
                        continue;
                    if (s >= 2 && !IsDiffuseVertex(sc, L.v[s - 1], &L.b[s - 1])) continue;
                    if (s == 0 && !(EmitterOf(bc, x.v[t - 1]))) continue;
                    MISSplit parts;
                    Float wx = MISWeight(bc, set, L.view(), x.view(), s, t, nullptr, m, &parts);
                    Float wy = MISWeight(bc, set, L.view(), sh.y.view(), s, t, nullptr);
                    ASSERT_TRUE(parts.valid);
                    EXPECT_NEAR(parts.weight(Q) / wy, 1.0, 1e-9) << "s " << s << " t " << t << " r " << sh.r;
                    EXPECT_NEAR(wx, MISWeight(bc, set, L.view(), x.view(), s, t, nullptr), 1e-15);
                    if (merging && std::abs(wy / MISWeight(bc, bc.strategies, L.view(), sh.y.view(), s, t, nullptr) - 1) > 1e-3)
                        ++mergeMatters;
                    ++compared;
                }
        }
        EXPECT_GT(compared, 300) << "light tracing " << lightTracing << ", merging " << merging;
        // The merge terms change the weights being compared (else merging would go untested).
        if (merging) {
            EXPECT_GT(mergeMatters, compared / 4);
        }
        std::printf("light tracing %d, merging %d: %d offset weights compared (%d changed by merging)\n",
                    int(lightTracing), int(merging), compared, mergeMatters);
    }
}
