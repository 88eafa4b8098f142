// pbrt-v3's "nurbs" shape: a tensor-product (rational) B-spline surface,
// tessellated as pbrt-v3 does into a 30 x 30 vertex grid over [u0,u1] x [v0,v1]
// with uv = (u, v) and shading normals dP/du x dP/dv.
#pragma once
#include <vector>

#include "shapes/heightfield.h"  // MeshData

namespace gradus {

// Homogeneous control point (x, y, z, w): the point is (x/w, y/w, z/w) —
// pbrt-v3's "Pw" convention (coordinates already multiplied by the weight).
struct HPoint {
    double x = 0, y = 0, z = 0, w = 1;
};

struct NurbsSurface {
    int nu = 0, nv = 0, uorder = 0, vorder = 0;
    std::vector<double> uknots, vknots;  // nu + uorder and nv + vorder values
    std::vector<HPoint> cp;              // nu * nv, u varies fastest: cp[i + j * nu]
    // Surface point and partial derivatives at (u, v) in the valid parameter
    // range [uknots[uorder-1], uknots[nu]] x [vknots[vorder-1], vknots[nv]].
    Point3 eval(double u, double v, Vec3 *dPdu = nullptr, Vec3 *dPdv = nullptr) const;
};

// Values N[j] and first derivatives D[j] (j = 0..order-1) of the B-spline basis
// functions N_{span-order+1+j} of the given order at t; returns span, the
// knot interval [knots[span], knots[span+1]) that holds t (The NURBS Book,
// Piegl & Tiller 1997, A2.1-A2.3). Requires t in [knots[order-1], knots[n]].
int BSplineBasis(const std::vector<double> &knots, int order, int n, double t, double *N, double *D);

constexpr int kNurbsDice = 30;  // pbrt-v3's dicing rate in u and v

// Tessellation into (dice x dice) vertices, cells split as the heightfield's.
MeshData TessellateNurbs(const NurbsSurface &s, double u0, double u1, double v0, double v1, int dice = kNurbsDice);

// Reads pbrt-v3's parameters; counts, orders, knots, ranges and weights are
// checked with located errors.
MeshData CreateNurbs(const ParamSet &ps, const FileLoc &loc);

}  // namespace gradus
