#include "shapes/triangle.h"

#include "core/error.h"
#include "samplers/sampling.h"

namespace gradus {

std::shared_ptr<TriangleMesh> TriangleMesh::Create(const Transform &xf, bool reverseOrientation,
                                                   std::vector<Point3> P, std::vector<int> indices,
                                                   std::vector<Normal3> N, std::vector<Vec3> S,
                                                   std::vector<Point2> uv, const FileLoc &loc) {
    if (indices.size() % 3 != 0)
        throw Error(loc, "triangle mesh: number of indices (" + std::to_string(indices.size()) +
                             ") is not a multiple of 3");
    for (int i : indices)
        if (i < 0 || size_t(i) >= P.size())
            throw Error(loc, "triangle mesh: vertex index " + std::to_string(i) + " out of range (" +
                                 std::to_string(P.size()) + " vertices)");
    if (!N.empty() && N.size() != P.size())
        throw Error(loc, "triangle mesh: \"N\" has " + std::to_string(N.size()) + " entries, \"P\" has " +
                             std::to_string(P.size()));
    if (!S.empty() && S.size() != P.size())
        throw Error(loc, "triangle mesh: \"S\" must have one entry per vertex");
    if (!uv.empty() && uv.size() != P.size())
        throw Error(loc, "triangle mesh: \"uv\" has " + std::to_string(uv.size()) + " entries, \"P\" has " +
                             std::to_string(P.size()));
    auto finite = [&](const char *what, size_t i, bool ok) {
        if (!ok)
            throw Error(loc, std::string("triangle mesh: \"") + what + "\" of vertex " + std::to_string(i) +
                                 " is not finite (NaN or Inf)");
    };
    for (size_t i = 0; i < P.size(); ++i) finite("P", i, P[i].isFinite());
    for (size_t i = 0; i < N.size(); ++i) finite("N", i, N[i].isFinite());
    for (size_t i = 0; i < S.size(); ++i) finite("S", i, S[i].isFinite());
    for (size_t i = 0; i < uv.size(); ++i) finite("uv", i, std::isfinite(uv[i].x) && std::isfinite(uv[i].y));
    auto m = std::make_shared<TriangleMesh>();
    m->reverseOrientation = reverseOrientation;
    m->transformSwapsHandedness = xf.swapsHandedness();
    m->p.resize(P.size());
    for (size_t i = 0; i < P.size(); ++i) {
        m->p[i] = xf.applyPoint(P[i]);
        finite("P", i, m->p[i].isFinite());  // also catches overflow by the transform
    }
    m->n.resize(N.size());
    for (size_t i = 0; i < N.size(); ++i) {
        Normal3 n = xf.applyNormal(N[i]);
        if (reverseOrientation) n = -n;
        m->n[i] = n;
    }
    m->s.resize(S.size());
    for (size_t i = 0; i < S.size(); ++i) m->s[i] = xf.applyVector(S[i]);
    m->uv = std::move(uv);
    m->indices = std::move(indices);
    return m;
}

void TriangleMesh::corners(int tri, const MeshPlacement *placement, Point3 c[3]) const {
    for (int k = 0; k < 3; ++k) {
        const Point3 &q = p[indices[3 * tri + k]];
        c[k] = placement ? placement->worldFromMesh.applyPoint(q) : q;
    }
}

void TriangleMesh::refineBarycentrics(int tri, const Ray &r, Float *b1, Float *b2,
                                      const MeshPlacement *placement) const {
    Point3 c[3];
    corners(tri, placement, c);
    const Point3 &p0 = c[0], &p1 = c[1], &p2 = c[2];
    Vec3 e1 = p1 - p0, e2 = p2 - p0;
    Vec3 pv = Cross(r.d, e2);
    Float det = Dot(e1, pv);
    if (!(std::abs(det) > 1e-300)) return;
    Float inv = 1 / det;
    Vec3 tv = r.o - p0;
    Float u = Dot(tv, pv) * inv;
    Float v = Dot(r.d, Cross(tv, e1)) * inv;
    if (!std::isfinite(u) || !std::isfinite(v)) return;
    u = std::max<Float>(0, u);
    v = std::max<Float>(0, v);
    if (u + v > 1) {
        Float s = 1 / (u + v);
        u *= s;
        v *= s;
    }
    *b1 = u;
    *b2 = v;
}

void TriangleMesh::interaction(int tri, Float b1, Float b2, const Vec3 &wo, SurfaceInteraction *si,
                               const MeshPlacement *placement) const {
    const int i0 = indices[3 * tri], i1 = indices[3 * tri + 1], i2 = indices[3 * tri + 2];
    Point3 c[3];
    corners(tri, placement, c);
    const Point3 &p0 = c[0], &p1 = c[1], &p2 = c[2];
    // Per-vertex normals and tangents, placed as TriangleMesh::Create places them.
    auto normalAt = [&](int i) { return placement ? placement->worldFromMesh.applyNormal(n[i]) : n[i]; };
    auto tangentAt = [&](int i) { return placement ? placement->worldFromMesh.applyVector(s[i]) : s[i]; };
    const bool flip = reverseOrientation ^ transformSwapsHandedness ^ (placement && placement->swapsHandedness);
    Float b0 = 1 - b1 - b2;
    Point2 uv0(0, 0), uv1(1, 0), uv2(1, 1);
    if (!uv.empty()) { uv0 = uv[i0]; uv1 = uv[i1]; uv2 = uv[i2]; }
    // Partial derivatives from the uv parameterisation.
    Vec2 duv02 = uv0 - uv2, duv12 = uv1 - uv2;
    Vec3 dp02 = p0 - p2, dp12 = p1 - p2;
    Float det = duv02.x * duv12.y - duv02.y * duv12.x;
    Normal3 ng = Cross(dp02, dp12);
    Float ngLen = ng.length();
    ng = ngLen > 0 ? ng / ngLen : Normal3(0, 0, 1);
    Vec3 dpdu, dpdv;
    bool degenerateUV = std::abs(det) < 1e-12;
    if (!degenerateUV) {
        Float inv = 1 / det;
        dpdu = (dp02 * duv12.y - dp12 * duv02.y) * inv;
        dpdv = (dp12 * duv02.x - dp02 * duv12.x) * inv;
    }
    if (degenerateUV || Cross(dpdu, dpdv).lengthSquared() == 0) CoordinateSystem(ng, &dpdu, &dpdv);

    si->p = p0 * b0 + p1 * b1 + p2 * b2;
    si->uv = uv0 * b0 + uv1 * b1 + uv2 * b2;
    si->wo = wo;
    si->dpdu = dpdu;
    si->dpdv = dpdv;
    si->dndu = si->dndv = Normal3(0, 0, 0);
    si->n = ng;
    si->shading.n = ng;
    si->shading.dpdu = dpdu;
    si->shading.dpdv = dpdv;
    si->shading.dndu = si->shading.dndv = Normal3(0, 0, 0);
    si->shading.dnhatdu = si->shading.dnhatdv = Normal3(0, 0, 0);

    if (!n.empty()) {
        const Normal3 n0 = normalAt(i0), n1 = normalAt(i1), n2 = normalAt(i2);
        const Normal3 m = n0 * b0 + n1 * b1 + n2 * b2;  // interpolated, not unit (scaled meshes: far from it)
        const Float mLen = m.length();
        Normal3 ns = mLen > 0 ? m / mLen : si->n;
        si->n = FaceForward(si->n, ns);
        Vec3 ss = s.empty() ? si->dpdu : tangentAt(i0) * b0 + tangentAt(i1) * b1 + tangentAt(i2) * b2;
        if (ss.lengthSquared() == 0) ss = si->dpdu;
        Vec3 ts = Cross(ss, ns);
        if (ts.lengthSquared() > 0) {
            ts = Normalize(ts);
            ss = Cross(ts, ns);
        } else {
            CoordinateSystem(ns, &ss, &ts);
        }
        // Normal derivatives from the per-vertex normals.
        Normal3 dndu(0, 0, 0), dndv(0, 0, 0);
        if (!degenerateUV) {
            Normal3 dn1 = n0 - n2, dn2 = n1 - n2;
            Float inv = 1 / det;
            dndu = (dn1 * duv12.y - dn2 * duv02.y) * inv;
            dndv = (dn2 * duv02.x - dn1 * duv12.x) * inv;
        }
        si->setShadingGeometry(ss, ts, dndu, dndv, true);
        // d(m/|m|)/du = (I - n n^T) dm/du / |m|: the unit normal's derivative.
        if (mLen > 0) {
            Normal3 dmdu = dndu, dmdv = dndv;
            if (degenerateUV) {
                // No uv parameterisation: dpdu, dpdv are a basis of the triangle's
                // plane; write each as a (p1 - p0) + b (p2 - p0) and take the same
                // combination of n1 - n0 and n2 - n0.
                Vec3 e1 = p1 - p0, e2 = p2 - p0;
                Float a11 = Dot(e1, e1), a12 = Dot(e1, e2), a22 = Dot(e2, e2), d = a11 * a22 - a12 * a12;
                auto along = [&](const Vec3 &e) {
                    if (!(d > 0)) return Normal3(0, 0, 0);
                    Float r1 = Dot(e1, e), r2 = Dot(e2, e);
                    Float a = (a22 * r1 - a12 * r2) / d, b = (a11 * r2 - a12 * r1) / d;
                    return (n1 - n0) * a + (n2 - n0) * b;
                };
                dmdu = along(dpdu);
                dmdv = along(dpdv);
            }
            auto unit = [&](const Normal3 &dm) { return (dm - ns * Dot(ns, dm)) / mLen; };
            si->shading.dnhatdu = unit(dmdu);
            si->shading.dnhatdv = unit(dmdv);
        }
    } else if (flip) {
        si->n = -si->n;
        si->shading.n = si->n;
    }
}

Triangle::Triangle(std::shared_ptr<const TriangleMesh> mesh, int tri) : mesh_(std::move(mesh)), tri_(tri) {
    const int *v = &mesh_->indices[3 * tri_];
    for (int k = 0; k < 3; ++k) p_[k] = mesh_->p[v[k]];
    const Normal3 n = Cross(p_[1] - p_[0], p_[2] - p_[0]);
    const Float len = n.length();
    area_ = 0.5 * len;
    n_ = len > 0 ? n / len : Normal3(0, 0, 1);
    if (!mesh_->n.empty()) {
        // FaceForward against the interpolated shading normal: constant over the
        // triangle when the three vertex normals lie on one side of n_.
        int pos = 0, neg = 0;
        for (int k = 0; k < 3; ++k) {
            const Float d = Dot(n_, mesh_->n[v[k]]);
            pos += d > 0;
            neg += d < 0;
        }
        if (pos == 3) varies_ = false;
        else if (neg == 3) n_ = -n_, varies_ = false;
        else varies_ = true;
    } else if (mesh_->reverseOrientation ^ mesh_->transformSwapsHandedness) {
        n_ = -n_;
    }
}

Normal3 Triangle::orientedNormal(Float b0, Float b1) const {
    if (!varies_) return n_;
    const int *v = &mesh_->indices[3 * tri_];
    return FaceForward(n_, mesh_->n[v[0]] * b0 + mesh_->n[v[1]] * b1 + mesh_->n[v[2]] * (1 - b0 - b1));
}

Float Triangle::area() const { return area_; }

Bounds3 Triangle::worldBound() const {
    Bounds3 b;
    for (const Point3 &q : p_) b.expand(q);
    return b;
}

Interaction Triangle::sampleArea(Point2 u, Float *pdf) const {
    const Point2 b = SampleUniformTriangle(u);
    Interaction it;
    it.p = p_[0] * b.x + p_[1] * b.y + p_[2] * (1 - b.x - b.y);
    it.n = orientedNormal(b.x, b.y);
    *pdf = area_ > 0 ? 1 / area_ : 0;
    return it;
}

// Moeller-Trumbore in double precision.
bool Triangle::intersectP(const Ray &r, Float *tHit, Interaction *hit) const {
    const Point3 &p0 = p_[0], &p1 = p_[1], &p2 = p_[2];
    Vec3 e1 = p1 - p0, e2 = p2 - p0;
    Vec3 pv = Cross(r.d, e2);
    Float det = Dot(e1, pv);
    if (det == 0) return false;
    Float inv = 1 / det;
    Vec3 tv = r.o - p0;
    Float b1 = Dot(tv, pv) * inv;
    if (b1 < 0 || b1 > 1) return false;
    Vec3 qv = Cross(tv, e1);
    Float b2 = Dot(r.d, qv) * inv;
    if (b2 < 0 || b1 + b2 > 1) return false;
    Float t = Dot(e2, qv) * inv;
    if (t <= 0 || t >= r.tMax) return false;
    *tHit = t;
    hit->p = r(t);
    hit->n = orientedNormal(1 - b1 - b2, b1);
    hit->wo = -r.d;
    return true;
}

}  // namespace gradus
