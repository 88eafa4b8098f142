#include "shapes/nurbs.h"

#include <algorithm>
#include <cmath>

namespace gradus {

int BSplineBasis(const std::vector<double> &U, int order, int n, double t, double *N, double *D) {
    const int p = order - 1;
    // Span: the last non-empty interval [U[k], U[k+1]) with U[k] <= t, k in [p, n-1]
    // (t = U[n] belongs to the last non-empty span).
    int k = p;
    for (int i = p; i < n; ++i)
        if (U[i] <= t && U[i] < U[i + 1]) k = i;
    // Cox-de Boor triangle (Piegl & Tiller A2.2); Nm keeps degree p-1 for the derivatives.
    double left[32], right[32], Nm[32];
    N[0] = 1;
    for (int j = 1; j <= p; ++j) {
        if (j == p) std::copy(N, N + p, Nm);
        left[j] = t - U[k + 1 - j];
        right[j] = U[k + j] - t;
        double saved = 0;
        for (int r = 0; r < j; ++r) {
            const double tmp = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * tmp;
            saved = left[j - r] * tmp;
        }
        N[j] = saved;
    }
    if (p == 0) {
        D[0] = 0;
        return k;
    }
    // N'_{i,p} = p (N_{i,p-1} / (U[i+p] - U[i]) - N_{i+1,p-1} / (U[i+p+1] - U[i+1])), i = k-p+j
    // (Piegl & Tiller Eq. 2.9); Nm[r] is N_{k-p+1+r, p-1}; 0/0 terms are 0.
    for (int j = 0; j <= p; ++j) {
        const int i = k - p + j;
        double d = 0;
        if (j >= 1) {
            const double den = U[i + p] - U[i];
            if (den > 0) d += Nm[j - 1] / den;
        }
        if (j <= p - 1) {
            const double den = U[i + p + 1] - U[i + 1];
            if (den > 0) d -= Nm[j] / den;
        }
        D[j] = p * d;
    }
    return k;
}

Point3 NurbsSurface::eval(double u, double v, Vec3 *dPdu, Vec3 *dPdv) const {
    double Nu[32], Du[32], Nv[32], Dv[32];
    const int ku = BSplineBasis(uknots, uorder, nu, u, Nu, Du);
    const int kv = BSplineBasis(vknots, vorder, nv, v, Nv, Dv);
    // Homogeneous sums A, A_u, A_v; the point is A.xyz / A.w and by the
    // quotient rule S_u = (A_u.xyz - A_u.w S) / A.w (Piegl & Tiller Eq. 4.8).
    double A[4] = {0, 0, 0, 0}, Au[4] = {0, 0, 0, 0}, Av[4] = {0, 0, 0, 0};
    for (int b = 0; b < vorder; ++b) {
        const int j = kv - vorder + 1 + b;
        for (int a = 0; a < uorder; ++a) {
            const int i = ku - uorder + 1 + a;
            const HPoint &c = cp[i + size_t(j) * nu];
            const double q[4] = {c.x, c.y, c.z, c.w};
            const double w = Nu[a] * Nv[b], wu = Du[a] * Nv[b], wv = Nu[a] * Dv[b];
            for (int m = 0; m < 4; ++m) {
                A[m] += w * q[m];
                Au[m] += wu * q[m];
                Av[m] += wv * q[m];
            }
        }
    }
    const double S[3] = {A[0] / A[3], A[1] / A[3], A[2] / A[3]};
    if (dPdu)
        *dPdu = Vec3((Au[0] - Au[3] * S[0]) / A[3], (Au[1] - Au[3] * S[1]) / A[3], (Au[2] - Au[3] * S[2]) / A[3]);
    if (dPdv)
        *dPdv = Vec3((Av[0] - Av[3] * S[0]) / A[3], (Av[1] - Av[3] * S[1]) / A[3], (Av[2] - Av[3] * S[2]) / A[3]);
    return Point3(S[0], S[1], S[2]);
}

MeshData TessellateNurbs(const NurbsSurface &s, double u0, double u1, double v0, double v1, int dice) {
    MeshData m;
    const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
    bool normalsOk = true;
    for (int y = 0; y < dice; ++y)
        for (int x = 0; x < dice; ++x) {
            const double u = u0 + (u1 - u0) * x / (dice - 1), v = v0 + (v1 - v0) * y / (dice - 1);
            Vec3 du, dv;
            m.P.push_back(s.eval(u, v, &du, &dv));
            m.uv.push_back(Point2(u, v));
            Vec3 n = Cross(du, dv);
            // Degenerate derivatives (a pole, a collapsed edge): take the normal
            // a little way towards the middle of the patch.
            for (double f = 1e-4; !(n.lengthSquared() > 0) && f < 0.2; f *= 10) {
                s.eval(u + f * (uc - u), v + f * (vc - v), &du, &dv);
                n = Cross(du, dv);
            }
            if (n.lengthSquared() > 0 && std::isfinite(n.lengthSquared())) m.N.push_back(Normal3(Normalize(n)));
            else normalsOk = false;
        }
    if (!normalsOk) m.N.clear();  // geometric normals only
    for (int y = 0; y + 1 < dice; ++y)
        for (int x = 0; x + 1 < dice; ++x) {
            const int a = x + y * dice, b = a + 1, c = a + 1 + dice, d = a + dice;
            for (int i : {a, b, c, a, c, d}) m.indices.push_back(i);
        }
    return m;
}

namespace {
std::vector<double> Knots(const ParamSet &ps, const FileLoc &loc, const char *name, int n, int order) {
    std::vector<Float> k = ps.getFloats(name);
    const FileLoc at = ps.locOf(name, loc);
    if (k.size() != size_t(n) + order)
        throw Error(at, std::string("nurbs: \"float ") + name + "\" has " + std::to_string(k.size()) +
                            " values, n + order = " + std::to_string(n + order) + " needed");
    for (size_t i = 0; i < k.size(); ++i) {
        if (!std::isfinite(k[i])) throw Error(at, std::string("nurbs: \"") + name + "\" value is not finite");
        if (i > 0 && k[i] < k[i - 1])
            throw Error(at, std::string("nurbs: \"") + name + "\" must be non-decreasing (value " +
                                std::to_string(i) + " is smaller than the one before)");
    }
    if (!(k[order - 1] < k[n]))
        throw Error(at, std::string("nurbs: \"") + name + "\" spans an empty parameter range");
    return std::vector<double>(k.begin(), k.end());
}
}  // namespace

MeshData CreateNurbs(const ParamSet &ps, const FileLoc &loc) {
    NurbsSurface s;
    s.nu = ps.getInt("nu", -1), s.nv = ps.getInt("nv", -1);
    s.uorder = ps.getInt("uorder", -1), s.vorder = ps.getInt("vorder", -1);
    constexpr int kMaxOrder = 31;  // fixed-size basis arrays
    for (auto [name, val] : {std::pair<const char *, int>{"uorder", s.uorder}, {"vorder", s.vorder}})
        if (val < 2 || val > kMaxOrder)
            throw Error(ps.locOf(name, loc), std::string("nurbs: \"integer ") + name + "\" must be given, in [2, 31]");
    if (s.nu < s.uorder)
        throw Error(ps.locOf("nu", loc), "nurbs: \"integer nu\" must be given and >= uorder");
    if (s.nv < s.vorder)
        throw Error(ps.locOf("nv", loc), "nurbs: \"integer nv\" must be given and >= vorder");
    if ((long long)s.nu * s.nv > 100000000LL) throw Error(ps.locOf("nu", loc), "nurbs: nu * nv is too large");
    s.uknots = Knots(ps, loc, "uknots", s.nu, s.uorder);
    s.vknots = Knots(ps, loc, "vknots", s.nv, s.vorder);
    // pbrt-v3: the range defaults to the whole valid domain and may not leave it.
    auto range = [&](const char *n0, const char *n1, const std::vector<double> &k, int n, int order, double *a,
                     double *b) {
        const double lo = k[order - 1], hi = k[n];
        *a = ps.getFloat(n0, Float(lo));
        *b = ps.getFloat(n1, Float(hi));
        // The defaults went through Float: snap them back onto the knots.
        if (!ps.has(n0)) *a = lo;
        if (!ps.has(n1)) *b = hi;
        for (auto [nm, val] : {std::pair<const char *, double>{n0, *a}, {n1, *b}})
            if (!(val >= lo && val <= hi))
                throw Error(ps.locOf(nm, loc), std::string("nurbs: \"float ") + nm + "\" must lie in [" +
                                                   std::to_string(lo) + ", " + std::to_string(hi) +
                                                   "] (knots[order-1], knots[n])");
        if (*a == *b) throw Error(ps.locOf(n1, loc), std::string("nurbs: \"") + n0 + "\" equals \"" + n1 + "\"");
    };
    double u0, u1, v0, v1;
    range("u0", "u1", s.uknots, s.nu, s.uorder, &u0, &u1);
    range("v0", "v1", s.vknots, s.nv, s.vorder, &v0, &v1);
    const size_t count = size_t(s.nu) * s.nv;
    if (ps.has("P")) {
        if (ps.has("Pw")) throw Error(ps.locOf("Pw", loc), "nurbs: give \"point P\" or \"float Pw\", not both");
        std::vector<Point3> P = ps.getPoint3s("P");
        if (P.size() != count)
            throw Error(ps.locOf("P", loc), "nurbs: \"point P\" has " + std::to_string(P.size()) +
                                                " points, nu * nv = " + std::to_string(count) + " needed");
        for (const Point3 &p : P) {
            if (!p.isFinite()) throw Error(ps.locOf("P", loc), "nurbs: \"P\" holds a non-finite value");
            s.cp.push_back(HPoint{p.x, p.y, p.z, 1});
        }
    } else if (ps.has("Pw")) {
        std::vector<Float> Pw = ps.getFloats("Pw");
        if (Pw.size() != 4 * count)
            throw Error(ps.locOf("Pw", loc), "nurbs: \"float Pw\" has " + std::to_string(Pw.size()) +
                                                 " values, 4 * nu * nv = " + std::to_string(4 * count) + " needed");
        for (size_t i = 0; i < count; ++i) {
            HPoint h{Pw[4 * i], Pw[4 * i + 1], Pw[4 * i + 2], Pw[4 * i + 3]};
            if (!(std::isfinite(h.x) && std::isfinite(h.y) && std::isfinite(h.z) && std::isfinite(h.w)))
                throw Error(ps.locOf("Pw", loc), "nurbs: \"Pw\" holds a non-finite value");
            if (!(h.w > 0))
                throw Error(ps.locOf("Pw", loc), "nurbs: \"Pw\" weight " + std::to_string(i) + " must be > 0");
            s.cp.push_back(h);
        }
    } else {
        throw Error(loc, "nurbs: missing control points (\"point P\" or \"float Pw\")");
    }
    return TessellateNurbs(s, u0, u1, v0, v1);
}

}  // namespace gradus
