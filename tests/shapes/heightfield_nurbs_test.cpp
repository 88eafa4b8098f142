// heightfield and nurbs: the grid and its triangulation against the input
// heights, exact (rational) B-spline evaluation against closed forms (a
// bilinear patch, a quarter circle), derivatives against finite differences,
// the scene builder's hits and located errors.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "samplers/rng.h"
#include "shapes/heightfield.h"
#include "shapes/nurbs.h"

namespace gradus {
namespace {

std::unique_ptr<Scene> Build(const std::string &world) {
    std::string text = "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" + world + "\nWorldEnd\n";
    return BuildScene(ParseString(text, "test.pbrt"), Point2i{8, 8});
}

// The error's message must name line 4 (the Shape directive) of test.pbrt and contain `what`.
void ExpectLocatedError(const std::string &world, const std::string &what) {
    try {
        Build(world);
        ADD_FAILURE() << "no error for: " << world;
    } catch (const Error &e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("test.pbrt:4:"), std::string::npos) << msg;
        EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
}

std::string Floats(const std::vector<double> &v) {
    std::string s = "[";
    for (double x : v) s += " " + std::to_string(x);
    return s + " ]";
}

TEST(Heightfield, GridVerticesUvAndTriangulation) {
    const int nu = 4, nv = 3;
    std::vector<Float> Pz(nu * nv);
    for (int i = 0; i < nu * nv; ++i) Pz[i] = 0.1 * i * i - 0.3;
    MeshData m = HeightfieldMesh(nu, nv, Pz);
    ASSERT_EQ(m.P.size(), size_t(nu * nv));
    ASSERT_EQ(m.indices.size(), size_t(6 * (nu - 1) * (nv - 1)));
    EXPECT_TRUE(m.N.empty());
    for (int y = 0; y < nv; ++y)
        for (int x = 0; x < nu; ++x) {
            const int i = x + y * nu;
            EXPECT_DOUBLE_EQ(m.P[i].x, double(x) / (nu - 1));
            EXPECT_DOUBLE_EQ(m.P[i].y, double(y) / (nv - 1));
            EXPECT_DOUBLE_EQ(m.P[i].z, Pz[i]);
            EXPECT_EQ(m.uv[i], Point2(m.P[i].x, m.P[i].y));
        }
    // Every cell is split along its (x,y)-(x+1,y+1) diagonal into two triangles
    // that cover it: their xy areas sum to the cell's, both wound counter-clockwise.
    // pbrt-v3's split: (x,y)(x+1,y)(x+1,y+1) then (x,y)(x+1,y+1)(x,y+1), cells in row order.
    for (int y = 0, c = 0; y + 1 < nv; ++y)
        for (int x = 0; x + 1 < nu; ++x, ++c) {
            const int v00 = x + y * nu, v10 = v00 + 1, v11 = v00 + 1 + nu, v01 = v00 + nu;
            const std::vector<int> want = {v00, v10, v11, v00, v11, v01};
            EXPECT_EQ(std::vector<int>(m.indices.begin() + 6 * c, m.indices.begin() + 6 * c + 6), want) << c;
        }
    const double cell = 1.0 / ((nu - 1) * (nv - 1));
    for (size_t t = 0; t < m.indices.size() / 3; ++t) {
        const Point3 &a = m.P[m.indices[3 * t]], &b = m.P[m.indices[3 * t + 1]], &c = m.P[m.indices[3 * t + 2]];
        const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        EXPECT_NEAR(area2, cell, 1e-12) << t;
    }
}

TEST(Heightfield, PlaneHeightsGiveHitsAndNormalsOfThePlane) {
    // Pz = 0.2 + 0.3 x - 0.5 y is a plane: every hit lies on it, with its normal.
    const int nu = 5, nv = 7;
    std::vector<double> Pz;
    for (int y = 0; y < nv; ++y)
        for (int x = 0; x < nu; ++x) Pz.push_back(0.2 + 0.3 * x / (nu - 1) - 0.5 * y / (nv - 1));
    auto s = Build("Shape \"heightfield\" \"integer nu\" 5 \"integer nv\" 7 \"float Pz\" " + Floats(Pz));
    const Vec3 nPlane = Normalize(Vec3(-0.3, 0.5, 1));
    RNG rng(7);
    for (int k = 0; k < 200; ++k) {
        const double x = 0.01 + 0.98 * rng.uniform(), y = 0.01 + 0.98 * rng.uniform();
        SurfaceInteraction si;
        ASSERT_TRUE(s->intersect(Ray(Point3(x, y, 3), Vec3(0, 0, -1)), &si)) << x << " " << y;
        EXPECT_NEAR(si.p.z, 0.2 + 0.3 * x - 0.5 * y, 1e-5);
        EXPECT_NEAR(si.uv.x, x, 1e-5);
        EXPECT_NEAR(si.uv.y, y, 1e-5);
        EXPECT_NEAR(std::abs(Dot(Vec3(si.n), nPlane)), 1, 1e-6);
    }
}

TEST(Heightfield, LocatedErrors) {
    ExpectLocatedError("Shape \"heightfield\" \"integer nu\" 2 \"integer nv\" 2 \"float Pz\" [0 0 0]", "nu * nv");
    ExpectLocatedError("Shape \"heightfield\" \"integer nu\" 1 \"integer nv\" 2 \"float Pz\" [0 0]", "nu");
    ExpectLocatedError("Shape \"heightfield\" \"integer nu\" 2 \"float Pz\" [0 0 0 0]", "nv");
    ExpectLocatedError("Shape \"heightfield\" \"integer nu\" 2 \"integer nv\" 2 \"float Pz\" [0 0 0 0] \"float pz\" 1",
                       "pz");
}

// A B-spline basis sums to 1 and its derivatives to 0 (partition of unity),
// and each derivative matches a central difference.
TEST(Nurbs, BasisPartitionOfUnityAndDerivatives) {
    const std::vector<double> U = {0, 0, 0, 0, 0.2, 0.5, 0.5, 0.9, 1, 1, 1, 1};
    const int order = 4, n = int(U.size()) - order;
    RNG rng(3);
    for (int k = 0; k < 500; ++k) {
        const double t = 0.001 + 0.998 * rng.uniform();
        double N[4], D[4];
        const int span = BSplineBasis(U, order, n, t, N, D);
        EXPECT_LE(U[span], t);
        EXPECT_LT(t, U[span + 1]);
        double sn = 0, sd = 0;
        for (int j = 0; j < order; ++j) sn += N[j], sd += D[j];
        EXPECT_NEAR(sn, 1, 1e-12);
        EXPECT_NEAR(sd, 0, 1e-9);
        // Finite difference of each basis function (same span on both sides, away from knots).
        const double h = 1e-6;
        double Np[4], Nm[4], Dd[4];
        if (BSplineBasis(U, order, n, t + h, Np, Dd) != span || BSplineBasis(U, order, n, t - h, Nm, Dd) != span)
            continue;
        for (int j = 0; j < order; ++j) EXPECT_NEAR(D[j], (Np[j] - Nm[j]) / (2 * h), 1e-5) << t << " " << j;
    }
}

TEST(Nurbs, BilinearPatchIsExact) {
    NurbsSurface s;
    s.nu = s.nv = 2, s.uorder = s.vorder = 2;
    s.uknots = {0, 0, 1, 1}, s.vknots = {-1, -1, 3, 3};
    const Point3 c[4] = {Point3(0, 0, 0), Point3(2, 0, 1), Point3(0, 1, -1), Point3(3, 2, 2)};
    for (const Point3 &p : c) s.cp.push_back(HPoint{p.x, p.y, p.z, 1});
    RNG rng(11);
    for (int k = 0; k < 100; ++k) {
        const double a = rng.uniform(), b = rng.uniform(), v = -1 + 4 * b;
        Vec3 du, dv;
        const Point3 p = s.eval(a, v, &du, &dv);
        for (int i = 0; i < 3; ++i) {
            const double want = (1 - a) * (1 - b) * c[0][i] + a * (1 - b) * c[1][i] + (1 - a) * b * c[2][i] +
                                a * b * c[3][i];
            EXPECT_NEAR(p[i], want, 1e-12);
            EXPECT_NEAR(du[i], (1 - b) * (c[1][i] - c[0][i]) + b * (c[3][i] - c[2][i]), 1e-12);
            EXPECT_NEAR(dv[i], ((1 - a) * (c[2][i] - c[0][i]) + a * (c[3][i] - c[1][i])) / 4, 1e-12);
        }
    }
}

// Quarter of the unit circle (rational quadratic, middle weight sqrt(2)/2)
// extruded along z: the exact circle, with the closed-form parameterisation
// x = ((1-u)^2 + s 2u(1-u)) / w, y = (s 2u(1-u) + u^2) / w, w = (1-u)^2 + 2 s u(1-u) + u^2, s = sqrt(2)/2.
NurbsSurface QuarterCylinder() {
    const double s = std::sqrt(0.5);
    NurbsSurface q;
    q.nu = 3, q.uorder = 3, q.nv = 2, q.vorder = 2;
    q.uknots = {0, 0, 0, 1, 1, 1}, q.vknots = {0, 0, 1, 1};
    for (double z : {0.0, 1.0}) {
        q.cp.push_back(HPoint{1, 0, z, 1});
        q.cp.push_back(HPoint{s, s, z * s, s});
        q.cp.push_back(HPoint{0, 1, z, 1});
    }
    return q;
}

TEST(Nurbs, RationalQuarterCircleIsExact) {
    const NurbsSurface q = QuarterCylinder();
    const double s = std::sqrt(0.5);
    for (int k = 0; k <= 100; ++k) {
        const double u = k / 100.0, v = 0.37;
        Vec3 du, dv;
        const Point3 p = q.eval(u, v, &du, &dv);
        const double w = (1 - u) * (1 - u) + 2 * s * u * (1 - u) + u * u;
        EXPECT_NEAR(p.x, ((1 - u) * (1 - u) + 2 * s * u * (1 - u)) / w, 1e-12);
        EXPECT_NEAR(p.y, (2 * s * u * (1 - u) + u * u) / w, 1e-12);
        EXPECT_NEAR(p.x * p.x + p.y * p.y, 1, 1e-12);
        EXPECT_NEAR(p.z, v, 1e-12);
        // Tangent of a circle is perpendicular to the radius; dP/dv is the axis.
        EXPECT_NEAR(du.x * p.x + du.y * p.y, 0, 1e-12);
        EXPECT_NEAR(du.z, 0, 1e-12);
        EXPECT_NEAR(dv.x, 0, 1e-12);
        EXPECT_NEAR(dv.y, 0, 1e-12);
        EXPECT_NEAR(dv.z, 1, 1e-12);
        // dP/du against a central difference of the exact evaluation.
        if (k > 0 && k < 100) {
            const double h = 1e-6;
            const Point3 a = q.eval(u + h, v), b = q.eval(u - h, v);
            for (int i = 0; i < 3; ++i) EXPECT_NEAR(du[i], (a[i] - b[i]) / (2 * h), 1e-6);
        }
    }
    // u = 1/2 is the 45-degree point by symmetry.
    const Point3 mid = q.eval(0.5, 0);
    EXPECT_NEAR(mid.x, s, 1e-12);
    EXPECT_NEAR(mid.y, s, 1e-12);
}

TEST(Nurbs, TessellationAt30x30WithOutwardNormals) {
    const NurbsSurface q = QuarterCylinder();
    MeshData m = TessellateNurbs(q, 0, 1, 0, 1);
    ASSERT_EQ(m.P.size(), size_t(kNurbsDice * kNurbsDice));
    ASSERT_EQ(m.N.size(), m.P.size());
    ASSERT_EQ(m.indices.size(), size_t(6 * (kNurbsDice - 1) * (kNurbsDice - 1)));
    for (size_t i = 0; i < m.P.size(); ++i) {
        const int x = int(i % kNurbsDice), y = int(i / kNurbsDice);
        EXPECT_DOUBLE_EQ(m.uv[i].x, double(x) / (kNurbsDice - 1));
        EXPECT_DOUBLE_EQ(m.uv[i].y, double(y) / (kNurbsDice - 1));
        EXPECT_NEAR(m.P[i].x * m.P[i].x + m.P[i].y * m.P[i].y, 1, 1e-12);
        // dP/du x dP/dv points along the outward radius for this orientation.
        EXPECT_NEAR(m.N[i].x, m.P[i].x, 1e-9);
        EXPECT_NEAR(m.N[i].y, m.P[i].y, 1e-9);
        EXPECT_NEAR(m.N[i].z, 0, 1e-9);
    }
}

// The same cylinder through the scene file (Pw), hit from the axis: every
// hit lies on the tessellated circle, within the chord error of 30 vertices.
TEST(Nurbs, SceneFileQuarterCylinder) {
    const double s = std::sqrt(0.5);
    const std::string pw = Floats({1, 0, 0, 1, s, s, 0, s, 0, 1, 0, 1, 1, 0, 1, 1, s, s, s, s, 0, 1, 1, 1});
    auto sc = Build("Shape \"nurbs\" \"integer nu\" 3 \"integer nv\" 2 \"integer uorder\" 3 \"integer vorder\" 2 "
                    "\"float uknots\" [0 0 0 1 1 1] \"float vknots\" [0 0 1 1] \"float Pw\" " + pw);
    // Chord sagitta bound: 1 - cos(dphi/2) for the widest angular step of the
    // 30 (non-uniform in angle) vertices of the rational parameterisation.
    const NurbsSurface q = QuarterCylinder();
    double maxStep = 0;
    for (int i = 0; i + 1 < kNurbsDice; ++i) {
        const Point3 a = q.eval(double(i) / (kNurbsDice - 1), 0), b = q.eval(double(i + 1) / (kNurbsDice - 1), 0);
        maxStep = std::max(maxStep, std::atan2(b.y, b.x) - std::atan2(a.y, a.x));
    }
    EXPECT_LT(maxStep, 1.2 * (M_PI / 2) / (kNurbsDice - 1));
    const double sag = 1 - std::cos(0.5 * maxStep);
    for (int k = 1; k < 50; ++k) {
        const double phi = (M_PI / 2) * k / 50;
        SurfaceInteraction si;
        ASSERT_TRUE(sc->intersect(Ray(Point3(0, 0, 0.5), Vec3(std::cos(phi), std::sin(phi), 0)), &si));
        const double r = std::hypot(si.p.x, si.p.y);
        EXPECT_LE(r, 1 + 1e-5);
        EXPECT_GE(r, 1 - sag - 1e-5);
        EXPECT_NEAR(si.shading.n.z, 0, 1e-5);
        EXPECT_NEAR(std::abs(si.shading.n.x * std::cos(phi) + si.shading.n.y * std::sin(phi)), 1, 2e-3);
    }
}

const char *kPatchHead = "Shape \"nurbs\" \"integer nu\" 2 \"integer nv\" 2 ";
const char *kPatchP = " \"point P\" [0 0 0 1 0 0 0 1 0 1 1 0]";
std::string Patch(const std::string &mid, const std::string &p = kPatchP) { return kPatchHead + mid + p; }

TEST(Nurbs, LocatedErrors) {
    const std::string orders = "\"integer uorder\" 2 \"integer vorder\" 2 ";
    const std::string knots = "\"float uknots\" [0 0 1 1] \"float vknots\" [0 0 1 1]";
    // The valid patch builds.
    EXPECT_NO_THROW(Build(Patch(orders + knots)));
    ExpectLocatedError(Patch(orders + "\"float uknots\" [0 0 1] \"float vknots\" [0 0 1 1]"), "n + order");
    ExpectLocatedError(Patch("\"integer uorder\" 1 \"integer vorder\" 2 \"float uknots\" [0 1 2] " 
                             "\"float vknots\" [0 0 1 1]"), "uorder");
    ExpectLocatedError(Patch(orders + "\"float uknots\" [0 1 0.5 1] \"float vknots\" [0 0 1 1]"), "non-decreasing");
    ExpectLocatedError(Patch(orders + knots, " \"point P\" [0 0 0 1 0 0 0 1 0]"), "nu * nv");
    ExpectLocatedError(Patch(orders + knots, " \"float Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0 0]"), "weight");
    ExpectLocatedError(Patch(orders + knots, " \"float Pw\" [0 0 0 1 1 0 0 1 0 1 0 1 1 1 0]"), "4 * nu * nv");
    ExpectLocatedError(Patch(orders + knots + " \"float u1\" 1.5"), "u1");
    ExpectLocatedError(Patch(orders + knots, ""), "control points");
    ExpectLocatedError(Patch(orders + knots + " \"float uu0\" 0"), "uu0");
}

}  // namespace
}  // namespace gradus
