// Participating media (pbrt-v3's `homogeneous` and `heterogeneous`), the
// Henyey-Greenstein phase function and the medium interfaces of surfaces.
//
// Conventions (pbrt-v3's): sigma_a, sigma_s are per unit of world distance;
// a medium is attached to rays by the integrator (Ray carries none): every
// ray segment knows the medium it travels in. A surface's MediumInterface
// names the media inside (against the geometric normal n) and outside (along
// n); a surface whose interface is not a transition (inside == outside, or no
// MediumInterface given) keeps the medium of the ray that hit it.
// Random numbers: distance sampling and transmittance estimates draw from a
// UniformSource (delta and ratio tracking take an unbounded number of them):
// an RNG the integrator seeds per sample, never the pixel sampler's
// dimensions, or mlt's primary samples (samplers/uniform_source.h).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "core/interaction.h"
#include "core/spectrum.h"
#include "core/transform.h"
#include "samplers/rng.h"
#include "samplers/uniform_source.h"

namespace gradus {

struct MediumDesc;

// Henyey-Greenstein phase function (pbrt-v3's convention: wo and wi both point
// away from the scattering point; g > 0 is forward scattering, i.e. wi near -wo).
struct HGPhase {
    Float g = 0;
    // Phase function value (= its pdf: HG is sampled exactly).
    Float p(const Vec3 &wo, const Vec3 &wi) const;
    // Samples wi; returns p(wo, wi) (also the pdf).
    Float sample(const Vec3 &wo, Point2 u, Vec3 *wi) const;
};
// HG density of the cosine between the propagation direction and the scattered one.
Float HenyeyGreenstein(Float cosTheta, Float g);

// A point in a medium where a ray scattered.
struct MediumInteraction : Interaction {
    const class Medium *medium = nullptr;
    HGPhase phase;
    bool valid() const { return medium != nullptr; }
};

class Medium {
  public:
    virtual ~Medium() = default;
    // Transmittance along ray from t = 0 to ray.tMax (ray.d need not be unit;
    // t is in units of |d|). Unbiased estimate (exact for homogeneous media).
    virtual Spectrum Tr(const Ray &ray, UniformSource rng) const = 0;
    // Samples a scattering point along ray in [0, ray.tMax) (pbrt-v3's
    // Medium::Sample). Returns the throughput factor: Tr * sigma_s / pdf when
    // *mi was filled (mi->medium set), Tr / P(no scattering) otherwise.
    virtual Spectrum sample(const Ray &ray, UniformSource rng, MediumInteraction *mi) const = 0;
    // True when sigma_t is the same in every channel.
    virtual bool greySigmaT() const = 0;
    // Point queries for the gradient-domain shifts (integrators/gradient/medium_shift.h).
    virtual bool homogeneous() const = 0;
    virtual Spectrum sigmaTAt(const Point3 &pWorld) const = 0;
    // An upper bound of sigma_t over every point and channel.
    virtual Float maxSigmaT() const = 0;
    // The part [*t0, *t1] (world distances) of ray where sigma_t may be non-zero;
    // false when there is none.
    virtual bool support(const Ray &ray, Float *t0, Float *t1) const = 0;
    HGPhase phase;
    std::string name;

  protected:
    // Fills *mi for a scattering at world distance dist along ray (len = |ray.d|).
    void ScatterAt(const Ray &ray, Float dist, Float len, MediumInteraction *mi) const;
};

class HomogeneousMedium : public Medium {
  public:
    HomogeneousMedium(const Spectrum &sigmaA, const Spectrum &sigmaS, Float g);
    Spectrum Tr(const Ray &ray, UniformSource rng) const override;
    Spectrum sample(const Ray &ray, UniformSource rng, MediumInteraction *mi) const override;
    bool greySigmaT() const override;
    bool homogeneous() const override { return true; }
    Spectrum sigmaTAt(const Point3 &) const override { return sigmaT; }
    Float maxSigmaT() const override { return sigmaT.maxComponent(); }
    bool support(const Ray &ray, Float *t0, Float *t1) const override;
    const Spectrum sigmaA, sigmaS, sigmaT;
};

// pbrt-v3's GridDensityMedium: density d(p) trilinearly interpolated over an
// nx x ny x nz grid spanning [p0, p1] in the medium's space (values at voxel
// centres, zero outside the grid), sigma = d(p) * sigma. Needs a grey sigma_t.
// Delta tracking (sample) and ratio tracking (Tr) run against a piecewise-
// constant majorant: the maximum density over each cell of a coarse grid (at
// most 16 cells per axis), visited in ray order (3-D DDA), so that empty and
// thin regions cost few null collisions.
class GridMedium : public Medium {
  public:
    GridMedium(const Spectrum &sigmaA, const Spectrum &sigmaS, Float g, const Transform &worldFromMedium,
               Point3 p0, Point3 p1, int nx, int ny, int nz, std::vector<Float> density);
    Spectrum Tr(const Ray &ray, UniformSource rng) const override;
    Spectrum sample(const Ray &ray, UniformSource rng, MediumInteraction *mi) const override;
    bool greySigmaT() const override { return true; }
    bool homogeneous() const override { return false; }
    Spectrum sigmaTAt(const Point3 &pWorld) const override;  // 0 outside the grid's box, as Tr and sample
    Float maxSigmaT() const override { return sigmaT_ * maxDensity_; }
    bool support(const Ray &ray, Float *t0, Float *t1) const override;
    Float density(const Point3 &pMedium) const;  // in the medium's space

  private:
    // The ray in the medium's space, clipped to the grid's bounds: [t0, t1).
    bool clip(const Ray &ray, Ray *local, Float *t0, Float *t1) const;
    Float d(int x, int y, int z) const;
    // Calls visit(majorant density, ta, tb) for the majorant cells the local
    // ray crosses within [t0, t1], in order, until visit returns false.
    template <class Visit>
    void traverse(const Ray &local, Float t0, Float t1, Visit &&visit) const;
    const Spectrum sigmaA_, sigmaS_;
    Float sigmaT_;      // grey
    Transform mediumFromWorld_;
    Point3 p0_, p1_;
    int nx_, ny_, nz_;
    std::vector<Float> density_;
    Float maxDensity_ = 0;
    int m_[3] = {1, 1, 1};          // majorant cells per axis
    std::vector<Float> majorant_;   // max density over each cell's support
};

// The RNG a camera sample's media draw from (distances, transmittances): keyed
// by the render seed and the sample's film and lens positions, so that it is the
// same whatever the thread or the number of dimensions the sampler used.
inline RNG MediaRNG(uint64_t seed, Point2 pFilm, Point2 pLens) {
    return RNG(Hash(seed, FloatBits(pFilm.x), FloatBits(pFilm.y), FloatBits(pLens.x) ^ (FloatBits(pLens.y) << 1)));
}

// Measured scattering coefficients (pbrt-v3's named presets: Jensen et al.
// 2001, Narasimhan et al. 2006), in mm^-1. False for an unknown name.
bool MediumPreset(const std::string &name, Spectrum *sigmaA, Spectrum *sigmaS);
// All preset names (for error messages).
std::vector<std::string> MediumPresetNames();

// Creates the medium of a MakeNamedMedium directive; consumes its parameters
// (the caller checks unused ones). Bad values throw located errors.
std::shared_ptr<Medium> CreateMedium(const MediumDesc &desc);

}  // namespace gradus
