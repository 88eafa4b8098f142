#include "accelerators/embree_accel.h"

#include "core/stats.h"

#include <algorithm>
#include <embree3/rtcore.h>

#include <cmath>
#include <cstring>

#include "core/error.h"

namespace gradus {

namespace {

void DeviceError(void *, RTCError code, const char *str) {
    throw Error(std::string("Embree error ") + std::to_string(int(code)) + ": " + (str ? str : ""));
}

// Conservative float bounds of a user primitive.
void SetUserBounds(const RTCBoundsFunctionArguments *args, const Bounds3 &b) {
    auto lo = [](double v) { return std::nextafter(float(v), -INFINITY); };
    auto hi = [](double v) { return std::nextafter(float(v), INFINITY); };
    args->bounds_o->lower_x = lo(b.pMin.x);
    args->bounds_o->lower_y = lo(b.pMin.y);
    args->bounds_o->lower_z = lo(b.pMin.z);
    args->bounds_o->upper_x = hi(b.pMax.x);
    args->bounds_o->upper_y = hi(b.pMax.y);
    args->bounds_o->upper_z = hi(b.pMax.z);
}

void AnalyticBounds(const RTCBoundsFunctionArguments *args) {
    SetUserBounds(args, static_cast<const AnalyticShape *>(args->geometryUserPtr)->worldBound());
}

// Double-precision world-space test of an analytic shape against a single Embree ray.
bool AnalyticHit(const AnalyticShape *s, const RTCRay &ray, Float *t) {
    Ray r(Point3(ray.org_x, ray.org_y, ray.org_z), Vec3(ray.dir_x, ray.dir_y, ray.dir_z), ray.tfar);
    Interaction hit;
    if (!s->intersectP(r, t, &hit)) return false;
    return *t > ray.tnear;
}

// Records a user primitive's hit at t with (u, v) and the normal n.
void SetUserHit(const RTCIntersectFunctionNArguments *args, RTCRayHit *rh, Float t, Float u, Float v, float nx,
                float ny, float nz) {
    rh->ray.tfar = float(t);
    rh->hit.u = float(u);
    rh->hit.v = float(v);
    rh->hit.Ng_x = nx;
    rh->hit.Ng_y = ny;
    rh->hit.Ng_z = nz;
    rh->hit.primID = args->primID;
    rh->hit.geomID = args->geomID;
    rh->hit.instID[0] = args->context->instID[0];
}

void AnalyticIntersect(const RTCIntersectFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *s = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    auto *rh = reinterpret_cast<RTCRayHit *>(args->rayhit);
    Float t;
    if (!AnalyticHit(s, rh->ray, &t)) return;
    SetUserHit(args, rh, t, 0, 0, 0, 0, 1);
}

void AnalyticOccluded(const RTCOccludedFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *s = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    auto *ray = reinterpret_cast<RTCRay *>(args->ray);
    Float t;
    if (AnalyticHit(s, *ray, &t)) ray->tfar = -INFINITY;
}

// Alpha cut-outs (pbrt-v3 semantics): a hit where the alpha texture is exactly
// 0 is ignored; shadow rays also ignore hits where "shadowalpha" is 0.
void AlphaFilter(const RTCFilterFunctionNArguments *args, bool shadow) {
    auto *mesh = static_cast<const TriangleMesh *>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        Float b1 = RTCHitN_u(args->hit, args->N, i), b2 = RTCHitN_v(args->hit, args->N, i);
        Vec3 d(RTCRayN_dir_x(args->ray, args->N, i), RTCRayN_dir_y(args->ray, args->N, i),
               RTCRayN_dir_z(args->ray, args->N, i));
        SurfaceInteraction si;
        mesh->interaction(int(prim), b1, b2, -Normalize(d), &si);
        bool cut = (mesh->alpha && mesh->alpha->evaluate(si) == 0) ||
                   (shadow && mesh->shadowAlpha && mesh->shadowAlpha->evaluate(si) == 0);
        if (cut) args->valid[i] = 0;
    }
}
// Curves (shapes/curve.h): one user primitive per piece, pbrt-v3's test in
// double precision; the hit's (u, v) travel in RayHit::b1, b2.
void CurveBounds(const RTCBoundsFunctionArguments *args) {
    SetUserBounds(args, static_cast<const CurveShape *>(args->geometryUserPtr)->pieceBound(int(args->primID)));
}

bool CurveHit(const CurveShape *c, unsigned prim, const RTCRay &ray, Float *t, Float *u, Float *v) {
    const Ray r(Point3(ray.org_x, ray.org_y, ray.org_z), Vec3(ray.dir_x, ray.dir_y, ray.dir_z), ray.tfar);
    return c->intersect(int(prim), r, t, u, v) && *t >= ray.tnear && *t < ray.tfar;
}

void CurveIntersect(const RTCIntersectFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *c = static_cast<const CurveShape *>(args->geometryUserPtr);
    auto *rh = reinterpret_cast<RTCRayHit *>(args->rayhit);
    Float t, u, v;
    if (!CurveHit(c, args->primID, rh->ray, &t, &u, &v)) return;
    SetUserHit(args, rh, t, u, v, -rh->ray.dir_x, -rh->ray.dir_y, -rh->ray.dir_z);
}

void CurveOccluded(const RTCOccludedFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *c = static_cast<const CurveShape *>(args->geometryUserPtr);
    auto *ray = reinterpret_cast<RTCRay *>(args->ray);
    Float t, u, v;
    if (CurveHit(c, args->primID, *ray, &t, &u, &v)) ray->tfar = -INFINITY;
}

void AlphaIntersectFilter(const RTCFilterFunctionNArguments *args) { AlphaFilter(args, false); }
void AlphaOccludedFilter(const RTCFilterFunctionNArguments *args) { AlphaFilter(args, true); }

// Returns the factor s by which the direction was scaled: Embree refuses
// directions above ~1.8e18 (and float loses ones below ~1e-38), so a direction
// outside [1e-8, 1e8] is normalised, with tfar / s; a hit's t is t_embree * s.
double ToRTCRay(const Ray &r, RTCRay *ray) {
    const double m = std::max({std::abs(r.d.x), std::abs(r.d.y), std::abs(r.d.z)});
    const double s = (m > 1e8 || (m > 0 && m < 1e-8)) && std::isfinite(m) ? 1 / m : 1;
    ray->org_x = float(r.o.x);
    ray->org_y = float(r.o.y);
    ray->org_z = float(r.o.z);
    ray->dir_x = float(r.d.x * s);
    ray->dir_y = float(r.d.y * s);
    ray->dir_z = float(r.d.z * s);
    ray->tnear = 0;
    ray->tfar = std::isinf(r.tMax) ? INFINITY : float(r.tMax / s);
    ray->time = 0;
    ray->mask = 0xFFFFFFFFu;
    ray->id = 0;
    ray->flags = 0;
    return s;
}

// Embree asserts (and aborts) on rays it cannot trace: non-finite origins or
// directions, origins beyond ~1.8e18, a NaN or negative tfar. Such rays come
// only from degenerate input (near-singular transforms, overflowing geometry):
// they are dropped - a miss for closest hits, blocked for shadow rays - and counted.
// (Directions are scaled into range by ToRTCRay; the bound is Embree's.)
bool Traceable(const RTCRay &r) {
    constexpr float kMax = 1e18f;
    auto ok = [](float v, float lim) { return std::abs(v) < lim; };  // false for NaN and Inf
    return ok(r.org_x, kMax) && ok(r.org_y, kMax) && ok(r.org_z, kMax) && ok(r.dir_x, kMax) && ok(r.dir_y, kMax) &&
           ok(r.dir_z, kMax) && (r.dir_x != 0 || r.dir_y != 0 || r.dir_z != 0) && r.tfar >= r.tnear;
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
    for (Object &o : objects_) rtcReleaseScene(o.scene);
    if (device_) rtcReleaseDevice(device_);
}

namespace {

// A committed Embree triangle geometry holding the mesh's positions (float).
RTCGeometry NewTriangleGeometry(RTCDevice device, const TriangleMesh &mesh) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto *v = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.p.size()));
    for (size_t i = 0; i < mesh.p.size(); ++i) {
        v[3 * i] = float(mesh.p[i].x);
        v[3 * i + 1] = float(mesh.p[i].y);
        v[3 * i + 2] = float(mesh.p[i].z);
    }
    size_t nt = mesh.indices.size() / 3;
    auto *idx = static_cast<unsigned *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nt));
    for (size_t i = 0; i < 3 * nt; ++i) idx[i] = unsigned(mesh.indices[i]);
    return g;
}

}  // namespace

int EmbreeAccel::attachTop(void *geometry, int records) {
    RTCGeometry g = static_cast<RTCGeometry>(geometry);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene_, g, unsigned(nextId_++));
    rtcReleaseGeometry(g);
    const int first = nextRecord_;
    recordOfTop_.push_back(first);
    nextRecord_ += records;
    return first;
}

int EmbreeAccel::addMesh(std::shared_ptr<const TriangleMesh> mesh) {
    RTCGeometry g = NewTriangleGeometry(device_, *mesh);
    if (mesh->alpha || mesh->shadowAlpha) {
        rtcSetGeometryUserData(g, const_cast<TriangleMesh *>(mesh.get()));
        rtcSetGeometryIntersectFilterFunction(g, AlphaIntersectFilter);
        rtcSetGeometryOccludedFilterFunction(g, AlphaOccludedFilter);
        alphaMeshes_.push_back(mesh);
    }
    return attachTop(g, 1);
}

int EmbreeAccel::addAnalytic(std::shared_ptr<const AnalyticShape> shape) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, const_cast<AnalyticShape *>(shape.get()));
    rtcSetGeometryBoundsFunction(g, AnalyticBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, AnalyticIntersect);
    rtcSetGeometryOccludedFunction(g, AnalyticOccluded);
    analytic_.push_back(std::move(shape));
    return attachTop(g, 1);
}

int EmbreeAccel::addCurve(std::shared_ptr<const CurveShape> curve) {
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, unsigned(curve->numPieces()));
    rtcSetGeometryUserData(g, const_cast<CurveShape *>(curve.get()));
    rtcSetGeometryBoundsFunction(g, CurveBounds, nullptr);
    rtcSetGeometryIntersectFunction(g, CurveIntersect);
    rtcSetGeometryOccludedFunction(g, CurveOccluded);
    curves_.push_back(std::move(curve));
    return attachTop(g, 1);
}

int EmbreeAccel::newObject() {
    Object o;
    o.scene = rtcNewScene(device_);
    rtcSetSceneBuildQuality(o.scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(o.scene, RTC_SCENE_FLAG_ROBUST);
    objects_.push_back(std::move(o));
    return int(objects_.size()) - 1;
}

void EmbreeAccel::addObjectMesh(int object, std::shared_ptr<const TriangleMesh> mesh) {
    Object &o = objects_.at(size_t(object));
    if (o.committed) throw Error("internal: mesh added to an object already instanced");
    if (mesh->alpha || mesh->shadowAlpha) throw Error("internal: alpha cut-outs in an instanced object");
    RTCGeometry g = NewTriangleGeometry(device_, *mesh);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(o.scene, g, unsigned(o.meshes.size()));  // geomID = index in the object
    rtcReleaseGeometry(g);
    o.meshes.push_back(std::move(mesh));
}

int EmbreeAccel::objectMeshCount(int object) const { return int(objects_.at(size_t(object)).meshes.size()); }

int EmbreeAccel::addInstance(int object, const Transform &worldFromObject) {
    Object &o = objects_.at(size_t(object));
    if (!o.committed) {
        rtcCommitScene(o.scene);
        o.committed = true;
    }
    RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, o.scene);
    rtcSetGeometryTimeStepCount(g, 1);
    // Embree's 3x4 column-major float layout; the renderer's interactions use
    // the double transform (GeometryRecord::placement), as it uses double
    // positions for world meshes traced in float.
    const Matrix4 &m = worldFromObject.matrix();
    float xfm[12];
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) xfm[3 * c + r] = float(m.m[r][c]);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
    return attachTop(g, int(o.meshes.size()));
}

void EmbreeAccel::commit() { rtcCommitScene(scene_); }

bool EmbreeAccel::intersect(const Ray &r, RayHit *hit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    const double scale = ToRTCRay(r, &rh.ray);
    if (!Traceable(rh.ray)) {
        GRADUS_STAT_COUNTER("Embree/Untraceable rays dropped", nBad);
        ++nBad;
        return false;
    }
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    // An instance hit: instID[0] is the instance's top-level id, geomID the mesh within its object.
    const bool inInstance = rh.hit.instID[0] != RTC_INVALID_GEOMETRY_ID;
    const unsigned top = inInstance ? rh.hit.instID[0] : rh.hit.geomID;
    hit->geomId = recordOfTop_[top] + (inInstance ? int(rh.hit.geomID) : 0);
    hit->primId = int(rh.hit.primID);
    hit->t = rh.ray.tfar * scale;
    hit->b1 = rh.hit.u;
    hit->b2 = rh.hit.v;
    return true;
}

bool EmbreeAccel::occluded(const Ray &r) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray;
    ToRTCRay(r, &ray);
    if (!Traceable(ray)) {
        GRADUS_STAT_COUNTER("Embree/Untraceable rays dropped", nBad);
        ++nBad;
        return true;
    }
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0;
}

}  // namespace gradus
