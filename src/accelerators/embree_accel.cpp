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

void AnalyticBounds(const RTCBoundsFunctionArguments *args) {
    auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    Bounds3 b = shape->worldBound();
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

// Double-precision world-space test of an analytic shape against a single Embree ray.
bool AnalyticHit(const AnalyticShape *s, const RTCRay &ray, Float *t) {
    Ray r(Point3(ray.org_x, ray.org_y, ray.org_z), Vec3(ray.dir_x, ray.dir_y, ray.dir_z), ray.tfar);
    Interaction hit;
    if (!s->intersectP(r, t, &hit)) return false;
    return *t > ray.tnear;
}

void AnalyticIntersect(const RTCIntersectFunctionNArguments *args) {
    if (args->N != 1 || !args->valid[0]) return;
    auto *s = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    auto *rh = reinterpret_cast<RTCRayHit *>(args->rayhit);
    Float t;
    if (!AnalyticHit(s, rh->ray, &t)) return;
    rh->ray.tfar = float(t);
    rh->hit.u = 0;
    rh->hit.v = 0;
    rh->hit.Ng_x = rh->hit.Ng_y = 0;
    rh->hit.Ng_z = 1;
    rh->hit.primID = args->primID;
    rh->hit.geomID = args->geomID;
    rh->hit.instID[0] = args->context->instID[0];
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
// Tubes (round curves) are seen from outside only: a hit whose geometric normal
// (outward) faces along the ray is where a ray leaves a fibre; it is ignored,
// so rays spawned inwards off a fibre pass through it (shapes/curve.h).
void TubeExitFilter(const RTCFilterFunctionNArguments *args) {
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const float dn = RTCRayN_dir_x(args->ray, args->N, i) * RTCHitN_Ng_x(args->hit, args->N, i) +
                         RTCRayN_dir_y(args->ray, args->N, i) * RTCHitN_Ng_y(args->hit, args->N, i) +
                         RTCRayN_dir_z(args->ray, args->N, i) * RTCHitN_Ng_z(args->hit, args->N, i);
        if (dn > 0) args->valid[i] = 0;
    }
}

// Shadow rays are made symmetric: a segment that ends on a tube, arriving from
// behind it, would be blocked by that tube's own near wall (within a chord of
// the end) while the reverse segment leaves through the (ignored) inside. Such hits
// are ignored too, so bdpt's connections see what path's next-event rays see.
// The segment's end travels in an extended context (the filter's tfar is the
// candidate hit's distance).
struct OcclusionContext {
    RTCIntersectContext ctx;  // first member: Embree passes &ctx
    float segmentEnd;         // the ray's tfar before tracing (inf: no end point)
};

void TubeOccludedFilter(const RTCFilterFunctionNArguments *args) {
    TubeExitFilter(args);
    auto *curve = static_cast<const CurveShape *>(args->geometryUserPtr);
    const float end = reinterpret_cast<const OcclusionContext *>(args->context)->segmentEnd;
    if (!std::isfinite(end)) return;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const float t = RTCRayN_tfar(args->ray, args->N, i);
        const float dx = RTCRayN_dir_x(args->ray, args->N, i), dy = RTCRayN_dir_y(args->ray, args->N, i),
                    dz = RTCRayN_dir_z(args->ray, args->N, i);
        const double len = std::sqrt(double(dx) * dx + double(dy) * dy + double(dz) * dz);
        const int prim = int(RTCHitN_primID(args->hit, args->N, i));
        const double u = Clamp<double>(RTCHitN_u(args->hit, args->N, i), 0, 1), r = curve->radius(prim, u);
        // A chord of the tube is at most 2 r / sin(angle to the axis) long.
        Vec3 T;
        curve->point(prim, u, &T);
        const double tl = T.length(), sinA = tl > 0 && len > 0 ? Cross(Vec3(dx, dy, dz), T).length() / (len * tl) : 1;
        // Spawned segments stop 1e-4 of their length short of the end point.
        if ((double(end) - t) * len <= 2.05 * r / std::max(sinA, 0.05) + 2e-4 * double(end) * len)
            args->valid[i] = 0;
    }
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
    const CurveType type = curve->type();
    RTCGeometry g = rtcNewGeometry(device_, type == CurveType::Cylinder ? RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE
                                            : type == CurveType::Flat   ? RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE
                                                                        : RTC_GEOMETRY_TYPE_NORMAL_ORIENTED_BEZIER_CURVE);
    const auto &segs = curve->segments();
    const size_t ns = segs.size();
    auto *v = static_cast<float *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 4 * ns));
    auto *idx = static_cast<unsigned *>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), ns));
    float *nb = nullptr;
    if (type == CurveType::Ribbon)
        nb = static_cast<float *>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4 * ns));
    for (size_t s = 0; s < ns; ++s) {
        idx[s] = unsigned(4 * s);
        for (int i = 0; i < 4; ++i) {
            float *q = v + 4 * (4 * s + i);
            const Point3 &p = segs[s].cp[i];
            q[0] = float(p.x), q[1] = float(p.y), q[2] = float(p.z);
            // Bezier control radii in arithmetic progression: radius linear in u.
            q[3] = float(Lerp(i / 3.0, segs[s].r0, segs[s].r1));
            if (nb) {
                const Normal3 n = curve->ribbonNormal(int(s), i / 3.0);
                float *m = nb + 3 * (4 * s + i);
                m[0] = float(n.x), m[1] = float(n.y), m[2] = float(n.z);
            }
        }
    }
    if (type == CurveType::Flat) rtcSetGeometryTessellationRate(g, 16);
    if (type == CurveType::Cylinder) {
        rtcSetGeometryUserData(g, const_cast<CurveShape *>(curve.get()));
        rtcSetGeometryIntersectFilterFunction(g, TubeExitFilter);
        rtcSetGeometryOccludedFilterFunction(g, TubeOccludedFilter);
    }
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
    OcclusionContext octx;
    RTCIntersectContext &ctx = octx.ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay ray;
    ToRTCRay(r, &ray);
    octx.segmentEnd = ray.tfar;
    if (!Traceable(ray)) {
        GRADUS_STAT_COUNTER("Embree/Untraceable rays dropped", nBad);
        ++nBad;
        return true;
    }
    rtcOccluded1(scene_, &ctx, &ray);
    return ray.tfar < 0;
}

}  // namespace gradus
