// Half-vector constraints, their analytic derivatives and the quantities built on
// them (JM12 Sec. 4; G-MLT Sec. 5.2).
#include <Eigen/Dense>

#include "integrators/manifold/manifold.h"

namespace gradus {

namespace {

// Tangent frame from the normal and a reference axis: s = normalize(a - n (n.a)).
bool FrameFromRef(const Vec3 &n, const Vec3 &a, Vec3 *s, Vec3 *t) {
    Vec3 u = a - n * Dot(n, a);
    Float l = u.length();
    if (!(l > 1e-12 * std::max<Float>(1, a.length()))) return false;
    *s = u / l;
    *t = Cross(n, *s);
    return true;
}

// Derivative of (s, t) when n changes by dn (frame defined by FrameFromRef).
void FrameDerivative(const Vec3 &n, const Vec3 &a, const Vec3 &s, const Vec3 &dn, Vec3 *ds,
                     Vec3 *dt) {
    Vec3 u = a - n * Dot(n, a);
    Float l = u.length();
    Vec3 du = -(dn * Dot(n, a) + n * Dot(dn, a));
    *ds = (du - s * Dot(s, du)) / l;
    *dt = Cross(dn, s) + Cross(n, *ds);
}

inline Vec3 ProjectPerp(const Vec3 &w, const Vec3 &e) { return e - w * Dot(w, e); }

struct HalfVector {
    Vec3 H;        // oriented, unit
    Float sigma;   // orientation sign applied to normalize(h)
    Float len;     // |h|
    Vec3 wi, wo;   // unit directions to previous / next vertex
    Float li, lo;  // distances
    Float etaA, etaB;
};

bool ComputeHalfVector(const ManifoldChain &c, int i, HalfVector *hv) {
    const ManifoldVertex &cur = c.v[i];
    Vec3 wi = c.v[i - 1].sp.p - cur.sp.p, wo = c.v[i + 1].sp.p - cur.sp.p;
    hv->li = wi.length();
    hv->lo = wo.length();
    if (!(hv->li > 0) || !(hv->lo > 0)) return false;
    wi = wi / hv->li;
    wo = wo / hv->lo;
    const Vec3 &n = cur.sp.n;
    bool inFront = Dot(wi, n) > 0, outFront = Dot(wo, n) > 0;
    if (cur.reflect) {
        if (inFront != outFront) return false;
        hv->etaA = hv->etaB = 1;
    } else {
        if (inFront == outFront) return false;
        hv->etaA = inFront ? cur.sp.etaExterior : cur.sp.etaInterior;
        hv->etaB = outFront ? cur.sp.etaExterior : cur.sp.etaInterior;
        if (hv->etaA == hv->etaB) return false;  // eta ratio 1: no half-vector
    }
    Vec3 h = wi * hv->etaA + wo * hv->etaB;
    hv->len = h.length();
    if (!(hv->len > 1e-12)) return false;
    hv->H = h / hv->len;
    hv->sigma = 1;
    if (Dot(hv->H, n) < 0) {
        hv->H = -hv->H;
        hv->sigma = -1;
    }
    hv->wi = wi;
    hv->wo = wo;
    return true;
}

// Block Thomas solve of A X = R (A block-tridiagonal over the k interior
// vertices, R with 2 columns per block). Returns det(A) through *det.
// Blocks are indexed 0..k-1 (chain vertex i+1).
struct Tridiag {
    std::array<Mat2, kMaxManifoldVertices> L, D, U;
    int k = 0;
    Mat2 Uend;  // dc_k / dx_{k+1}
};

bool AssembleTridiag(const ManifoldChain &c, Tridiag *T) {
    T->k = c.interiorCount();
    for (int j = 0; j < T->k; ++j) {
        Vec2 val;
        if (!ConstraintDerivatives(c, j + 1, &val, &T->L[j], &T->D[j], &T->U[j])) return false;
    }
    if (T->k > 0) T->Uend = T->U[T->k - 1];
    return true;
}

// Solve in place. R: k blocks (input), X: k blocks (output). Returns false if a
// pivot block is singular.
bool SolveTridiag(const Tridiag &T, const Mat2 *R, Mat2 *X, Float *det) {
    std::array<Mat2, kMaxManifoldVertices> Dp, Rp;
    Float d = 1;
    for (int j = 0; j < T.k; ++j) {
        if (j == 0) {
            Dp[0] = T.D[0];
            if (R) Rp[0] = R[0];
        } else {
            Mat2 m = T.L[j] * Dp[j - 1].inverse();
            Dp[j] = T.D[j] - m * T.U[j - 1];
            if (R) Rp[j] = R[j] - m * Rp[j - 1];
        }
        Float dj = Dp[j].det(), scale = Dp[j].maxAbs();
        if (!(std::abs(dj) > 1e-14 * scale * scale) || !std::isfinite(dj)) return false;
        d *= dj;
    }
    if (det) *det = d;
    if (X && R) {
        for (int j = T.k - 1; j >= 0; --j) {
            Mat2 rhs = Rp[j];
            if (j + 1 < T.k) rhs = rhs - T.U[j] * X[j + 1];
            X[j] = Dp[j].inverse() * rhs;
        }
    }
    return true;
}

}  // namespace

void SetupManifoldVertex(ManifoldVertex *v, const ManifoldSurfacePoint &sp, const Vec3 *frameRef) {
    v->sp = sp;
    v->frameRef = frameRef ? *frameRef : sp.dpdu;
    if (!FrameFromRef(sp.n, v->frameRef, &v->s, &v->t)) {
        // Reference parallel to n (or unusable): fall back to the branchless basis.
        CoordinateSystem(sp.n, &v->s, &v->t);
        v->frameRef = v->s;
    }
    // Motion axes: s projected onto the geometric tangent plane (ng on n's side,
    // so (ps, pt) has the handedness of (s, t)). Equal to (s, t) where ng = n.
    Vec3 ng = GeometricNormal(sp);
    if (!(ng.lengthSquared() > 0) || !FrameFromRef(ng, v->s, &v->ps, &v->pt)) {
        v->ps = v->s;
        v->pt = v->t;
    }
    // Normal derivatives along ps and pt (in the span of dpdu, dpdv): write
    // e = alpha dpdu + beta dpdv.
    Float a11 = Dot(sp.dpdu, sp.dpdu), a12 = Dot(sp.dpdu, sp.dpdv), a22 = Dot(sp.dpdv, sp.dpdv);
    Float det = a11 * a22 - a12 * a12;
    auto along = [&](const Vec3 &e) {
        if (!(std::abs(det) > 0)) return Vec3(0, 0, 0);
        Float b1 = Dot(sp.dpdu, e), b2 = Dot(sp.dpdv, e);
        Float alpha = (a22 * b1 - a12 * b2) / det, beta = (a11 * b2 - a12 * b1) / det;
        return sp.dndu * alpha + sp.dndv * beta;
    };
    v->dnds = along(v->ps);
    v->dndt = along(v->pt);
}

bool MakeChain(const ManifoldSurfacePoint *points, int count, const bool *reflect,
               const bool *specular, ManifoldChain *chain) {
    if (count < 2 || count > kMaxManifoldVertices) return false;
    chain->size = count;
    for (int i = 0; i < count; ++i) {
        ManifoldVertex &v = chain->v[i];
        SetupManifoldVertex(&v, points[i]);
        bool interior = i > 0 && i < count - 1;
        v.reflect = interior ? reflect[i - 1] : true;
        v.specular = interior ? specular[i - 1] : false;
        v.o = Vec2();
    }
    for (int i = 1; i < count - 1; ++i) {
        bool ok = false;
        chain->v[i].o = ProjectedHalfVector(*chain, i, &ok);
        if (!ok) return false;
    }
    return true;
}

Vec2 ProjectedHalfVector(const ManifoldChain &c, int i, bool *ok) {
    HalfVector hv;
    bool good = ComputeHalfVector(c, i, &hv);
    if (ok) *ok = good;
    if (!good) return Vec2();
    return Vec2(Dot(c.v[i].s, hv.H), Dot(c.v[i].t, hv.H));
}

bool ConstraintDerivatives(const ManifoldChain &c, int i, Vec2 *value, Mat2 *dPrev, Mat2 *dSelf,
                           Mat2 *dNext) {
    HalfVector hv;
    if (!ComputeHalfVector(c, i, &hv)) return false;
    const ManifoldVertex &prev = c.v[i - 1], &cur = c.v[i], &next = c.v[i + 1];
    const Vec3 &H = hv.H;
    *value = Vec2(Dot(cur.s, H), Dot(cur.t, H));
    // dH = sigma/|h| (I - H H^T) dh, so d(s.H) = Sp . dh with Sp as below.
    Float k = hv.sigma / hv.len;
    Vec3 Sp = (cur.s - H * Dot(H, cur.s)) * k, Tp = (cur.t - H * Dot(H, cur.t)) * k;
    Float ai = hv.etaA / hv.li, ao = hv.etaB / hv.lo;
    auto column = [&](const Vec3 &dh, Mat2 *m, int col, const Vec3 &dsH, const Vec3 &dtH) {
        Float r0 = Dot(Sp, dh) + Dot(dsH, H), r1 = Dot(Tp, dh) + Dot(dtH, H);
        if (col == 0) { m->a = r0; m->c = r1; } else { m->b = r0; m->d = r1; }
    };
    const Vec3 zero(0, 0, 0);
    // x_{i-1} moves (along its motion axes): dw_i = (I - w_i w_i^T) e / l_i.
    column(ProjectPerp(hv.wi, prev.ps) * ai, dPrev, 0, zero, zero);
    column(ProjectPerp(hv.wi, prev.pt) * ai, dPrev, 1, zero, zero);
    column(ProjectPerp(hv.wo, next.ps) * ao, dNext, 0, zero, zero);
    column(ProjectPerp(hv.wo, next.pt) * ao, dNext, 1, zero, zero);
    // x_i moves: both directions change and so does the shading frame (through n).
    for (int col = 0; col < 2; ++col) {
        const Vec3 &e = col == 0 ? cur.ps : cur.pt;
        const Vec3 &dn = col == 0 ? cur.dnds : cur.dndt;
        Vec3 dh = -(ProjectPerp(hv.wi, e) * ai + ProjectPerp(hv.wo, e) * ao);
        Vec3 ds, dt;
        FrameDerivative(cur.sp.n, cur.frameRef, cur.s, dn, &ds, &dt);
        column(dh, dSelf, col, ds, dt);
    }
    return true;
}

// x_1's response to a move of an endpoint: A dx = -(dc/dx_endpoint) dx_endpoint,
// whose only nonzero block is that of the endpoint's neighbour constraint.
static bool FirstVertexResponse(const Tridiag &T, int row, const Mat2 &dcdEndpoint, Mat2 *dx1) {
    std::array<Mat2, kMaxManifoldVertices> R{}, X;
    R[size_t(row)] = -dcdEndpoint;
    if (!SolveTridiag(T, R.data(), X.data(), nullptr)) return false;
    *dx1 = X[0];
    return true;
}

bool FirstVertexDerivative(const ManifoldChain &c, Mat2 *dx1dxEnd) {
    int k = c.interiorCount();
    if (k <= 0) {
        *dx1dxEnd = Mat2::Identity();
        return k == 0;
    }
    Tridiag T;
    return AssembleTridiag(c, &T) && FirstVertexResponse(T, k - 1, T.Uend, dx1dxEnd);
}

bool FirstVertexDerivatives(const ManifoldChain &c, Mat2 *dx1dx0, Mat2 *dx1dxEnd) {
    int k = c.interiorCount();
    if (k <= 0) return false;
    Tridiag T;
    return AssembleTridiag(c, &T) && FirstVertexResponse(T, 0, T.L[0], dx1dx0) &&
           FirstVertexResponse(T, k - 1, T.Uend, dx1dxEnd);
}

Float ConstraintDeterminant(const ManifoldChain &c) {
    int k = c.interiorCount();
    if (k <= 0) return 1;
    Tridiag T;
    if (!AssembleTridiag(c, &T)) return 0;
    Float det = 0;
    if (!SolveTridiag(T, nullptr, nullptr, &det)) return 0;
    return det;
}

Float HalfVectorJacobian(const ManifoldChain &c) {
    int k = c.interiorCount();
    if (k <= 0) return 1;
    Tridiag T;
    if (!AssembleTridiag(c, &T)) return 0;
    // Dense 2k x 2k matrix (k <= 10): LU with partial pivoting for det(A) and det(A_pp).
    using Mat = Eigen::Matrix<Float, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * kMaxManifoldVertices,
                              2 * kMaxManifoldVertices>;
    Mat A = Mat::Zero(2 * k, 2 * k);
    auto put = [&](int r, int col, const Mat2 &m) {
        A(2 * r, 2 * col) = m.a; A(2 * r, 2 * col + 1) = m.b;
        A(2 * r + 1, 2 * col) = m.c; A(2 * r + 1, 2 * col + 1) = m.d;
    };
    for (int j = 0; j < k; ++j) {
        if (j > 0) put(j, j - 1, T.L[j]);
        put(j, j, T.D[j]);
        if (j + 1 < k) put(j, j + 1, T.U[j]);
    }
    Float detA = A.fullPivLu().determinant();
    if (!(std::abs(detA) > 0) || !std::isfinite(detA)) return 0;
    std::array<int, 2 * kMaxManifoldVertices> idx;
    int np = 0;
    for (int j = 0; j < k; ++j)
        if (c.v[j + 1].specular) { idx[np++] = 2 * j; idx[np++] = 2 * j + 1; }
    Float detP = 1;
    if (np > 0) {
        Mat P(np, np);
        for (int r = 0; r < np; ++r)
            for (int q = 0; q < np; ++q) P(r, q) = A(idx[r], idx[q]);
        detP = P.fullPivLu().determinant();
    }
    return std::abs(detP / detA);
}

Float GeneralizedGeometryTerm(const ManifoldChain &c) {
    if (c.size < 2) return 0;
    Vec3 d = c.v[1].sp.p - c.v[0].sp.p;
    Float r2 = d.lengthSquared();
    if (!(r2 > 0)) return 0;
    Vec3 w = d / std::sqrt(r2);
    // Solid angle at x_0 per area of x_1's surface: the geometric normal's cosine
    // (det P below is per unit area of the motion planes).
    Float g = AbsDot(c.v[0].sp.n, w) * AbsDot(GeometricNormal(c.v[1].sp), w) / r2;
    Mat2 P;
    if (!FirstVertexDerivative(c, &P)) return 0;
    return g * std::abs(P.det());
}

Float ShiftJacobianFactor(const ManifoldChain &eyeChain, const ManifoldChain *secondChain) {
    Float G = GeneralizedGeometryTerm(eyeChain);
    if (!(G > 0)) return 0;
    Vec3 w = Normalize(eyeChain.v[1].sp.p - eyeChain.v[0].sp.p);
    Float cos0 = AbsDot(eyeChain.v[0].sp.n, w);
    // Eq. 15: |dx_b/ds| = G(x0<->x1)/G(x0<->..<->xb) * r^2 cos^3 th0 / cos th1
    //                   = cos^4 th0 / G(x0<->..<->xb).
    Float F = Sqr(Sqr(cos0)) / G * HalfVectorJacobian(eyeChain);
    if (secondChain) F *= HalfVectorJacobian(*secondChain);
    return F;
}

const char *ToString(ManifoldStatus s) {
    switch (s) {
    case ManifoldStatus::Success: return "success";
    case ManifoldStatus::LeftSurface: return "left surface";
    case ManifoldStatus::Occluded: return "occluded";
    case ManifoldStatus::TotalInternalReflection: return "total internal reflection";
    case ManifoldStatus::WrongSide: return "wrong side";
    case ManifoldStatus::Degenerate: return "degenerate";
    case ManifoldStatus::IterationCap: return "iteration cap";
    case ManifoldStatus::Fold: return "fold";
    case ManifoldStatus::StepFloor: return "step floor";
    case ManifoldStatus::StepLeavesSurface: return "step leaves surface";
    case ManifoldStatus::NotReversible: return "not reversible";
    case ManifoldStatus::InvalidInput: return "invalid input";
    default: return "?";
    }
}

}  // namespace gradus
