// G-PT in scenes with participating media (gpt.h, "Participating media"). A
// scene without media never reaches this tracer (gpt_tracer.h), so its
// images stay those of the surface-only G-PT.
//
// Base path: path's volumetric estimator (path/volpath.cpp, pbrt-v3 volpath):
// distance sampling per segment (spectral MIS in homogeneous media, delta
// tracking in grids), interfaces crossed without a bounce, next-event
// estimation with the transmittance of the shadow ray, MIS of the light and
// the BSDF/phase densities.
//
// Shift (Gruson et al. 2018-style extension of G-PT's):
//  - the offset walks its own segments in lockstep with the base's between
//    two scattering vertices: the same interface crossings, a surface where
//    the base hits one, escaping where it escapes; where the base scatters in
//    a medium at world distance t from the segment's start, the offset
//    scatters at the same distance along its own ray (|T'| = 1). It fails when
//    it hits a surface first, is in another medium, or the density there is 0;
//  - a medium vertex is rough; two rough vertices in a row reconnect the
//    offset to the base's next vertex: |T'| = d_x^2 / d_y^2, times
//    |cos_y| / |cos_x| only where that vertex is on a surface (gradient/shift.h);
//    the reconnection segment crosses the interfaces on its way;
//  - otherwise the direction is shifted: half-vector copy or replay at
//    surfaces (as without media), the same world direction at medium vertices
//    (|T'| = 1; also with shift "hybrid"; counted as half-vector copies in
//    the statistics);
//  - every changed segment multiplies the offset's throughput f(y)|T'|/p(x)
//    by T_y / T_x (the base's p(x) holds T_x), estimated without bias by
//    TransmittanceRatio (gradient/medium_shift.h: exact in homogeneous media,
//    ratio tracking of the optical-depth difference in grids), and a
//    scattering vertex by sigma_s(y) / sigma_s(x). Next-event terms of a
//    diverged offset estimate their own shadow ray's transmittance (ratio
//    tracking), which sits in f, not in p.
// Gradient MIS (G-BDPT Eq. 8, power heuristic) uses the directional densities
// only (distance densities left out of every technique alike, as pbrt-v3's
// BDPT does): the ratio of the pair is still a function of the pair, so
// w_ij(x) + w_ji(y) = 1 holds and the gradients stay unbiased.
// Limitation: emission of a material-less emitter (an interface with an
// area light) reaches the primal only, not the gradients.
#pragma once
#include "integrators/gpt/gpt_tracer.h"
#include "integrators/gradient/medium_shift.h"
#include "media/medium.h"
#include "samplers/rng.h"

namespace gradus::gpt {

// A scattering vertex of a volumetric path.
struct VolumeVertex {
    enum Kind { Surface, InMedium, Infinity };
    Kind kind = Surface;
    SurfaceInteraction isect;  // Surface
    MediumInteraction mi;      // InMedium
    BSDF bsdf;                 // Surface
    ShiftVertexClass cls = ShiftVertexClass::Invalid;
    Ray ray;                           // the segment that reached it (after interface crossings)
    const Medium *arriving = nullptr;  // that segment's medium
    const Interaction &it() const {
        return kind == InMedium ? static_cast<const Interaction &>(mi) : static_cast<const Interaction &>(isect);
    }
    // f |cos| at a surface, the phase function in a medium; and the density of wi.
    Spectrum f(const Vec3 &wo, const Vec3 &wi) const;
    Float pdf(const Vec3 &wo, const Vec3 &wi) const;
    bool hasNonSpecular() const { return kind == InMedium || (kind == Surface && bsdf.hasNonSpecular()); }
    // The medium a ray leaving towards wi travels in.
    const Medium *leaving(const Vec3 &wi) const {
        return kind == Surface ? isect.mediumAfter(wi, arriving) : arriving;
    }
};

// One segment of the base between two scattering vertices (up to an
// interface, a scattering point, a surface or infinity).
struct BaseSegment {
    enum End { Crossing, Scatter, Hit, Escape };
    End end = Hit;
    Ray ray;
    const Medium *medium = nullptr;
    Float dist = 0;           // world distance to its end (Infinity: escaped)
    Spectrum factor{1};       // Medium::sample's throughput factor (1 in vacuum)
    MediumPiece piece() const { return {ray.o, Normalize(ray.d), dist, medium}; }
};

struct VolumeOffset {
    OffsetPath::State state = OffsetPath::Dead;
    VolumeVertex v;            // Diverged: its own vertex
    Ray ray;                   // Diverged: its ray while it walks
    const Medium *medium = nullptr;
    Vec3 wo;                   // Reconnected: the incoming direction at the base vertex
    Spectrum beta{0};
    Float ratio = 1, lastPdfY = 1, lastJ = 1;
    bool lastSpecular = true, diracChain = true;
    Interaction prevIt;
    Spectrum diff{0};
    void kill(LocalShiftStats &st, ShiftFailure why) {
        state = OffsetPath::Dead;
        ratio = 0;
        st.fail(why);
    }
};

class VolumeGradientPathTracer {
  public:
    VolumeGradientPathTracer(const Scene &scene, const LightSampler &lights, Float threshold, bool hybrid,
                             const bool inside[kNumNeighbours], Arena &arena, LocalShiftStats &st, RNG &rng)
        : scene_(scene), lights_(lights), threshold_(threshold), hybrid_(hybrid), inside_(inside), arena_(arena),
          st_(st), rng_(rng) {}
    bool start(const CameraSample &cs, GradientSample *out);
    void trace(Sampler &sampler, int maxDepth, Float rrThreshold);
    void result(GradientSample *out) const;

  private:
    enum class Event { Scatter, Hit, Escape, End };
    Event walkBase(int bounces, int maxDepth);
    void classify(VolumeVertex *v) const;
    void advanceOffset(VolumeOffset &o);
    bool walkOffset(VolumeOffset &o);
    void reconnect(VolumeOffset &o);
    bool shiftDirection(VolumeOffset &o, Vec3 *wiY);
    int tracePieces(const VolumeVertex &from, const Vec3 &wi, MediumPiece *pieces) const;
    Spectrum segmentsFactor() const;
    void emissionTerms();
    void nextEventTerms(Sampler &sampler);
    Spectrum divergedNextEvent(const VolumeOffset &o, const LightChoice &lc, Float *ny, Float *by, Float *J);
    bool edgeFree(const Interaction &a, bool aSurface, const Interaction &b, bool bSurface, const Vec3 &d) const;

    const Scene &scene_;
    const LightSampler &lights_;
    const Float threshold_;
    const bool hybrid_;
    const bool *inside_;
    Arena &arena_;
    LocalShiftStats &st_;
    RNG &rng_;
    VolumeOffset off_[kNumNeighbours];
    // Base: its scattering vertex, the next one, the segments between them.
    VolumeVertex cur_, next_;
    bool atCamera_ = true;
    BaseSegment seg_[kMaxMediumPieces];
    int nSeg_ = 0;
    Ray ray_;
    const Medium *medium_ = nullptr;
    // The base's scattering sample at cur_ (what the offsets shift).
    BSDFSample bs_;
    Float uc_ = 0;
    Point2 u_;
    Vec3 wi_;
    Float pdfX_ = 1;
    Spectrum scatterFactor_{1};
    Spectrum beta_, primal_{0}, separated_{0};
    bool specularBounce_ = true, diracChain_ = true;
    Float prevPdf_ = 1;
    Interaction prevIt_;
    Float etaScale_ = 1;
};

}  // namespace gradus::gpt
