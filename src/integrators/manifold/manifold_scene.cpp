#include "integrators/manifold/manifold_scene.h"

namespace gradus {

EmbreeManifoldScene::EmbreeManifoldScene(const Scene &scene) : scene_(scene), nGeom_(scene.geometry.size()) {
    Point3 c;
    Float r = 0;
    scene.bounds.boundingSphere(&c, &r);
    eps_ = std::isfinite(r) && r > 0 ? 1e-6 * r : 1e-6;
    eta_.reset(new std::atomic<float>[nGeom_ ? nGeom_ : 1]);
    extent_.assign(nGeom_, Infinity);
    for (size_t i = 0; i < nGeom_; ++i) {
        eta_[i] = 1.f;
        const GeometryRecord &g = scene.geometry[i];
        if (g.mesh && !g.placement) {
            Bounds3 b;
            for (const Point3 &p : g.mesh->p) b.expand(p);
            if (!b.empty()) extent_[i] = b.diagonal().length();
        } else if (g.analytic) {
            Bounds3 b = g.analytic->worldBound();
            if (!b.empty()) extent_[i] = b.diagonal().length();
        }
        for (const AreaLight *l : scene.geometry[i].areaLights)
            if (l) lightGeom_.emplace(static_cast<const Light *>(l), int(i));
    }
}

int EmbreeManifoldScene::geomOfLight(const Light *l) const {
    auto it = lightGeom_.find(l);
    return it == lightGeom_.end() ? -1 : it->second;
}

ManifoldSurfacePoint EmbreeManifoldScene::fromInteraction(const SurfaceInteraction &si) const {
    ManifoldSurfacePoint sp;
    sp.p = si.p;
    sp.n = si.shading.n;
    sp.ng = si.n;
    sp.dpdu = si.dpdu;
    sp.dpdv = si.dpdv;
    sp.dndu = Vec3(si.shading.dnhatdu);
    sp.dndv = Vec3(si.shading.dnhatdv);
    sp.etaExterior = 1;
    sp.etaInterior = eta(si.geomId);
    sp.primitiveId = si.geomId;
    return sp;
}

bool EmbreeManifoldScene::intersect(const Ray &r, ManifoldSurfacePoint *hit) const {
    Vec3 d = Normalize(r.d);
    SurfaceInteraction si;
    // Skip the surface the ray starts on (the walk starts rays on chain vertices).
    if (!scene_.intersect(Ray(r.o + d * eps_, d, r.tMax), &si)) return false;
    *hit = fromInteraction(si);
    return true;
}

bool EmbreeManifoldScene::visible(const Point3 &a, const Point3 &b) const {
    Vec3 d = b - a;
    Float len = d.length();
    if (!(len > 2 * eps_)) return true;
    d = d / len;
    return !scene_.occluded(Ray(a + d * eps_, d, len - 2 * eps_));
}

Float EmbreeManifoldScene::extent(int geomId) const {
    return geomId >= 0 && size_t(geomId) < nGeom_ ? extent_[size_t(geomId)] : Infinity;
}

Float EmbreeManifoldScene::eta(int geomId) const {
    return geomId >= 0 && size_t(geomId) < nGeom_ ? Float(eta_[geomId].load(std::memory_order_relaxed)) : 1;
}

void EmbreeManifoldScene::recordEta(int geomId, Float eta) const {
    if (geomId >= 0 && size_t(geomId) < nGeom_ && eta > 0 && eta != 1)
        eta_[geomId].store(float(eta), std::memory_order_relaxed);
}

}  // namespace gradus
