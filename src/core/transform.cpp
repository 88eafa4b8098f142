#include "core/transform.h"

#include <cstring>

#include "core/error.h"

namespace gradus {

Matrix4::Matrix4() {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) m[i][j] = (i == j) ? 1 : 0;
}

Matrix4::Matrix4(const Float v[16]) {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) m[i][j] = v[i * 4 + j];
}

Matrix4::Matrix4(Float t00, Float t01, Float t02, Float t03, Float t10, Float t11, Float t12, Float t13,
                 Float t20, Float t21, Float t22, Float t23, Float t30, Float t31, Float t32, Float t33) {
    Float v[16] = {t00, t01, t02, t03, t10, t11, t12, t13, t20, t21, t22, t23, t30, t31, t32, t33};
    *this = Matrix4(v);
}

bool Matrix4::operator==(const Matrix4 &o) const {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (m[i][j] != o.m[i][j]) return false;
    return true;
}

bool Matrix4::isIdentity() const { return *this == Matrix4(); }

Matrix4 Matrix4::transposed() const {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
    return r;
}

Matrix4 Matrix4::Mul(const Matrix4 &a, const Matrix4 &b) {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j] +
                        a.m[i][3] * b.m[3][j];
    return r;
}

// Gauss-Jordan elimination with partial pivoting.
Matrix4 Matrix4::inverse() const {
    Float a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = m[i][j];
            a[i][j + 4] = (i == j) ? 1 : 0;
        }
    for (int c = 0; c < 4; ++c) {
        int piv = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
        if (a[piv][c] == 0 || !std::isfinite(a[piv][c])) throw Error("singular matrix in transform inverse");
        if (piv != c)
            for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
        Float inv = 1 / a[c][c];
        for (int j = 0; j < 8; ++j) a[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            Float f = a[r][c];
            if (f != 0)
                for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
        }
    }
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = a[i][j + 4];
    return r;
}

bool Transform::swapsHandedness() const {
    const auto &m = m_.m;
    Float det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    return det < 0;
}

Point3 Transform::applyPoint(const Point3 &p) const {
    const auto &m = m_.m;
    Float x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
    Float y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
    Float z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
    Float w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
    return w == 1 ? Point3(x, y, z) : Point3(x, y, z) / w;
}

Vec3 Transform::applyVector(const Vec3 &v) const {
    const auto &m = m_.m;
    return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
            m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
}

Normal3 Transform::applyNormal(const Normal3 &n) const {
    const auto &mi = mInv_.m;
    return {mi[0][0] * n.x + mi[1][0] * n.y + mi[2][0] * n.z, mi[0][1] * n.x + mi[1][1] * n.y + mi[2][1] * n.z,
            mi[0][2] * n.x + mi[1][2] * n.y + mi[2][2] * n.z};
}

Bounds3 Transform::applyBounds(const Bounds3 &b) const {
    Bounds3 r;
    if (b.empty()) return r;
    for (int i = 0; i < 8; ++i)
        r.expand(applyPoint(Point3((i & 1) ? b.pMax.x : b.pMin.x, (i & 2) ? b.pMax.y : b.pMin.y,
                                   (i & 4) ? b.pMax.z : b.pMin.z)));
    return r;
}

Transform Translate(const Vec3 &d) {
    Matrix4 m(1, 0, 0, d.x, 0, 1, 0, d.y, 0, 0, 1, d.z, 0, 0, 0, 1);
    Matrix4 mi(1, 0, 0, -d.x, 0, 1, 0, -d.y, 0, 0, 1, -d.z, 0, 0, 0, 1);
    return Transform(m, mi);
}

Transform Scale(Float x, Float y, Float z) {
    Matrix4 m(x, 0, 0, 0, 0, y, 0, 0, 0, 0, z, 0, 0, 0, 0, 1);
    return Transform(m);  // inverse() throws on a zero scale
}

Transform RotateX(Float theta) {
    Float s = std::sin(Radians(theta)), c = std::cos(Radians(theta));
    Matrix4 m(1, 0, 0, 0, 0, c, -s, 0, 0, s, c, 0, 0, 0, 0, 1);
    return Transform(m, m.transposed());
}

Transform RotateY(Float theta) {
    Float s = std::sin(Radians(theta)), c = std::cos(Radians(theta));
    Matrix4 m(c, 0, s, 0, 0, 1, 0, 0, -s, 0, c, 0, 0, 0, 0, 1);
    return Transform(m, m.transposed());
}

Transform RotateZ(Float theta) {
    Float s = std::sin(Radians(theta)), c = std::cos(Radians(theta));
    Matrix4 m(c, -s, 0, 0, s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1);
    return Transform(m, m.transposed());
}

// Rodrigues rotation about a normalized axis.
Transform Rotate(Float theta, const Vec3 &axis) {
    Float len = axis.length();
    if (!(len > 0)) throw Error("Rotate: zero-length axis");
    Vec3 a = axis / len;
    Float s = std::sin(Radians(theta)), c = std::cos(Radians(theta));
    Matrix4 m;
    m.m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
    m.m[0][1] = a.x * a.y * (1 - c) - a.z * s;
    m.m[0][2] = a.x * a.z * (1 - c) + a.y * s;
    m.m[0][3] = 0;
    m.m[1][0] = a.x * a.y * (1 - c) + a.z * s;
    m.m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
    m.m[1][2] = a.y * a.z * (1 - c) - a.x * s;
    m.m[1][3] = 0;
    m.m[2][0] = a.x * a.z * (1 - c) - a.y * s;
    m.m[2][1] = a.y * a.z * (1 - c) + a.x * s;
    m.m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
    m.m[2][3] = 0;
    return Transform(m, m.transposed());
}

Transform LookAt(const Point3 &pos, const Point3 &look, const Vec3 &up) {
    Vec3 dir = look - pos;
    if (!(dir.length() > 0)) throw Error("LookAt: eye and look-at point coincide");
    dir = Normalize(dir);
    Vec3 upn = up.length() > 0 ? Normalize(up) : up;
    Vec3 right = Cross(upn, dir);
    if (!(right.length() > 1e-12)) throw Error("LookAt: up vector is parallel to the viewing direction");
    right = Normalize(right);
    Vec3 newUp = Cross(dir, right);
    // world-from-camera columns: right, up, dir, pos
    Matrix4 worldFromCamera(right.x, newUp.x, dir.x, pos.x, right.y, newUp.y, dir.y, pos.y, right.z, newUp.z,
                            dir.z, pos.z, 0, 0, 0, 1);
    return Transform(worldFromCamera.inverse(), worldFromCamera);
}

Transform Perspective(Float fov, Float n, Float f) {
    Matrix4 persp(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, f / (f - n), -f * n / (f - n), 0, 0, 1, 0);
    Float invTan = 1 / std::tan(Radians(fov) / 2);
    return Scale(invTan, invTan, 1) * Transform(persp);
}

Transform Orthographic(Float n, Float f) { return Scale(1, 1, 1 / (f - n)) * Translate(Vec3(0, 0, -n)); }

}  // namespace gradus
