#include "accelerators/embree_accel.h"

#include <embree3/rtcore.h>

#include <cstring>

#include "core/error.h"

namespace gradus {

namespace {

void DeviceError(void *, RTCError code, const char *str) {
    throw Error(std::string("Embree error ") + std::to_string(int(code)) + ": " + (str ? str : ""));
}

void SphereBounds(const RTCBoundsFunctionArguments *args) {
    auto *sphere = static_cast<const Sphere *>(args->geometryUserPtr);
    Bounds3 b = sphere->worldBound();
    // Conservative float bounds.
    auto lo = [](double v) { return std::nextafter(float(v), -INFINITY); };
    auto hi = [](double v) { return std::nextafter(float(v), INFINITY); };
    args->bounds_o->lower_x = lo(b.pMin.x);
    args->bounds_o->lower_y = lo(b.pMin.y);
    args->bounds_o->lower_z = lo(b.pMin.z);
    args->bounds_o->upper_x = hi(b.pMax.x);
    args->bounds_o->upper_y = hi(b.pMax.y);
    args->bounds_o->upper_z = hi(b.pMax.z);
}

// Double-precision world-space test of a user sphere against a single Embree ray.
bool SphereHit(const Sphere *s, const RTCRay &ray, Float *t) {
    Ray r(Point3(ray.org_x, ray.org_y, ray.org_z), Vec3(ray.dir_x, ray.dir_y, ray.dir_z), ray.tfar);
    Interaction hit;
    if (!s->intersectP(r, t, &hit)) return false;
    return *t > ray.tnear;
}

void SphereIntersect(const RTCIntersectFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *s = static_cast<const Sphere *>(args->geometryUserPtr);
    auto *rh = reinterpret_cast<RTCRayHit *>(args->rayhit);
    Float t;
    if (!SphereHit(s, rh->ray, &t)) return;
    rh->ray.tfar = float(t);
    rh->hit.u = 0;
    rh->hit.v = 0;
    rh->hit.Ng_x = rh->hit.Ng_y = 0;
    rh->hit.Ng_z = 1;
    rh->hit.primID = args->primID;
    rh->hit.geomID = args->geomID;
    rh->hit.instID[0] = args->context->instID[0];
}

void SphereOccluded(const RTCOccludedFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *s = static_cast<const Sphere *>(args->geometryUserPtr);
    auto *ray = reinterpret_cast<RTCRay *>(args->ray);
    Float t;
    if (SphereHit(s, *ray, &t)) ray->tfar = -INFINITY;
}

void ToRTCRay(const Ray &r, RTCRay *ray) {
    ray->org_x = float(r.o.x);
    ray->org_y = float(r.o.y);
    ray->org_z = float(r.o.z);
    ray->dir_x = float(r.d.x);
    ray->dir_y = float(r.d.y);
    ray->dir_z = float(r.d.z);
    ray->tnear = 0;
    ray->tfar = std::isinf(r.tMax) ? INFINITY : float(r.tMax);
    ray->time = 0;
    ray->mask = 0xFFFFFFFFu;
    ray->id = 0;
    ray->flags = 0;
}

}  // namespace

EmbreeAccel::EmbreeAccel() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw Error("cannot create the Embree device");
    rtcSetDeviceErrorFunction(device_, DeviceError, nullptr);
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
}

EmbreeAccel::~EmbreeAccel() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
}

int EmbreeAccel::addMesh(std::shared_ptr<const TriangleMesh> mesh) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto *v = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh->p.size()));
    for (size_t i = 0; i < mesh->p.size(); ++i) {
        v[3 * i] = float(mesh->p[i].x);
        v[3 * i + 1] = float(mesh->p[i].y);
        v[3 * i + 2] = float(mesh->p[i].z);
    }
    size_t nt = mesh->indices.size() / 3;
    auto *idx = static_cast<unsigned *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
    for (size_t i = 0; i < 3 * nt; ++i) idx[i] = unsigned(mesh->indices[i]);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene_, g, unsigned(nextId_));
    rtcReleaseGeometry(g);
    return nextId_++;
}

int EmbreeAccel::addSphere(std::shared_ptr<const Sphere> sphere) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, const_cast<Sphere *>(sphere.get()));
    rtcSetGeometryBoundsFunction(g, SphereBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, SphereIntersect);
    rtcSetGeometryOccludedFunction(g, SphereOccluded);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene_, g, unsigned(nextId_));
    rtcReleaseGeometry(g);
    spheres_.push_back(std::move(sphere));
    return nextId_++;
}

void EmbreeAccel::commit() { rtcCommitScene(scene_); }

bool EmbreeAccel::intersect(const Ray &r, RayHit *hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    ToRTCRay(r, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit->geomId = int(rh.hit.geomID);
    hit->primId = int(rh.hit.primID);
    hit->t = rh.ray.tfar;
    hit->b1 = rh.hit.u;
    hit->b2 = rh.hit.v;
    return true;
}

bool EmbreeAccel::occluded(const Ray &r) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray;
    ToRTCRay(r, &ray);
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0;
}

}  // namespace gradus
