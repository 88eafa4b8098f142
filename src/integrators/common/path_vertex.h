// Compact path vertices shared by the bidirectional integrators (BDPT, and the
// base for M-BDPT, G-BDPT, VCM, MLT).
//
// Storage choice: a vertex holds no pointer into a per-sample arena. It keeps
// what a connection needs (position, geometric and shading normals, wo,
// throughput, area-measure pdfs, flags) plus the Embree (geomId, primId) and
// the triangle barycentrics, from which RebuildBSDF() (bidir.h) recreates the
// full SurfaceInteraction and the material's BSDF. Integrators that connect
// within one sample (BDPT) keep the BSDFs built during the random walk in a
// parallel array (SubpathView::bsdf) and never rebuild; integrators that store
// vertices across an iteration (M-BDPT, VCM) store PathVertex only and rebuild
// the BSDF of a stored vertex when they connect/merge with it.
// Normals and directions are unit vectors stored in float (enough for cosines
// and BSDF frames); the position stays double (ray offsets, short edges).
// Media (pbrt-v3's BDPT, PBR 3rd ed. Sec. 16.3): a scattering point in a
// medium is a Medium vertex holding its medium (phase function); a surface
// vertex keeps the index of the medium its ray arrived in (mediumIndex), from
// which, with its shape's MediumInterface, a connecting ray's medium follows
// (MediumTowards, bidir.h). 120 bytes as without media.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "core/geometry.h"
#include "core/spectrum.h"
#include "materials/bsdf.h"

namespace gradus {

class Light;
class Material;
class Medium;

struct PackedVec3 {
    float x = 0, y = 0, z = 0;
    PackedVec3() = default;
    PackedVec3(const Vec3 &v) : x(float(v.x)), y(float(v.y)), z(float(v.z)) {}
    operator Vec3() const { return Vec3(x, y, z); }
    bool isZero() const { return x == 0 && y == 0 && z == 0; }
};

enum class VertexType : uint8_t { Camera, Light, Surface, Medium };

enum VertexFlags : uint8_t {
    VERTEX_DELTA = 1,        // the direction sampled at this vertex was a specular (delta) lobe
    VERTEX_DELTA_LIGHT = 2,  // light vertex of a delta-position or delta-direction light
    VERTEX_INFINITE = 4,     // light vertex of an infinite or distant light (direction only)
    VERTEX_SPAWN_OFFSET = 8, // surface vertex with Interaction::spawnOffset (curves), kept in b2
};

// Throughputs are stored as float with a power-of-two exponent: the
// components keep float's 24-bit precision, the range is double's. A plain
// float overflowed for light subpaths above 3.4e38 (an environment of radiance
// 1e28 over a scene of radius 1e5: every such sample was discarded as
// non-finite). Values within [1e-30, 1e30] take exponent 0 (no scaling).
// The exponent is stored in units of 8 (one byte: 2^(8 e), |8 e| <= 1016 covers
// double's range; the scaled maximum stays within [2^-1, 2^8]).
inline int PackThroughput(const Spectrum &s, float out[3]) {
    const double m = std::max({std::abs(s.r), std::abs(s.g), std::abs(s.b)});
    int e = 0;
    if (std::isfinite(m) && m > 0 && (m > 1e30 || m < 1e-30)) {
        std::frexp(m, &e);
        e = std::clamp(e >= 0 ? e / 8 : -((-e + 7) / 8), -127, 127);  // floor(e / 8)
    }
    const double scale = e ? std::ldexp(1.0, -8 * e) : 1.0;
    out[0] = float(s.r * scale);
    out[1] = float(s.g * scale);
    out[2] = float(s.b * scale);
    return e;
}
inline Spectrum UnpackThroughput(const float b[3], int e) {
    const Spectrum s(b[0], b[1], b[2]);
    return e ? s * std::ldexp(1.0, 8 * e) : s;
}

struct PathVertex {
    Point3 p;                 // position (for infinite-light vertices: a point along the direction)
    PackedVec3 ng;            // geometric normal (zero for point lights; infinite: towards the scene)
    PackedVec3 ns;            // shading normal (after bump mapping)
    PackedVec3 wo;            // unit direction towards the previous vertex of its own subpath
    float beta[3] = {0, 0, 0};// subpath throughput up to and including this vertex, times 2^(-8 betaExp)
    Float pdfFwd = 0;         // area density of generating this vertex from its own subpath
    Float pdfRev = 0;         // area density of generating it from the opposite direction
    union {
        const Material *material;  // Surface
        const Light *light;        // Light (nullptr for the infinite vertex of an escaped camera path)
        const Medium *medium;      // Medium: the medium scattered in (its phase function)
    };
    int32_t geomId = -1, primId = -1;
    float b1 = 0, b2 = 0;     // triangle barycentrics (RebuildBSDF); b2: VERTEX_SPAWN_OFFSET's offset
    VertexType type = VertexType::Surface;
    uint8_t flags = 0;
    // 1 / continuation probability of Russian roulette applied to the
    // throughput after this vertex (1: no roulette here). Shifts that re-derive
    // an offset's throughput from BSDF ratios multiply it back in (the offset
    // reuses the base's roulette decisions; camera_shift.cpp). Fits the padding.
    int8_t betaExp = 0;       // beta's power-of-two exponent / 8 (PackThroughput)
    // Surface: 1 + index in Scene::media of the medium the vertex was reached
    // in (0: none); Medium: that of its own medium. Unused at other vertices.
    uint8_t mediumIndex = 0;
    float rrScale = 1;

    PathVertex() : material(nullptr) {}

    Spectrum throughput() const { return UnpackThroughput(beta, betaExp); }
    void setThroughput(const Spectrum &s) { betaExp = PackThroughput(s, beta); }
    bool delta() const { return flags & VERTEX_DELTA; }
    bool isInfiniteLight() const { return type == VertexType::Light && (flags & VERTEX_INFINITE); }
    bool isDeltaLight() const { return type == VertexType::Light && (flags & VERTEX_DELTA_LIGHT); }
    // Area-measure conversions use the cosine at vertices that lie on a surface.
    bool onSurface() const {
        return type == VertexType::Surface || (type == VertexType::Light && !isInfiniteLight() && !ng.isZero());
    }
    bool inMedium() const { return type == VertexType::Medium; }
    // Surface or medium: a vertex that scatters (BSDF or phase function).
    bool scatters() const { return type == VertexType::Surface || type == VertexType::Medium; }
};

// One subpath: vertices and (optionally) the BSDFs of its surface vertices.
// bsdf may be nullptr for stored subpaths; the connection code then needs
// rebuilt BSDFs (see RebuildBSDF) passed through a view that has them.
struct SubpathView {
    const PathVertex *v = nullptr;
    const BSDF *bsdf = nullptr;
    int n = 0;
};

// The fields every compact copy of a vertex keeps (connection records, VCM's
// light vertices), copied either way: position, normals, wo, the packed
// throughput, the surface and the medium.
template <class From, class To>
void CopyVertexCore(const From &f, To &t) {
    t.p = f.p;
    t.ng = f.ng;
    t.ns = f.ns;
    t.wo = f.wo;
    t.beta[0] = f.beta[0], t.beta[1] = f.beta[1], t.beta[2] = f.beta[2];
    t.betaExp = f.betaExp;
    t.geomId = f.geomId;
    t.mediumIndex = f.mediumIndex;
}

}  // namespace gradus
