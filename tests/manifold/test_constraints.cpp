// Constraint derivatives, determinants and the generalised geometry term against
// finite differences on analytic scenes.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "configs.h"

using namespace gradus;
using namespace gradus::testing;

namespace {

std::vector<ChainConfig> AllConfigs() {
    std::vector<ChainConfig> v;
    v.push_back(MirrorConfig());
    v.push_back(MirrorConfig(true));
    v.push_back(SlabConfig());
    v.push_back(SphereConfig());
    v.push_back(TwoSlabConfig());
    return v;
}

// Copy of c with vertex j moved by e on its surface (same frame reference).
ManifoldChain Moved(const AnalyticScene &scene, const ManifoldChain &c, int j, const Vec3 &e) {
    ManifoldChain m = c;
    ManifoldVertex &v = m.v[j];
    SetupManifoldVertex(&v, scene.moveOn(c.v[j].sp, e), &c.v[j].frameRef);
    return m;
}

// Perturb the interior vertices off the specular configuration so derivatives
// are checked at a generic point too.
ManifoldChain OffManifold(const AnalyticScene &scene, const ManifoldChain &c) {
    ManifoldChain m = c;
    for (int i = 1; i < c.size - 1; ++i) {
        const ManifoldVertex &v = c.v[i];
        m = Moved(scene, m, i, v.s * (0.013 * i) - v.t * 0.021);
    }
    return m;
}

void CheckDerivatives(const AnalyticScene &scene, const ManifoldChain &c, const std::string &name) {
    const Float h = 1e-6;
    for (int i = 1; i < c.size - 1; ++i) {
        Vec2 val;
        Mat2 blocks[3];
        ASSERT_TRUE(ConstraintDerivatives(c, i, &val, &blocks[0], &blocks[1], &blocks[2])) << name;
        Vec2 direct = ProjectedHalfVector(c, i);
        EXPECT_NEAR(val.x, direct.x, 1e-15);
        for (int nb = 0; nb < 3; ++nb) {
            int j = i - 1 + nb;
            for (int axis = 0; axis < 2; ++axis) {
                Vec3 e = axis == 0 ? c.v[j].s : c.v[j].t;
                bool okP, okM;
                Vec2 cp = ProjectedHalfVector(Moved(scene, c, j, e * h), i, &okP);
                Vec2 cm = ProjectedHalfVector(Moved(scene, c, j, e * -h), i, &okM);
                ASSERT_TRUE(okP && okM);
                Vec2 fd = (cp - cm) / (2 * h);
                const Mat2 &B = blocks[nb];
                Float a0 = axis == 0 ? B.a : B.b, a1 = axis == 0 ? B.c : B.d;
                Float tol = 1e-6 * std::max<Float>(1, B.maxAbs());
                EXPECT_NEAR(a0, fd.x, tol) << name << " vertex " << i << " wrt " << j << " axis " << axis;
                EXPECT_NEAR(a1, fd.y, tol) << name << " vertex " << i << " wrt " << j << " axis " << axis;
            }
        }
    }
}

}  // namespace

TEST(ManifoldConstraints, BaseChainsAreSpecular) {
    for (const ChainConfig &cfg : AllConfigs()) {
        ASSERT_GE(cfg.base.size, 3) << cfg.name;
        for (int i = 1; i < cfg.base.size - 1; ++i) {
            bool ok;
            Vec2 c = ProjectedHalfVector(cfg.base, i, &ok);
            ASSERT_TRUE(ok) << cfg.name;
            if (cfg.base.v[i].specular) {
                EXPECT_NEAR(c.x, 0, 1e-12) << cfg.name;
                EXPECT_NEAR(c.y, 0, 1e-12) << cfg.name;
            } else {
                EXPECT_GT(std::hypot(c.x, c.y), 1e-2) << cfg.name << ": glossy base should be off-specular";
            }
        }
    }
}

TEST(ManifoldConstraints, DerivativesMatchFiniteDifferences) {
    for (const ChainConfig &cfg : AllConfigs()) {
        CheckDerivatives(cfg.scene, cfg.base, cfg.name);
        CheckDerivatives(cfg.scene, OffManifold(cfg.scene, cfg.base), cfg.name + " (off manifold)");
    }
}

TEST(ManifoldConstraints, DerivativeOfFrameMattersOnCurvedSurfaces) {
    // On the sphere the frame rotates with the normal; dropping that term must be
    // detectable, i.e. the self block differs from the pure direction part.
    ChainConfig cfg = SphereConfig();
    ManifoldChain c = OffManifold(cfg.scene, cfg.base);
    Vec2 v;
    Mat2 a, b, d;
    ASSERT_TRUE(ConstraintDerivatives(c, 1, &v, &a, &b, &d));
    ManifoldChain flat = c;
    flat.v[1].dnds = flat.v[1].dndt = Vec3(0, 0, 0);
    Mat2 b2;
    ASSERT_TRUE(ConstraintDerivatives(flat, 1, &v, &a, &b2, &d));
    EXPECT_GT((b - b2).maxAbs(), 1e-3);
}

// Determinant of d(o_1..o_k)/d(x_1..x_k) by finite differences.
Float FiniteDifferenceConstraintDet(const AnalyticScene &scene, const ManifoldChain &c,
                                    Eigen::MatrixXd *out = nullptr) {
    int k = c.size - 2;
    Eigen::MatrixXd A(2 * k, 2 * k);
    const Float h = 1e-6;
    for (int j = 1; j <= k; ++j)
        for (int axis = 0; axis < 2; ++axis) {
            Vec3 e = axis == 0 ? c.v[j].s : c.v[j].t;
            ManifoldChain p = Moved(scene, c, j, e * h), m = Moved(scene, c, j, e * -h);
            for (int i = 1; i <= k; ++i) {
                Vec2 d = (ProjectedHalfVector(p, i) - ProjectedHalfVector(m, i)) / (2 * h);
                A(2 * (i - 1), 2 * (j - 1) + axis) = d.x;
                A(2 * (i - 1) + 1, 2 * (j - 1) + axis) = d.y;
            }
        }
    if (out) *out = A;
    return A.determinant();
}

TEST(ManifoldConstraints, DeterminantsMatchFiniteDifferences) {
    for (const ChainConfig &cfg : AllConfigs()) {
        Float fd = FiniteDifferenceConstraintDet(cfg.scene, cfg.base);
        Float an = ConstraintDeterminant(cfg.base);
        EXPECT_NEAR(an, fd, 1e-6 * std::abs(fd)) << cfg.name;
        // All-glossy chain: nothing is eliminated, |dx/dO| = 1/|det A|.
        ManifoldChain g = cfg.base;
        for (int i = 1; i < g.size - 1; ++i) g.v[i].specular = false;
        EXPECT_NEAR(HalfVectorJacobian(g), 1 / std::abs(fd), 1e-6 / std::abs(fd)) << cfg.name;
        // All-specular chain: every vertex is eliminated, |dx/dO| = 1.
        ManifoldChain s = cfg.base;
        for (int i = 1; i < s.size - 1; ++i) s.v[i].specular = true;
        EXPECT_NEAR(HalfVectorJacobian(s), 1, 1e-9) << cfg.name;
    }
}

TEST(ManifoldConstraints, MixedChainEliminatesSpecularVertices) {
    // Four interfaces, two of them ideal: |dx_g/do_g| is the inverse determinant
    // of the Schur complement of the finite-difference matrix.
    ChainConfig cfg = TwoSlabConfig();
    ManifoldChain c = OffManifold(cfg.scene, cfg.base);
    c.v[1].specular = false;
    c.v[2].specular = true;
    c.v[3].specular = true;
    c.v[4].specular = false;
    Eigen::MatrixXd A;
    FiniteDifferenceConstraintDet(cfg.scene, c, &A);
    std::vector<int> g = {0, 1, 6, 7}, p = {2, 3, 4, 5};
    Eigen::MatrixXd Agg(4, 4), Agp(4, 4), Apg(4, 4), App(4, 4);
    for (int r = 0; r < 4; ++r)
        for (int q = 0; q < 4; ++q) {
            Agg(r, q) = A(g[r], g[q]);
            Agp(r, q) = A(g[r], p[q]);
            Apg(r, q) = A(p[r], g[q]);
            App(r, q) = A(p[r], p[q]);
        }
    Eigen::MatrixXd S = Agg - Agp * App.inverse() * Apg;
    Float expected = 1 / std::abs(S.determinant());
    EXPECT_NEAR(HalfVectorJacobian(c), expected, 1e-6 * expected);
}

// G by finite differences: move the end vertex, walk, measure the projected
// solid angle swept by the first segment at x_0.
Float FiniteDifferenceG(const ChainConfig &cfg) {
    const ManifoldChain &c = cfg.base;
    ManifoldWalkOptions opts;
    opts.relativeTolerance = 1e-13;
    opts.maxIterations = 60;
    Vec3 w0 = Normalize(c.v[1].sp.p - c.v[0].sp.p), e1, e2;
    CoordinateSystem(w0, &e1, &e2);
    const Float h = 1e-5;
    Float J[2][2];
    for (int axis = 0; axis < 2; ++axis) {
        Vec3 e = axis == 0 ? c.back().s : c.back().t;
        Vec3 w[2];
        for (int sgn = 0; sgn < 2; ++sgn) {
            ManifoldSurfacePoint t = cfg.scene.moveOn(c.back().sp, e * (sgn ? -h : h));
            ManifoldWalkResult r = ManifoldWalk(cfg.scene, c, c.front().sp, t, opts);
            EXPECT_TRUE(r.ok()) << cfg.name << " " << ToString(r.status);
            w[sgn] = Normalize(r.chain.v[1].sp.p - r.chain.v[0].sp.p);
        }
        Vec3 dw = (w[0] - w[1]) / (2 * h);
        J[0][axis] = Dot(dw, e1);
        J[1][axis] = Dot(dw, e2);
    }
    return AbsDot(c.front().sp.n, w0) * std::abs(J[0][0] * J[1][1] - J[0][1] * J[1][0]);
}

TEST(ManifoldConstraints, GeneralizedGeometryTermMatchesFiniteDifferences) {
    for (const ChainConfig &cfg : AllConfigs()) {
        Float G = GeneralizedGeometryTerm(cfg.base);
        Float fd = FiniteDifferenceG(cfg);
        EXPECT_GT(G, 0) << cfg.name;
        EXPECT_NEAR(G, fd, 1e-5 * G) << cfg.name;
    }
}

TEST(ManifoldConstraints, GeneralizedGeometryTermMirrorIsUnfoldedSegment) {
    // A mirror unfolds the path into one straight segment of length r0 + r1.
    ChainConfig cfg = MirrorConfig();
    const ManifoldChain &c = cfg.base;
    Vec3 d0 = c.v[1].sp.p - c.v[0].sp.p, d1 = c.v[2].sp.p - c.v[1].sp.p;
    Float L = d0.length() + d1.length();
    Float expected = AbsDot(c.v[0].sp.n, Normalize(d0)) * AbsDot(c.v[2].sp.n, Normalize(d1)) / (L * L);
    EXPECT_NEAR(GeneralizedGeometryTerm(c), expected, 1e-12 * expected);
    // k = 0 reduces to the classical geometry term.
    ManifoldChain direct;
    ManifoldSurfacePoint pts[2] = {c.v[0].sp, c.v[2].sp};
    ASSERT_TRUE(MakeChain(pts, 2, nullptr, nullptr, &direct));
    Vec3 d = c.v[2].sp.p - c.v[0].sp.p;
    Float g = AbsDot(c.v[0].sp.n, Normalize(d)) * AbsDot(c.v[2].sp.n, Normalize(d)) / d.lengthSquared();
    EXPECT_NEAR(GeneralizedGeometryTerm(direct), g, 1e-12 * g);
}

TEST(ManifoldConstraints, RefractionWithUnitEtaRatioIsRejected) {
    ChainConfig cfg = SlabConfig();
    ManifoldChain c = cfg.base;
    c.v[1].sp.etaInterior = c.v[1].sp.etaExterior = 1.0;
    bool ok = true;
    ProjectedHalfVector(c, 1, &ok);
    EXPECT_FALSE(ok);
    Vec2 v;
    Mat2 a, b, d;
    EXPECT_FALSE(ConstraintDerivatives(c, 1, &v, &a, &b, &d));
}
