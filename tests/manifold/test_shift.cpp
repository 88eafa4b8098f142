// G-MLT shift Jacobian (Eqs. 12-15) against a finite-difference Jacobian of the
// whole shift: camera -> glossy x1 -> diffuse x_b -> glossy x3 -> diffuse x_c.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "configs.h"

using namespace gradus;
using namespace gradus::testing;

namespace {

struct ShiftScene {
    AnalyticScene scene;
    int glossy, wall, ceiling;
    ManifoldSurfacePoint camera;  // normal = camera axis
    Vec3 cu, cv;                  // image-plane axes
    ShiftScene() {
        glossy = scene.addPlane({0, 0, 0}, {0, 0, 1});
        wall = scene.addPlane({3, 0, 0}, {-1, 0, 0});
        ceiling = scene.addPlane({0, 0, 4}, {0, 0, -1});
        camera = FreePoint({0, 0, 3}, Normalize(Vec3(0.4, 0.1, -1)));
        CoordinateSystem(camera.n, &cu, &cv);
    }
};

// Base path x1..x3 (x0 = camera, x4 fixed). Shift: image-plane coordinate + delta,
// re-trace the eye chain keeping o1, walk the second chain keeping o3 to x4.
bool Shift(const ShiftScene &S, const ManifoldSurfacePoint x[5], const Vec2 &delta,
           ManifoldChain *eyeOut, ManifoldChain *secondOut, const ManifoldChain *eyeRef = nullptr,
           const ManifoldChain *secondRef = nullptr) {
    bool refl[1] = {true}, spec[1] = {false};
    ManifoldChain eye, second;
    ManifoldSurfacePoint e3[3] = {x[0], x[1], x[2]}, s3[3] = {x[2], x[3], x[4]};
    if (!MakeChain(e3, 3, refl, spec, &eye) || !MakeChain(s3, 3, refl, spec, &second)) return false;
    // Keep one frame field for all FD evaluations.
    auto refit = [](ManifoldChain *c, const ManifoldChain *ref) {
        if (!ref) return;
        for (int i = 0; i < c->size; ++i) SetupManifoldVertex(&c->v[i], c->v[i].sp, &ref->v[i].frameRef);
        for (int i = 1; i < c->size - 1; ++i) c->v[i].o = ProjectedHalfVector(*c, i);
    };
    refit(&eye, eyeRef);
    refit(&second, secondRef);
    Vec3 d = x[1].p - x[0].p;
    Float dz = Dot(d, S.camera.n);
    Vec2 s(Dot(d, S.cu) / dz + delta.x, Dot(d, S.cv) / dz + delta.y);
    Vec3 dir = Normalize(S.camera.n + S.cu * s.x + S.cv * s.y);
    if (TraceChain(S.scene, x[0], dir, eye, eyeOut) != ManifoldStatus::Success) return false;
    ManifoldWalkOptions o;
    o.relativeTolerance = 1e-14;
    o.maxIterations = 60;
    ManifoldWalkResult r = ManifoldWalk(S.scene, second, eyeOut->back().sp, x[4], o);
    if (!r.ok() && r.relativeError > 1e-12) return false;
    *secondOut = r.chain;
    return true;
}

}  // namespace

TEST(ManifoldShift, JacobianMatchesFiniteDifferences) {
    ShiftScene S;
    ManifoldSurfacePoint x[5] = {S.camera, S.scene.pointOn(S.glossy, {1.0, 0.2, 0}),
                                 S.scene.pointOn(S.wall, {3, 0.5, 1.2}),
                                 S.scene.pointOn(S.glossy, {1.8, 1.2, 0}),
                                 S.scene.pointOn(S.ceiling, {0.5, 2.5, 4})};
    const Vec2 delta(0.02, -0.015);
    ManifoldChain eyeBase, secondBase, eyeOff, secondOff;
    ASSERT_TRUE(Shift(S, x, Vec2(0, 0), &eyeBase, &secondBase));
    // The zero shift reproduces the base path.
    EXPECT_LT(Distance(eyeBase.v[1].sp.p, x[1].p), 1e-9);
    EXPECT_LT(Distance(secondBase.v[1].sp.p, x[3].p), 1e-9);
    ASSERT_TRUE(Shift(S, x, delta, &eyeOff, &secondOff));
    Float jac = ShiftJacobianFactor(eyeOff, &secondOff) / ShiftJacobianFactor(eyeBase, &secondBase);

    // Finite differences of (x~1, x~2, x~3) with respect to (x1, x2, x3), each in
    // its tangent frame.
    const Float h = 1e-6;
    Eigen::Matrix<double, 6, 6> J;
    const ManifoldVertex *outV[3] = {&eyeOff.v[1], &eyeOff.v[2], &secondOff.v[1]};
    const ManifoldVertex *inV[3] = {&eyeBase.v[1], &eyeBase.v[2], &secondBase.v[1]};
    for (int j = 0; j < 3; ++j)
        for (int axis = 0; axis < 2; ++axis) {
            Vec3 e = axis == 0 ? inV[j]->s : inV[j]->t;
            Point3 out[2][3];
            for (int sgn = 0; sgn < 2; ++sgn) {
                ManifoldSurfacePoint y[5] = {x[0], x[1], x[2], x[3], x[4]};
                y[j + 1] = S.scene.moveOn(x[j + 1], e * (sgn ? -h : h));
                ManifoldChain eo, so;
                ASSERT_TRUE(Shift(S, y, delta, &eo, &so, &eyeBase, &secondBase));
                out[sgn][0] = eo.v[1].sp.p;
                out[sgn][1] = eo.v[2].sp.p;
                out[sgn][2] = so.v[1].sp.p;
            }
            for (int i = 0; i < 3; ++i) {
                Vec3 d = (out[0][i] - out[1][i]) / (2 * h);
                J(2 * i, 2 * j + axis) = Dot(d, outV[i]->s);
                J(2 * i + 1, 2 * j + axis) = Dot(d, outV[i]->t);
            }
        }
    Float fd = std::abs(J.determinant());
    EXPECT_GT(std::abs(jac - 1), 1e-3) << "shift too small to test anything";
    EXPECT_NEAR(jac, fd, 1e-5 * fd);
}
