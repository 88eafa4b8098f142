#include "shapes/curve.h"

#include <cmath>

#include "core/error.h"

namespace gradus {

namespace {

// Cubic Bezier point and derivative (de Casteljau).
Point3 Bezier(const Point3 cp[4], Float u, Vec3 *d) {
    const Point3 a = cp[0] + (cp[1] - cp[0]) * u, b = cp[1] + (cp[2] - cp[1]) * u, c = cp[2] + (cp[3] - cp[2]) * u;
    const Point3 e = a + (b - a) * u, f = b + (c - b) * u;
    if (d) *d = (f - e) * 3;
    return e + (f - e) * u;
}

Vec3 BezierSecond(const Point3 cp[4], Float u) {
    const Vec3 a = cp[2] - cp[1] * 2 + cp[0], b = cp[3] - cp[2] * 2 + cp[1];
    return (a + (b - a) * u) * 6;
}

Point3 ToFloat(const Point3 &p) { return Point3(float(p.x), float(p.y), float(p.z)); }

// Unit vector perpendicular to unit t, close to `hint` where possible.
Vec3 PerpendicularTo(const Vec3 &t, const Vec3 &hint) {
    Vec3 v = hint - t * Dot(hint, t);
    if (v.lengthSquared() > 1e-20) return Normalize(v);
    Vec3 s, u;
    CoordinateSystem(t, &s, &u);
    return s;
}

}  // namespace

CurveShape::CurveShape(CurveType type, std::vector<Segment> segments, bool reverseOrientation)
    : type_(type), segs_(std::move(segments)), reverseOrientation_(reverseOrientation) {}

Bounds3 CurveShape::worldBound() const {
    Bounds3 b;
    for (const Segment &s : segs_) {
        const Float r = std::max(s.r0, s.r1);
        for (const Point3 &p : s.cp) {
            b.expand(p - Vec3(r, r, r));
            b.expand(p + Vec3(r, r, r));
        }
    }
    return b;
}

Point3 CurveShape::point(int seg, Float u, Vec3 *dpdu) const { return Bezier(segs_[seg].cp, u, dpdu); }

Normal3 CurveShape::ribbonNormal(int seg, Float u) const {
    const Segment &s = segs_[seg];
    const Float c = Clamp<Float>(Dot(s.n0, s.n1), -1, 1), angle = std::acos(c), sn = std::sin(angle);
    if (sn < 1e-6) return Normalize(s.n0 * (1 - u) + s.n1 * u);
    return Normalize(s.n0 * (std::sin((1 - u) * angle) / sn) + s.n1 * (std::sin(u * angle) / sn));
}

Float CurveShape::closestU(int seg, const Point3 &p, Float uHint) const {
    const Point3 *cp = segs_[seg].cp;
    Float u = uHint;
    if (!(u >= 0 && u <= 1)) {
        Float best = Infinity;
        for (int i = 0; i <= 16; ++i) {
            const Float d2 = DistanceSquared(p, Bezier(cp, i / Float(16), nullptr));
            if (d2 < best) best = d2, u = i / Float(16);
        }
    }
    // Newton on g(u) = (c(u) - p) . c'(u) = 0 (stationary distance to the axis).
    for (int it = 0; it < 8; ++it) {
        Vec3 d1;
        const Point3 c = Bezier(cp, u, &d1);
        const Vec3 d2 = BezierSecond(cp, u);
        const Float g = Dot(c - p, d1), dg = Dot(d1, d1) + Dot(c - p, d2);
        if (!(dg > 0)) break;
        const Float next = Clamp<Float>(u - g / dg, 0, 1);
        const bool done = std::abs(next - u) < 1e-12;
        u = next;
        if (done) break;
    }
    return u;
}

void CurveShape::interaction(int seg, Float uHint, const Point3 &pHit, const Vec3 &wo, SurfaceInteraction *si) const {
    const Float u = closestU(seg, pHit, uHint);
    Vec3 dpdu;
    const Point3 c = point(seg, u, &dpdu);
    if (dpdu.lengthSquared() == 0) dpdu = segs_[seg].cp[3] - segs_[seg].cp[0];
    if (dpdu.lengthSquared() == 0) dpdu = Vec3(1, 0, 0);
    const Vec3 T = Normalize(dpdu);
    const Float r = radius(seg, u);
    Point3 p = pHit;
    Vec3 off = p - c;
    Vec3 n;
    switch (type_) {
    case CurveType::Cylinder:
        n = PerpendicularTo(T, off.lengthSquared() > 0 ? off : wo);
        p = c + n * r;  // onto the tube (double precision)
        off = p - c;
        break;
    case CurveType::Flat: n = PerpendicularTo(T, wo); break;
    case CurveType::Ribbon:
        n = PerpendicularTo(T, ribbonNormal(seg, u));
        if (reverseOrientation_) n = -n;
        break;
    }
    // Signed offset across the ray in units of r (Chiang et al. 2016's h).
    const Vec3 across = Cross(wo, T);
    Float h = 0;
    if (across.lengthSquared() > 1e-20 && r > 0) h = Clamp<Float>(Dot(off, Normalize(across)) / r, -1, 1);

    si->p = p;
    si->n = n;
    si->wo = wo;
    si->uv = Point2(u, 0.5 * (1 + h));
    si->dpdu = dpdu;
    si->dpdv = Normalize(Cross(n, dpdu)) * (2 * std::max<Float>(r, 1e-12));
    si->dndu = si->dndv = Normal3(0, 0, 0);
    // A tube's normal turns with the circumference (Weingarten: dn = dp / r along
    // it; the axis' own curvature is ignored). Hair reads it as "a tube".
    if (type_ == CurveType::Cylinder && r > 0) si->dndv = si->dpdv / r;
    si->setShadingGeometry(si->dpdu, si->dpdv, Normal3(0, 0, 0), Normal3(0, 0, 0), true);
    si->shading.dnhatdu = si->shading.dnhatdv = Normal3(0, 0, 0);
}

std::shared_ptr<CurveShape> CreateCurveShape(const ParamSet &ps, const Transform &xf, bool ro, const FileLoc &loc) {
    auto fail = [&](const char *param, const std::string &msg) -> Error {
        return Error(param ? ps.locOf(param, loc) : loc, "Shape \"curve\": " + msg);
    };
    const Float width = ps.getFloat("width", 1);
    const Float w0 = ps.getFloat("width0", width), w1 = ps.getFloat("width1", width);
    for (auto [name, w] : {std::pair<const char *, Float>{"width", width}, {"width0", w0}, {"width1", w1}})
        if (!(w >= 0) || !std::isfinite(w)) throw fail(ps.has(name) ? name : nullptr, std::string("\"") + name + "\" must be >= 0 and finite");
    if (!(w0 > 0 || w1 > 0)) throw fail("width", "the curve has zero width");
    const int degree = ps.getInt("degree", 3);
    if (degree != 2 && degree != 3) throw fail("degree", "\"degree\" must be 2 or 3, got " + std::to_string(degree));
    const std::string basis = ps.getString("basis", "bezier");
    if (basis != "bezier" && basis != "bspline")
        throw fail("basis", "unknown basis \"" + basis + "\" (valid: bezier, bspline)");
    const std::string typeName = ps.getString("type", "flat");
    CurveType type;
    if (typeName == "flat") type = CurveType::Flat;
    else if (typeName == "cylinder") type = CurveType::Cylinder;
    else if (typeName == "ribbon") type = CurveType::Ribbon;
    else throw fail("type", "unknown curve type \"" + typeName + "\" (valid: flat, cylinder, ribbon)");
    // pbrt-v3 reads splitdepth as an integer or a float; Embree needs no splitting.
    if (ps.has("splitdepth")) {
        const Param *sp = ps.find("splitdepth");
        if (sp->type == "float") (void)ps.getFloat("splitdepth", 3);
        else (void)ps.getInt("splitdepth", 3);
    }

    const std::vector<Point3> P = ps.getPoint3s("P");
    const int ncp = int(P.size());
    if (ncp == 0) throw fail(nullptr, "missing \"point P\"");
    for (const Point3 &p : P)
        if (!p.isFinite()) throw fail("P", "a control point is not finite");
    int nSeg;
    if (basis == "bezier") {
        // degree + 1 points for the first segment, degree more for each further one.
        if (ncp < degree + 1 || (ncp - 1) % degree != 0)
            throw fail("P", std::to_string(ncp) + " control points; the degree-" + std::to_string(degree) +
                                " Bezier basis needs " + std::to_string(degree + 1) + " + n * " + std::to_string(degree));
        nSeg = (ncp - 1) / degree;
    } else {
        if (ncp < degree + 1)
            throw fail("P", std::to_string(ncp) + " control points; the degree-" + std::to_string(degree) +
                                " B-spline basis needs at least " + std::to_string(degree + 1));
        nSeg = ncp - degree;
    }
    std::vector<Normal3> N;
    if (ps.has("N")) {
        N = ps.getNormals("N");  // pbrt-v3 ignores normals on flat and cylinder curves (with a warning)
        if (type != CurveType::Ribbon) N.clear();
        else if (int(N.size()) != nSeg + 1)
            throw fail("N", std::to_string(N.size()) + " normals; a ribbon curve with " + std::to_string(nSeg) +
                                " segments needs " + std::to_string(nSeg + 1));
    } else if (type == CurveType::Ribbon) {
        throw fail("type", "a \"ribbon\" curve needs \"normal N\" at the segment ends");
    }
    for (Normal3 &n : N) {
        n = xf.applyNormal(n);
        if (!n.isFinite() || n.lengthSquared() == 0) throw fail("N", "a ribbon normal is zero or not finite");
        n = Normalize(n);
    }
    // World radius: object width times the transform's mean linear scale.
    const Matrix4 &m = xf.matrix();
    const Float det = m.m[0][0] * (m.m[1][1] * m.m[2][2] - m.m[1][2] * m.m[2][1]) -
                      m.m[0][1] * (m.m[1][0] * m.m[2][2] - m.m[1][2] * m.m[2][0]) +
                      m.m[0][2] * (m.m[1][0] * m.m[2][1] - m.m[1][1] * m.m[2][0]);
    const Float scale = std::cbrt(std::abs(det));

    std::vector<CurveShape::Segment> segs(nSeg);
    for (int s = 0; s < nSeg; ++s) {
        Point3 b[4];  // cubic Bezier control points of segment s (object space)
        if (basis == "bezier") {
            const Point3 *q = &P[size_t(s * degree)];
            if (degree == 3) {
                for (int i = 0; i < 4; ++i) b[i] = q[i];
            } else {  // degree elevation 2 -> 3
                b[0] = q[0], b[1] = q[0] + (q[1] - q[0]) * (2.0 / 3), b[2] = q[2] + (q[1] - q[2]) * (2.0 / 3), b[3] = q[2];
            }
        } else {
            const Point3 *q = &P[size_t(s)];
            if (degree == 3) {  // uniform cubic B-spline -> Bezier
                b[0] = (q[0] + q[1] * 4 + q[2]) / 6;
                b[1] = (q[1] * 2 + q[2]) / 3;
                b[2] = (q[1] + q[2] * 2) / 3;
                b[3] = (q[1] + q[2] * 4 + q[3]) / 6;
            } else {  // uniform quadratic B-spline -> quadratic Bezier -> cubic
                const Point3 a0 = (q[0] + q[1]) * 0.5, a1 = q[1], a2 = (q[1] + q[2]) * 0.5;
                b[0] = a0, b[1] = a0 + (a1 - a0) * (2.0 / 3), b[2] = a2 + (a1 - a2) * (2.0 / 3), b[3] = a2;
            }
        }
        CurveShape::Segment &seg = segs[size_t(s)];
        for (int i = 0; i < 4; ++i) {
            seg.cp[i] = ToFloat(xf.applyPoint(b[i]));
            if (!seg.cp[i].isFinite()) throw fail("P", "a transformed control point is not finite");
        }
        seg.r0 = float(0.5 * scale * Lerp(Float(s) / nSeg, w0, w1));
        seg.r1 = float(0.5 * scale * Lerp(Float(s + 1) / nSeg, w0, w1));
        if (!N.empty()) seg.n0 = N[size_t(s)], seg.n1 = N[size_t(s + 1)];
    }
    return std::make_shared<CurveShape>(type, std::move(segs), ro);
}

}  // namespace gradus
