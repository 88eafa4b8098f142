// The per-sample tracer of G-PT (gpt.h): the base path with next-event
// estimation and BSDF sampling (power-heuristic MIS), its four offset paths
// and their gradient terms. gpt_tracer.cpp walks the paths and shifts the
// offsets; gpt_terms.cpp evaluates the emission and next-event terms.
#pragma once
#include "integrators/gradient/gradient_film.h"
#include "integrators/gradient/shift.h"
#include "lights/light.h"
#include "lights/light_sampler.h"
#include "scene/scene.h"

namespace gradus::gpt {

// State of one offset path relative to the base path.
struct OffsetPath {
    enum State { Dead, Diverged, Reconnected, Identical };
    State state = Dead;
    // Diverged: the offset's own current vertex.
    Ray ray;
    bool found = false;
    SurfaceInteraction isect;
    BSDF bsdf;
    ShiftVertexClass cls = ShiftVertexClass::Invalid;
    // Reconnected: the offset's incoming direction at the base vertex.
    Vec3 wo;
    Spectrum beta{0};       // f(y) |T'| / p(x) up to the current vertex
    Float ratio = 1;        // prod p_y |T'| / p_x over committed segments
    Float lastPdfY = 1;     // last segment: the offset's own pdf of its direction
    Float lastJ = 1;        // last segment: |T'| (solid angle)
    bool lastSpecular = true;
    bool diracChain = true;  // every segment so far sampled from a Dirac lobe (separated light)
    Interaction prevIt;     // the offset's previous vertex
    Spectrum diff{0};
    void kill(LocalShiftStats &st, ShiftFailure why) {
        state = Dead;
        ratio = 0;
        st.fail(why);
    }
};

// A vertex of the base path: the ray that reached it, the hit (or a point at
// infinity), its BSDF and shift class.
struct PathHit {
    Ray ray;
    SurfaceInteraction isect;
    bool found = false;
    BSDF bsdf;
    ShiftVertexClass cls = ShiftVertexClass::Invalid;
};

// One next-event sample of the base vertex (the offsets keep its light).
struct LightChoice {
    const Light *light = nullptr;
    Point2 u;
    LightLiSample ls;
    bool delta = false;
    Float nx = 0, bx = 0;  // the base's light and BSDF pdfs (solid angle)
    Spectrum fx;           // f |cos| of the base
    bool visible = false;
};

// Visibility of an edge for G-PT's shadow and reconnection rays: edges in the
// tangent plane of a surface end carry no light (InTangentPlane), as in the
// bidirectional connections; offsets saw a light outside a closed box through
// a face's own plane before (bench/stress camera_in_box, 6e-32 in the gradients).
// Russian roulette of the base path after depth 3 (path's rule; offsets follow
// the base's decision). Returns 0 to stop, else the survival probability 1 - q.
inline Float BaseRouletteSurvival(const Spectrum &rrBeta, int bounces, Float rrThreshold, Float u) {
    if (!(rrBeta.maxComponent() < rrThreshold && bounces > 3)) return 1;
    const Float q = std::max<Float>(0.05, 1 - rrBeta.maxComponent());
    return u < q ? 0 : 1 - q;
}

inline bool ShiftEdgeVisible(const Scene &scene, const Interaction &a, const Interaction &b) {
    const Vec3 d = b.p - a.p;
    return !InTangentPlane(a.n, d) && !InTangentPlane(b.n, d) && scene.unoccluded(a, b);
}

// One camera sample of G-PT: the base path (next-event estimation + BSDF
// sampling, power-heuristic MIS) and its four offsets, with the gradient MIS
// of G-BDPT Eq. 8 (power heuristic, GradientMISWeight) for each technique.
class GradientPathTracer {
  public:
    GradientPathTracer(const Scene &scene, const LightSampler &lights, Float threshold, bool hybrid,
                       const bool inside[kNumNeighbours], Arena &arena, LocalShiftStats &st)
        : scene_(scene), lights_(lights), threshold_(threshold), hybrid_(hybrid), inside_(inside), arena_(arena),
          st_(st) {}
    // Base camera ray and the offsets' (false: zero camera weight, nothing to trace).
    bool start(const CameraSample &cs, GradientSample *out);
    void trace(Sampler &sampler, int maxDepth, Float rrThreshold);
    void result(GradientSample *out) const;

  private:
    ShiftVertexClass classify(bool found, SurfaceInteraction &si, BSDF *b) const;
    void initOffset(const CameraSample &cs, int k);
    void emissionTerms();
    Spectrum offsetEmission(const OffsetPath &o, const Light *light, const Spectrum &Lx, Float nx, Float bx,
                            Float *ny, Float *by) const;
    void nextEventTerms(Sampler &sampler);
    Spectrum offsetNextEvent(const OffsetPath &o, const LightChoice &lc, Float *ny, Float *by, Float *J) const;
    Spectrum divergedNextEvent(const OffsetPath &o, const LightChoice &lc, Float *ny, Float *by, Float *J) const;
    void advanceOffset(OffsetPath &o, const BSDFSample &bs, Float uc, Point2 u, const PathHit &next);
    void reconnectOffset(OffsetPath &o, const BSDFSample &bs, const PathHit &next);
    void copyHalfVectorOrReplay(OffsetPath &o, const BSDFSample &bs, Float uc, Point2 u);

    const Scene &scene_;
    const LightSampler &lights_;
    const Float threshold_;
    const bool hybrid_;
    const bool *inside_;
    Arena &arena_;
    LocalShiftStats &st_;
    OffsetPath off_[kNumNeighbours];
    // Base path.
    PathHit cur_;
    Spectrum beta_, primal_{0}, separated_{0};
    bool specularBounce_ = true;
    bool diracChain_ = true;  // every bounce so far sampled from a Dirac lobe
    Float prevBsdfPdf_ = 1;  // the camera segment acts as a specular technique with pdf 1
    Interaction prevIt_;
    Float etaScale_ = 1;
};

}  // namespace gradus::gpt
