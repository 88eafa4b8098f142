#include "scene/scene.h"

#include <sstream>

#include "core/stats.h"

namespace gradus {

Float gRayEpsilon = 1e-6;

Spectrum SurfaceInteraction::Le(const Vec3 &w) const {
    return areaLight ? areaLight->L(*this, w) : Spectrum(0);
}

Scene::Scene() = default;
Scene::~Scene() = default;

bool Scene::intersect(const Ray &r, SurfaceInteraction *si) const {
    GRADUS_STAT_COUNTER("Rays/Closest-hit rays", nRays);
    ++nRays;
    RayHit h;
    if (!accel.intersect(r, &h)) return false;
    const GeometryRecord &g = geometry[h.geomId];
    Float dlen = r.d.length();
    Vec3 wo = -r.d / dlen;
    if (g.mesh) {
        Float b1 = h.b1, b2 = h.b2;
        g.mesh->refineBarycentrics(h.primId, r, &b1, &b2, g.placement);
        g.meshInteraction(h.primId, b1, b2, wo, si);
    } else if (g.curve) {
        g.curve->interaction(h.primId, h.b1, h.b2, r(h.t), wo, si);
    } else {
        // Refine the analytic hit in double precision along the original ray.
        Float t;
        Interaction tmp;
        if (!g.analytic->intersectP(r, &t, &tmp)) t = h.t;
        g.analytic->interaction(r, t, si);
    }
    si->material = g.material;
    si->areaLight = g.areaLights.empty() ? nullptr : g.areaLights[h.primId];
    si->geomId = h.geomId;
    si->primId = h.primId;
    si->mediumInterface = g.mediumInterface;
    return true;
}

Scene::SurfaceHit Scene::intersectSurface(Ray *ray, SurfaceInteraction *si) const {
    bool hit = intersect(*ray, si);
    for (int k = 0; hit && !si->material && k < kMaxInterfaceCrossings; ++k) {
        *ray = si->spawnRay(ray->d);
        hit = intersect(*ray, si);
    }
    return !hit ? SurfaceHit::Miss : si->material ? SurfaceHit::Hit : SurfaceHit::Stuck;
}

bool Scene::occluded(const Ray &r) const {
    GRADUS_STAT_COUNTER("Rays/Shadow rays", nShadow);
    ++nShadow;
    return accel.occluded(r);
}

Spectrum Scene::transmittance(const Interaction &a, const Medium *ma, const Interaction &b, UniformSource rng) const {
    if (!features.media) return unoccluded(a, b) ? Spectrum(1) : Spectrum(0);
    GRADUS_STAT_COUNTER("Rays/Transmittance rays", nTr);
    ++nTr;
    Spectrum tr(1);
    Interaction from = a;
    const Medium *medium = ma;
    for (int k = 0; k <= kMaxInterfaceCrossings; ++k) {
        Ray ray = from.spawnRayTo(b);
        SurfaceInteraction si;
        const bool hit = intersect(ray, &si);
        if (hit && si.material) return Spectrum(0);  // an opaque or scattering surface in between
        if (medium) {
            // The segment up to the interface (or to b): t in units of |ray.d|.
            Ray seg = ray;
            if (hit) seg.tMax = Dot(si.p - ray.o, ray.d) / ray.d.lengthSquared();
            tr *= medium->Tr(seg, rng);
            if (tr.isBlack()) return tr;
        }
        if (!hit) return tr;
        medium = si.mediumAfter(ray.d, medium);
        from = si;
    }
    return Spectrum(0);  // stuck between interfaces
}

std::string SceneFeatures::describe() const {
    std::ostringstream os;
    auto yn = [](bool b) { return b ? "yes" : "no"; };
    os << "Scene features:\n"
       << "  triangles: " << numTriangles << " (stored: " << numStoredTriangles << ", in " << numInstances
       << " instances: " << numInstancedTriangles << "), spheres: " << numSpheres << ", other analytic shapes: " << numAnalytic
       << ", curve segments: " << numCurveSegments << ", lights: " << numLights << "\n"
       << "  specular surfaces: " << yn(specularSurfaces) << "\n"
       << "  near-specular surfaces (roughness < " << kDefaultShiftThreshold << "): " << yn(nearSpecularSurfaces) << "\n"
       << "  lowest material roughness: " << minRoughness << "\n"
       << "  delta lights: " << yn(deltaLights) << ", infinite lights: " << yn(infiniteLights)
       << ", area lights: " << yn(areaLights) << "\n"
       << "  textures: " << yn(textures) << ", subdivision surfaces: " << yn(subdivisionSurfaces) << "\n"
       << "  participating media: " << yn(media) << ", subsurface scattering: " << yn(subsurface) << "\n"
       << "  emitters directly visible: " << yn(emittersDirectlyVisible) << "\n";
    return os.str();
}

}  // namespace gradus
