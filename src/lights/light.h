// Lights. Every light can be sampled from a reference point (next-event
// estimation) and can emit (light subpaths), with the matching pdfs in
// area/solid-angle measure that bidirectional MIS needs.
#pragma once
#include <memory>
#include <string>

#include "core/transform.h"
#include "parser/scene_desc.h"
#include "core/interaction.h"
#include "shapes/shape.h"

namespace gradus {

enum LightFlags : int {
    LIGHT_DELTA_POSITION = 1,
    LIGHT_DELTA_DIRECTION = 2,
    LIGHT_AREA = 4,
    LIGHT_INFINITE = 8,
};
inline bool IsDeltaLight(int flags) { return flags & (LIGHT_DELTA_POSITION | LIGHT_DELTA_DIRECTION); }

struct LightLiSample {
    Spectrum L;          // incident radiance at ref (before visibility)
    Vec3 wi;             // unit direction from ref towards the light
    Float pdf = 0;       // solid angle at ref (delta lights: 1)
    Interaction pLight;  // sampled point (for infinite lights: far along wi, n = -wi)
};

struct LightLeSample {
    Spectrum L;
    Ray ray;             // unit direction
    Point3 p;            // the emitter point: on the surface (area lights offset ray.o from it), else ray.o
    Normal3 nLight;      // surface normal at the origin (zero for point lights)
    Float pdfPos = 0;    // area measure (delta position: 1; infinite: disk area measure)
    Float pdfDir = 0;    // solid angle (delta direction: 1)
};

class Light {
  public:
    Light(int flags, const Transform &worldFromLight) : flags(flags), worldFromLight(worldFromLight) {}
    virtual ~Light() = default;
    const int flags;
    const Transform worldFromLight;
    // The media around the light (scene builder): point, spot, goniometric and
    // projection lights sit in `outside`; an area light has its shape's
    // interface; infinite and distant lights have none.
    MediumInterface mediumInterface;
    // Samples per hit in directlighting's "all" strategy (pbrt-v3's "samples"
    // of area and infinite lights; 1 for the others).
    int nSamples = 1;

    virtual Spectrum power() const = 0;
    virtual void preprocess(const Bounds3 &sceneBounds) {}
    virtual bool sampleLi(const Interaction &ref, Point2 u, LightLiSample *s) const = 0;
    virtual Float pdfLi(const Interaction &ref, const Vec3 &wi) const = 0;
    // Radiance carried by an escaped ray (infinite lights only).
    virtual Spectrum Le(const Ray &r) const { return Spectrum(0); }
    virtual bool sampleLe(Point2 u1, Point2 u2, LightLeSample *s) const = 0;
    virtual void pdfLe(const Ray &ray, const Normal3 &nLight, Float *pdfPos, Float *pdfDir) const = 0;
    // pdfLe's positional density alone, for callers that need no directional
    // one (an infinite light then skips its direction's map lookup).
    virtual Float pdfLePosition(const Ray &ray, const Normal3 &nLight) const {
        Float pdfPos, pdfDir;
        pdfLe(ray, nLight, &pdfPos, &pdfDir);
        return pdfPos;
    }
};

// Diffuse area light attached to one shape primitive.
class AreaLight : public Light {
  public:
    AreaLight(std::shared_ptr<const Shape> shape, const Spectrum &Lemit, bool twoSided)
        : Light(LIGHT_AREA, Transform()), shape_(std::move(shape)), Lemit_(Lemit), twoSided_(twoSided) {}
    // Emitted radiance at a point with normal n towards w.
    Spectrum L(const Interaction &it, const Vec3 &w) const {
        return (twoSided_ || Dot(it.n, w) > 0) ? Lemit_ : Spectrum(0);
    }
    Spectrum power() const override { return Lemit_ * ((twoSided_ ? 2 : 1) * shape_->area() * Pi); }
    bool sampleLi(const Interaction &ref, Point2 u, LightLiSample *s) const override;
    Float pdfLi(const Interaction &ref, const Vec3 &wi) const override { return shape_->pdfFrom(ref, wi); }
    bool sampleLe(Point2 u1, Point2 u2, LightLeSample *s) const override;
    void pdfLe(const Ray &ray, const Normal3 &nLight, Float *pdfPos, Float *pdfDir) const override;
    const Shape &shape() const { return *shape_; }
    bool twoSided() const { return twoSided_; }

  private:
    std::shared_ptr<const Shape> shape_;
    Spectrum Lemit_;
    bool twoSided_;
};

class Image;
// Environment light (lat-long map, or constant L when map is null); used by
// CreateLight and by tests that build a map in memory.
std::shared_ptr<Light> CreateInfiniteLight(const Transform &worldFromLight, const Spectrum &L, const Image *map);

// Creates a LightSource of pbrt-v3 type desc.type (point, spot, distant,
// infinite; goniometric and projection give UnsupportedError).
std::shared_ptr<Light> CreateLight(const LightDesc &desc, const SceneDesc &scene);

}  // namespace gradus
