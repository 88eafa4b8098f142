// Analytic ManifoldScene for the tests and benchmarks: planes (optionally
// finite rectangles) and spheres, intersected exactly in double.
#pragma once
#include <vector>

#include "integrators/manifold/manifold.h"

namespace gradus::testing {

struct AnalyticShape {
    enum Kind { Plane, Sphere } kind = Plane;
    Point3 c;              // plane origin or sphere centre
    Vec3 n, u, v;          // plane: unit normal and in-plane axes (u x v = n)
    Float halfExtent = Infinity;  // plane: |p.u|, |p.v| limit around c
    Float radius = 1;      // sphere
    Float etaInterior = 1, etaExterior = 1;
};

class AnalyticScene : public ManifoldScene {
  public:
    int addPlane(const Point3 &c, const Vec3 &n, Float etaInt = 1, Float etaExt = 1,
                 Float halfExtent = Infinity) {
        AnalyticShape s;
        s.kind = AnalyticShape::Plane;
        s.c = c;
        s.n = Normalize(n);
        CoordinateSystem(s.n, &s.u, &s.v);
        s.halfExtent = halfExtent;
        s.etaInterior = etaInt;
        s.etaExterior = etaExt;
        shapes.push_back(s);
        return int(shapes.size()) - 1;
    }
    int addSphere(const Point3 &c, Float r, Float etaInt = 1, Float etaExt = 1) {
        AnalyticShape s;
        s.kind = AnalyticShape::Sphere;
        s.c = c;
        s.radius = r;
        s.etaInterior = etaInt;
        s.etaExterior = etaExt;
        shapes.push_back(s);
        return int(shapes.size()) - 1;
    }

    // Surface point of shape id at p (p projected onto the shape).
    ManifoldSurfacePoint pointOn(int id, Point3 p) const {
        const AnalyticShape &s = shapes[id];
        ManifoldSurfacePoint sp;
        sp.primitiveId = id;
        sp.etaInterior = s.etaInterior;
        sp.etaExterior = s.etaExterior;
        if (s.kind == AnalyticShape::Plane) {
            sp.p = p - s.n * Dot(p - s.c, s.n);
            sp.n = s.n;
            sp.dpdu = s.u;
            sp.dpdv = s.v;
        } else {
            Vec3 r = Normalize(p - s.c);
            sp.p = s.c + r * s.radius;
            sp.n = r;
            Vec3 a, b;
            CoordinateSystem(r, &a, &b);
            sp.dpdu = a;
            sp.dpdv = b;
            sp.dndu = a / s.radius;
            sp.dndv = b / s.radius;
        }
        return sp;
    }
    // Move a surface point by the tangent vector e, staying on the surface; the
    // derivative of the result with respect to e at e = 0 is the identity on the
    // tangent plane.
    ManifoldSurfacePoint moveOn(const ManifoldSurfacePoint &sp, const Vec3 &e) const {
        const AnalyticShape &s = shapes[sp.primitiveId];
        if (s.kind == AnalyticShape::Plane) return pointOn(sp.primitiveId, sp.p + e);
        return pointOn(sp.primitiveId, s.c + Normalize(sp.p - s.c + e) * s.radius);
    }

    bool intersect(const Ray &r, ManifoldSurfacePoint *hit) const override {
        Float tMin = 1e-9 * (1 + MaxComponent(Abs(r.o))), best = r.tMax;
        int bestId = -1;
        for (size_t i = 0; i < shapes.size(); ++i) {
            const AnalyticShape &s = shapes[i];
            if (s.kind == AnalyticShape::Plane) {
                Float dn = Dot(r.d, s.n);
                if (dn == 0) continue;
                Float t = Dot(s.c - r.o, s.n) / dn;
                if (!(t > tMin && t < best)) continue;
                Vec3 q = r(t) - s.c;
                if (std::abs(Dot(q, s.u)) > s.halfExtent || std::abs(Dot(q, s.v)) > s.halfExtent)
                    continue;
                best = t;
                bestId = int(i);
            } else {
                Vec3 oc = r.o - s.c;
                Float a = r.d.lengthSquared(), b = Dot(oc, r.d), c = oc.lengthSquared() - Sqr(s.radius);
                Float disc = b * b - a * c;
                if (disc < 0) continue;
                Float sq = std::sqrt(disc);
                Float t0 = (-b - sq) / a, t1 = (-b + sq) / a;
                for (Float t : {t0, t1})
                    if (t > tMin && t < best) {
                        best = t;
                        bestId = int(i);
                        break;
                    }
            }
        }
        if (bestId < 0) return false;
        *hit = pointOn(bestId, r(best));
        if (shapes[bestId].kind == AnalyticShape::Plane) hit->p = r(best) - shapes[bestId].n * Dot(r(best) - shapes[bestId].c, shapes[bestId].n);
        return true;
    }
    bool visible(const Point3 &a, const Point3 &b) const override {
        ManifoldSurfacePoint h;
        Vec3 d = b - a;
        Float l = d.length();
        return !intersect(Ray(a, d / l, l * (1 - 1e-9)), &h);
    }

    std::vector<AnalyticShape> shapes;
};

// A free point (camera or chain endpoint not on scene geometry) with normal n.
inline ManifoldSurfacePoint FreePoint(const Point3 &p, const Vec3 &n) {
    ManifoldSurfacePoint sp;
    sp.p = p;
    sp.n = Normalize(n);
    CoordinateSystem(sp.n, &sp.dpdu, &sp.dpdv);
    return sp;
}

}  // namespace gradus::testing
