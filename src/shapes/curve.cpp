#include "shapes/curve.h"

#include <cmath>
#include <cstring>

#include "core/error.h"

namespace gradus {

namespace {

Point3 Lerp(Float t, const Point3 &a, const Point3 &b) { return a * (1 - t) + b * t; }

// The point of a cubic Bezier at the blossom (u0, u1, u2) (de Casteljau).
Point3 Blossom(const Point3 p[4], Float u0, Float u1, Float u2) {
    const Point3 a[3] = {Lerp(u0, p[0], p[1]), Lerp(u0, p[1], p[2]), Lerp(u0, p[2], p[3])};
    const Point3 b[2] = {Lerp(u1, a[0], a[1]), Lerp(u1, a[1], a[2])};
    return Lerp(u2, b[0], b[1]);
}

// The two halves of a cubic Bezier: control points 0..3 and 3..6.
void Subdivide(const Point3 cp[4], Point3 out[7]) {
    out[0] = cp[0];
    out[1] = (cp[0] + cp[1]) * 0.5;
    out[2] = (cp[0] + cp[1] * 2 + cp[2]) * 0.25;
    out[3] = (cp[0] + cp[1] * 3 + cp[2] * 3 + cp[3]) * 0.125;
    out[4] = (cp[1] + cp[2] * 2 + cp[3]) * 0.25;
    out[5] = (cp[2] + cp[3]) * 0.5;
    out[6] = cp[3];
}

// Point and derivative of a cubic Bezier; where the derivative vanishes (coincident
// control points) pbrt-v3 takes the chord cp[3] - cp[0] instead.
Point3 Bezier(const Point3 cp[4], Float u, Vec3 *d) {
    const Point3 a[3] = {Lerp(u, cp[0], cp[1]), Lerp(u, cp[1], cp[2]), Lerp(u, cp[2], cp[3])};
    const Point3 b[2] = {Lerp(u, a[0], a[1]), Lerp(u, a[1], a[2])};
    if (d) *d = (b[1] - b[0]).lengthSquared() > 0 ? (b[1] - b[0]) * 3 : cp[3] - cp[0];
    return Lerp(u, b[0], b[1]);
}

// pbrt-v3's refinement depth rounding: log2 of a float, rounded to nearest
// through its exponent and first mantissa bit; 0 below 1.
int Log2Round(float v) {
    if (!(v >= 1)) return 0;
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return int(bits >> 23) - 127 + ((bits & (1u << 22)) ? 1 : 0);
}

// Does the box of the control points, widened by width / 2, miss the ray
// (the z axis, from 0 to zMax)?
bool MissesBox(const Point3 cp[4], Float width, Float zMax) {
    const Float h = 0.5 * width;
    auto lo = [&](int k) { return std::min(std::min(cp[0][k], cp[1][k]), std::min(cp[2][k], cp[3][k])); };
    auto hi = [&](int k) { return std::max(std::max(cp[0][k], cp[1][k]), std::max(cp[2][k], cp[3][k])); };
    return hi(1) + h < 0 || lo(1) - h > 0 || hi(0) + h < 0 || lo(0) - h > 0 || hi(2) + h < 0 || lo(2) - h > zMax;
}

// Newton on g(u) = (c(u) - p) . c'(u) from the best of 17 samples: the
// parameter of the point of the segment nearest to p.
Float NearestU(const Point3 cp[4], const Point3 &p) {
    Float u = 0, best = Infinity;
    for (int i = 0; i <= 16; ++i) {
        const Float d2 = DistanceSquared(p, Bezier(cp, i / Float(16), nullptr));
        if (d2 < best) best = d2, u = i / Float(16);
    }
    for (int it = 0; it < 8; ++it) {
        Vec3 d1;
        const Point3 c = Bezier(cp, u, &d1);
        const Vec3 d2 = ((cp[2] - cp[1] * 2 + cp[0]) * (1 - u) + (cp[3] - cp[2] * 2 + cp[1]) * u) * 6;
        const Float g = Dot(c - p, d1), dg = Dot(d1, d1) + Dot(c - p, d2);
        if (!(dg > 0)) break;
        u = Clamp<Float>(u - g / dg, 0, 1);
    }
    return u;
}

}  // namespace

CurveShape::CurveShape(CurveType type, std::vector<Segment> segments, bool flipNormal, int splitDepth, Vec3 errorScale)
    : type_(type), segs_(std::move(segments)), flip_(flipNormal), splitDepth_(splitDepth), errorScale_(errorScale) {}

Point3 CurveShape::point(int seg, Float u, Vec3 *dpdu) const { return Bezier(segs_[seg].cp, u, dpdu); }

Vec3 CurveShape::ribbonNormal(int seg, Float u) const {
    // pbrt-v3: sin((1 - u) a) / sin(a) n0 + sin(u a) / sin(a) n1 with a the angle
    // between the normals clamped to [0, pi/2]; its limit (a lerp) for parallel ones.
    const Segment &s = segs_[seg];
    const Float a = std::acos(Clamp<Float>(Dot(s.n0, s.n1), 0, 1)), sa = std::sin(a);
    if (sa < 1e-9) return Vec3(s.n0) * (1 - u) + Vec3(s.n1) * u;
    return Vec3(s.n0) * (std::sin((1 - u) * a) / sa) + Vec3(s.n1) * (std::sin(u * a) / sa);
}

Bounds3 CurveShape::pieceBound(int piece) const {
    const int seg = segmentOf(piece), n = 1 << splitDepth_, k = piece & (n - 1);
    const Float u0 = Float(k) / n, u1 = Float(k + 1) / n;
    const Point3 *cp = segs_[seg].cp;
    const Float h = 0.5 * std::max(width(seg, u0), width(seg, u1));
    Bounds3 b;
    for (const Point3 &p : {Blossom(cp, u0, u0, u0), Blossom(cp, u0, u0, u1), Blossom(cp, u0, u1, u1),
                            Blossom(cp, u1, u1, u1)}) {
        b.expand(p - Vec3(h, h, h));
        b.expand(p + Vec3(h, h, h));
    }
    return b;
}

Bounds3 CurveShape::worldBound() const {
    Bounds3 b;
    for (int i = 0; i < numPieces(); ++i) {
        const Bounds3 pb = pieceBound(i);
        b.expand(pb.pMin);
        b.expand(pb.pMax);
    }
    return b;
}

bool CurveShape::intersect(int piece, const Ray &ray, Float *t, Float *u, Float *v) const {
    const int seg = segmentOf(piece), n = 1 << splitDepth_, k = piece & (n - 1);
    const Float u0 = Float(k) / n, u1 = Float(k + 1) / n;
    const Segment &S = segs_[seg];
    const Point3 cpw[4] = {Blossom(S.cp, u0, u0, u0), Blossom(S.cp, u0, u0, u1), Blossom(S.cp, u0, u1, u1),
                           Blossom(S.cp, u1, u1, u1)};
    // The ray's frame (pbrt-v3's LookAt from the origin along d, "up" d x chord):
    // the ray is the z axis; the piece's chord lies roughly along x.
    const Float rayLength = ray.d.length();
    if (!(rayLength > 0)) return false;
    const Vec3 dir = ray.d / rayLength;
    Vec3 up = Cross(ray.d, cpw[3] - cpw[0]);
    if (up.lengthSquared() == 0) {
        // pbrt-v3's CoordinateSystem(d): a vector normal to d.
        const Vec3 &a = ray.d;
        up = std::abs(a.x) > std::abs(a.y) ? Vec3(-a.z, 0, a.x) / std::sqrt(a.x * a.x + a.z * a.z)
                                           : Vec3(0, a.z, -a.y) / std::sqrt(a.y * a.y + a.z * a.z);
    }
    const Vec3 right = Normalize(Cross(Normalize(up), dir)), newUp = Cross(dir, right);
    Point3 cp[4];
    for (int i = 0; i < 4; ++i) {
        const Vec3 q = cpw[i] - ray.o;
        cp[i] = Point3(Dot(q, right), Dot(q, newUp), Dot(q, dir));
    }
    const Float zMax = rayLength * ray.tMax;
    if (MissesBox(cp, std::max(width(seg, u0), width(seg, u1)), zMax)) return false;
    // Refinement depth: enough halvings that the sub-pieces' chords deviate from
    // them by less than width / 20 (pbrt-v3's bound from the second differences).
    Float L0 = 0;
    for (int i = 0; i < 2; ++i)
        for (int c = 0; c < 3; ++c) L0 = std::max(L0, std::abs(cp[i][c] - 2 * cp[i + 1][c] + cp[i + 2][c]));
    const Float eps = std::max(S.w0, S.w1) * 0.05;
    const int depth = Clamp(Log2Round(float(1.41421356237 * 6 * L0 / (8 * eps))) / 2, 0, 10);
    Float z;
    if (!recursiveIntersect(seg, cp, dir, zMax, u0, u1, depth, &z, u, v)) return false;
    *t = z / rayLength;
    return true;
}

bool CurveShape::recursiveIntersect(int seg, const Point3 cp[4], const Vec3 &dir, Float zMax, Float u0, Float u1,
                                    int depth, Float *z, Float *u, Float *v) const {
    if (depth > 0) {
        // Both halves whose widened boxes meet the ray; as in pbrt-v3 a hit in the
        // second half replaces one in the first.
        Point3 half[7];
        Subdivide(cp, half);
        const Float um[3] = {u0, (u0 + u1) / 2, u1};
        bool hit = false;
        for (int h = 0; h < 2; ++h) {
            const Point3 *c = half + 3 * h;
            if (MissesBox(c, std::max(width(seg, um[h]), width(seg, um[h + 1])), zMax)) continue;
            hit |= recursiveIntersect(seg, c, dir, zMax, um[h], um[h + 1], depth - 1, z, u, v);
        }
        return hit;
    }
    // Beyond the perpendiculars to the tangents at the sub-piece's ends: no hit.
    if ((cp[1].y - cp[0].y) * -cp[0].y + cp[0].x * (cp[0].x - cp[1].x) < 0) return false;
    if ((cp[2].y - cp[3].y) * -cp[3].y + cp[3].x * (cp[3].x - cp[2].x) < 0) return false;
    // w: the ray's (the origin's) projection on the chord, in the xy plane.
    const Float sx = cp[3].x - cp[0].x, sy = cp[3].y - cp[0].y, denom = sx * sx + sy * sy;
    if (denom == 0) return false;
    const Float w = (-cp[0].x * sx - cp[0].y * sy) / denom;
    const Float uu = Clamp(Lerp(w, u0, u1), u0, u1);
    Float hitWidth = width(seg, uu);
    if (type_ == CurveType::Ribbon) hitWidth *= std::abs(Dot(ribbonNormal(seg, uu), dir));
    if (!(hitWidth > 0)) return false;
    Vec3 dc;
    const Point3 pc = Bezier(cp, Clamp<Float>(w, 0, 1), &dc);
    const Float d2 = pc.x * pc.x + pc.y * pc.y;
    if (d2 > hitWidth * hitWidth * 0.25) return false;
    if (pc.z < 0 || pc.z > zMax) return false;
    // v: which side of the curve (in the projection) the ray passes.
    const Float dist = std::sqrt(d2), side = dc.x * -pc.y + pc.x * dc.y;
    *v = side > 0 ? 0.5 + dist / hitWidth : 0.5 - dist / hitWidth;
    *u = uu;
    *z = pc.z;
    return true;
}

void CurveShape::interaction(int piece, Float u, Float v, const Point3 &p, const Vec3 &wo,
                             SurfaceInteraction *si) const {
    const int seg = segmentOf(piece);
    Vec3 dpdu;
    point(seg, u, &dpdu);
    if (dpdu.lengthSquared() == 0) dpdu = Vec3(1, 0, 0);  // a curve collapsed to a point
    const Vec3 d = -wo;
    Float hitWidth = width(seg, u);
    Vec3 dpdv;
    if (type_ == CurveType::Ribbon) {
        const Vec3 nh = ribbonNormal(seg, u);
        hitWidth *= std::abs(Dot(nh, d));
        dpdv = Cross(nh, dpdu);
    } else {
        // Across the curve, normal to the ray (pbrt-v3's (-dpdu.y, dpdu.x, 0) in the
        // ray's frame); a cylinder turns it about dpdu by -90 (2 v - 1) degrees.
        dpdv = Cross(d, dpdu);
        if (dpdv.lengthSquared() == 0) {  // looking along the curve
            Vec3 s, t;
            CoordinateSystem(Normalize(dpdu), &s, &t);
            dpdv = s;
        }
        if (type_ == CurveType::Cylinder) {
            const Vec3 a = Normalize(dpdu), b = Normalize(dpdv);
            const Float theta = Radians(Lerp(v, -90, 90)), c = std::cos(theta), s = std::sin(theta);
            dpdv = b * c - Cross(a, b) * s + a * (Dot(a, b) * (1 - c));
        }
    }
    dpdv = dpdv.lengthSquared() > 0 ? Normalize(dpdv) * hitWidth : Vec3(0, 0, 0);
    Vec3 n = Cross(dpdu, dpdv);
    n = n.lengthSquared() > 0 ? Normalize(n) : Normalize(d);
    if (flip_) n = -n;
    si->p = p;
    si->n = n;
    si->wo = wo;
    si->uv = Point2(u, v);
    si->dpdu = dpdu;
    si->dpdv = dpdv;
    si->dndu = si->dndv = Normal3(0, 0, 0);
    si->shading.n = n;  // the geometry's own (pbrt-v3: no shading geometry on curves)
    si->shading.dpdu = dpdu;
    si->shading.dpdv = dpdv;
    si->shading.dndu = si->shading.dndv = Normal3(0, 0, 0);
    si->shading.dnhatdu = si->shading.dnhatdv = Normal3(0, 0, 0);
    // pbrt-v3's error bound: 2 hitWidth in every axis (through the transform).
    const Vec3 err = errorScale_ * (2 * hitWidth);
    si->spawnOffset = std::abs(n.x) * err.x + std::abs(n.y) * err.y + std::abs(n.z) * err.z;
}

void CurveShape::interaction(int piece, const Point3 &p, const Vec3 &wo, SurfaceInteraction *si) const {
    // The line through p along wo, traced back towards p from beyond the piece.
    const int seg = segmentOf(piece);
    const Float back = 1 + 2 * (std::max(segs_[seg].w0, segs_[seg].w1) + Distance(p, segs_[seg].cp[0]));
    Float t, u, v;
    if (!intersect(piece, Ray(p + wo * back, -wo, 2 * back), &t, &u, &v)) {
        // Not a hit of this piece (rounding at its edge): the nearest point's u and
        // the offset across the line, with pbrt-v3's side convention.
        u = NearestU(segs_[seg].cp, p);
        Vec3 dpdu;
        const Point3 c = point(seg, u, &dpdu);
        const Vec3 across = Cross(-wo, dpdu);
        const Float w = width(seg, u);
        v = across.lengthSquared() > 0 && w > 0 ? Clamp<Float>(0.5 + Dot(p - c, Normalize(across)) / w, 0, 1) : 0.5;
    }
    interaction(piece, u, v, p, wo, si);
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
    // pbrt-v3 reads splitdepth as an integer or a float: 2^splitdepth pieces per segment.
    int splitDepth = 3;
    if (ps.has("splitdepth")) {
        const Param *sp = ps.find("splitdepth");
        const Float sd = sp->type == "float" ? ps.getFloat("splitdepth", 3) : Float(ps.getInt("splitdepth", 3));
        if (!(sd >= 0 && sd <= 12)) throw fail("splitdepth", "\"splitdepth\" must be in [0, 12]");
        splitDepth = int(sd);
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
    // World width: object width times the transform's mean linear scale.
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
            seg.cp[i] = xf.applyPoint(b[i]);
            if (!seg.cp[i].isFinite()) throw fail("P", "a transformed control point is not finite");
        }
        seg.w0 = scale * Lerp(Float(s) / nSeg, w0, w1);
        seg.w1 = scale * Lerp(Float(s + 1) / nSeg, w0, w1);
        if (!N.empty()) seg.n0 = N[size_t(s)], seg.n1 = N[size_t(s + 1)];
    }
    // pbrt-v3's error bound through the transform: |M| times the object-space one.
    Vec3 errorScale(1, 1, 1);
    if (scale > 0)
        for (int i = 0; i < 3; ++i)
            errorScale[i] = (std::abs(m.m[i][0]) + std::abs(m.m[i][1]) + std::abs(m.m[i][2])) / scale;
    return std::make_shared<CurveShape>(type, std::move(segs), ro != (det < 0), splitDepth, errorScale);
}

}  // namespace gradus
