// Surface hit records shared by shapes, materials, lights and integrators.
#pragma once
#include "core/geometry.h"
#include "core/spectrum.h"

namespace gradus {

class Material;
class AreaLight;
class Medium;

// Media on the two sides of a surface (media/medium.h): inside is against the
// geometric normal n, outside along it. pbrt-v3: inside == outside is not a
// transition, and a ray crossing or scattering at such a surface keeps its medium.
struct MediumInterface {
    const Medium *inside = nullptr, *outside = nullptr;
    bool transition() const { return inside != outside; }
};

// Offset for spawning rays off a surface: Embree intersects in float, hits are
// refined in double; a relative epsilon of the scene scale keeps rays off the
// surface they leave (set once per scene by the scene builder).
extern Float gRayEpsilon;

// Interfaces (surfaces without a material) are crossed by re-spawning the ray;
// where the refined double hit and Embree's float triangle disagree by more
// than the spawn offset (huge triangles), the ray can hit the same interface
// again and again. Every walk ends after this many consecutive crossings.
constexpr int kMaxInterfaceCrossings = 64;

// True when d lies in the tangent plane of a surface with normal n (|cos| <
// 1e-6; false for n = 0, points not on a surface). Visibility along a
// surface's own plane is not decided by the ray tracer, and the geometry term
// of such an edge is ~0: connections and shifts give these edges no light.
inline bool InTangentPlane(const Normal3 &n, const Vec3 &d) {
    const Vec3 v(n);
    const Float n2 = v.lengthSquared();
    return n2 > 0 && Dot(v, d) * Dot(v, d) < Float(1e-12) * n2 * d.lengthSquared();
}

struct Interaction {
    Point3 p;
    Normal3 n;  // geometric normal (unit); zero for points in space / on point lights
    Vec3 wo;    // outgoing direction (unit), towards the previous vertex
    // The least distance along +-n at which rays leaving this point start: a
    // shape's own error bound where it is pbrt-v3's semantics (curves: rays
    // leave 2 widths off the hit, shapes/curve.h); 0 elsewhere.
    Float spawnOffset = 0;
    Interaction() = default;
    Interaction(const Point3 &p_, const Normal3 &n_, const Vec3 &wo_) : p(p_), n(n_), wo(wo_) {}
    bool onSurface() const { return n != Normal3(0, 0, 0); }
    Point3 offsetOrigin(const Vec3 &d) const {
        if (!onSurface()) return p;
        const Float eps = std::max(gRayEpsilon * (1 + MaxComponent(Abs(p))), spawnOffset);
        return p + (Dot(d, n) > 0 ? n : -n) * eps;
    }
    Ray spawnRay(const Vec3 &d) const { return Ray(offsetOrigin(d), d, Infinity); }
    // Ray towards p2 with tMax just short of it (d not normalized: t in [0,1)).
    Ray spawnRayTo(const Point3 &p2) const {
        Point3 o = offsetOrigin(p2 - p);
        Vec3 d = p2 - o;
        return Ray(o, d, 1 - 1e-4);
    }
    Ray spawnRayTo(const Interaction &it) const {
        Point3 o = offsetOrigin(it.p - p);
        Point3 t = it.offsetOrigin(o - it.p);
        return Ray(o, t - o, 1 - 1e-4);
    }
};

struct SurfaceInteraction : Interaction {
    Point2 uv;
    Vec3 dpdu, dpdv;
    Normal3 dndu, dndv;
    struct {
        Normal3 n;  // shading normal, same hemisphere as n
        Vec3 dpdu, dpdv;
        // pbrt-v3's convention, which bump mapping uses: for triangle meshes the
        // derivative of the interpolated (unnormalised) vertex normal, for analytic
        // shapes the object-space Weingarten derivative carried as a normal.
        Normal3 dndu, dndv;
        // Derivatives of the unit shading normal n itself, (I - n n^T) dm/du / |m| for
        // n = m / |m|, in n's orientation: what manifold walks need (manifold.h).
        // Zero where the shape does not provide them.
        Normal3 dnhatdu, dnhatdv;
    } shading;
    const Material *material = nullptr;
    const AreaLight *areaLight = nullptr;
    MediumInterface mediumInterface;  // of the surface hit (Scene::intersect)
    int geomId = -1, primId = -1;  // Embree ids (for shifts: "same surface" tests)

    // Sets the shading frame; flips the geometric normal into the shading hemisphere
    // when `orientationIsAuthoritative` is false (pbrt-v3 semantics).
    void setShadingGeometry(const Vec3 &dpdus, const Vec3 &dpdvs, const Normal3 &dndus, const Normal3 &dndvs,
                            bool orientationIsAuthoritative) {
        shading.n = Normalize(Cross(dpdus, dpdvs));
        if (orientationIsAuthoritative)
            n = FaceForward(n, shading.n);
        else
            shading.n = FaceForward(shading.n, n);
        shading.dpdu = dpdus;
        shading.dpdv = dpdvs;
        shading.dndu = dndus;
        shading.dndv = dndvs;
    }
    // The medium a ray leaving this point in direction d travels in; `current`
    // is the medium of the ray that arrived (kept where the surface is no transition).
    const Medium *mediumAfter(const Vec3 &d, const Medium *current) const {
        if (!mediumInterface.transition()) return current;
        return Dot(Vec3(n), d) > 0 ? mediumInterface.outside : mediumInterface.inside;
    }
    // Emitted radiance from an area light at this point towards w (0 if none).
    Spectrum Le(const Vec3 &w) const;
};

}  // namespace gradus
