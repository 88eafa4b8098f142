// 4x4 affine/projective transforms with cached inverse (pbrt-v3 conventions:
// left-handed camera space, Rotate in degrees, LookAt returns world-from-camera
// inverse i.e. camera-from-world).
#pragma once
#include "core/geometry.h"

namespace gradus {

struct Matrix4 {
    Float m[4][4];
    Matrix4();  // identity
    explicit Matrix4(const Float v[16]);  // row-major
    Matrix4(Float t00, Float t01, Float t02, Float t03, Float t10, Float t11, Float t12, Float t13,
            Float t20, Float t21, Float t22, Float t23, Float t30, Float t31, Float t32, Float t33);
    bool operator==(const Matrix4 &o) const;
    bool isIdentity() const;
    Matrix4 transposed() const;
    // Throws gradus::Error if singular.
    Matrix4 inverse() const;
    static Matrix4 Mul(const Matrix4 &a, const Matrix4 &b);
};

class Transform {
  public:
    Transform() = default;
    explicit Transform(const Matrix4 &m) : m_(m), mInv_(m.inverse()) {}
    Transform(const Matrix4 &m, const Matrix4 &mInv) : m_(m), mInv_(mInv) {}
    const Matrix4 &matrix() const { return m_; }
    const Matrix4 &inverseMatrix() const { return mInv_; }
    Transform inverse() const { return Transform(mInv_, m_); }
    bool isIdentity() const { return m_.isIdentity(); }
    bool operator==(const Transform &o) const { return m_ == o.m_; }
    Transform operator*(const Transform &o) const {
        return Transform(Matrix4::Mul(m_, o.m_), Matrix4::Mul(o.mInv_, mInv_));
    }
    // True if the transform flips handedness (negative determinant of the 3x3 part).
    bool swapsHandedness() const;

    Point3 applyPoint(const Point3 &p) const;  // homogeneous divide
    Vec3 applyVector(const Vec3 &v) const;
    Normal3 applyNormal(const Normal3 &n) const;  // inverse transpose, not normalized
    Ray applyRay(const Ray &r) const { return Ray(applyPoint(r.o), applyVector(r.d), r.tMax); }
    Bounds3 applyBounds(const Bounds3 &b) const;

  private:
    Matrix4 m_, mInv_;
};

Transform Translate(const Vec3 &delta);
Transform Scale(Float x, Float y, Float z);
Transform RotateX(Float thetaDeg);
Transform RotateY(Float thetaDeg);
Transform RotateZ(Float thetaDeg);
Transform Rotate(Float thetaDeg, const Vec3 &axis);
// camera-from-world for a camera at pos looking at look (pbrt-v3 LookAt).
// Throws gradus::Error when up is parallel to the view direction.
Transform LookAt(const Point3 &pos, const Point3 &look, const Vec3 &up);
Transform Perspective(Float fovDeg, Float znear, Float zfar);
Transform Orthographic(Float znear, Float zfar);

}  // namespace gradus
