// Gradient-domain bidirectional path tracing (Manzi et al. 2015,
// gradient-domain-bdpt.md), Algorithm 1 on the shared BDPT core (common/).
//
// Per camera sample: a camera and a light subpath (line 1); the camera subpath
// is shifted once per neighbour (+x, -x, +y, -y; lines 3-5, Eqs. 6 and 7,
// gbdpt_shift.h); every BDPT strategy whose connection vertices are diffuse
// (Sec. 3.2: no connections at vertices classified specular) gives a base
// path (line 6); strategies with t >= 2 reuse the shifted camera subpaths
// (lines 12-14: case (ii) when the camera part ends at b, else case (i)),
// light-tracing paths (t = 1, case (iii)) are shifted one by one (lines 9-11).
// Gradients use the combined MIS of Eq. 8 (or Eq. 9); failed shifts and
// blocked/black offsets fall back to the base's BDPT weight with a zero offset
// (Sec. 4); blocked base paths are not shifted. Near-specular glossy vertices
// (roughness below shiftthreshold) are specular in both chains (Sec. 3.1): the
// first chain copies their half-vectors, the manifold walk of the second keeps
// them, its Jacobian taking their directions as variables (subpath_shift.h).
// Every strategy of a path must
// shift or fall back alike (else its Eq. 8 weights do not sum to one): a path
// ending at infinity (escaped camera subpath, next-event estimation of an
// infinite or distant light, light subpath started there) keeps the
// direction towards it in all of them (environment shift, |T'| = 1), and one
// ending at a point light reconnects to the point in all of them. Russian
// roulette: offsets reuse the base's decisions, so the 1/q factors are the
// base's and cancel in f(y)/f(x) (camera_shift.cpp). The primal gets the usual
// BDPT weight (line 15). Light-tracing values are splatted at their raster
// position and normalised like BDPT's splats (by the number of bidirectional
// samples, line 16); the screened-Poisson reconstruction runs in finish()
// (line 17).
//
// Participating media (issue 56; Gruson et al. 2018's volumetric shift on
// G-BDPT's): both subpaths carry medium vertices as bdpt's (common/bidir.h:
// pbrt-v3's MIS, phase densities converted to area, distance densities left
// out of every strategy alike, so rho compares directional densities only).
// A medium vertex is diffuse (rough). The camera-subpath shift walks each
// segment of the first chain in lockstep with the base's (the same interface
// crossings; at a medium vertex the base's free-flight distance copied along
// the offset's own ray, |T'| = 1, failing where the offset meets a surface
// first, is in another medium or sigma_t is 0 there) and reconnects b to c
// (|T'| = d_x^2 / d_y^2, cosines only at surface ends). Every changed segment
// multiplies the base's distance-sampling factor (GenerateCameraSubpath's
// segFactors) by T_y / T_x (gradient/medium_shift.h: exact in homogeneous
// media, ratio tracking in grids), a medium vertex by sigma_s(y) / sigma_s(x).
// Connections of offsets estimate their own edge's transmittance. The
// light-tracing shift walks the lens segment in lockstep the same way and
// carries T_y / T_x on both changed segments. Limitation: a second chain with
// specular vertices (b -> specular ... -> c) is not walked in a scene with
// media: the shift fails for such paths, in every strategy and for base and
// offset alike (the chain's vertex classes are kept by the shift), so their
// gradient samples fall back to the BDPT weight (unbiased; counted in the
// statistics). A scene without media runs the surface-only code.
//
// Parameters (bidirectional family, integrators/common/bidir_family.h; MIS
// always the balance heuristic, as Eq. 8 assumes):
//   integer maxdepth 5               maximum path depth (edges - 1)
//   string lightsamplestrategy "power"  uniform | power | spatial (= power, as bdpt: position-free,
//                                    as the MIS and the shifts of next-event estimation assume)
//   integer rrdepth 3                Russian roulette after this many bounces (-1: off); the
//                                    offsets reuse the base's decisions (camera_shift.cpp)
//   integer pixelbounds []           accepted (use --cropwindow)
// (gradient family, integrators/gradient/gradient_params.h):
//   float shiftthreshold 0.001       roughness below which a vertex is "specular"
//   string reconstruction "hybrid"   hybrid | l1 | l2 | weighted: the image in the unprefixed R,G,B
//   float alpha 0.2                  screened-Poisson primal weight
//   string pixelfilter "film"        film: the scene's PixelFilter (as bdpt; light-tracing
//                                    splats land in their pixel, as bdpt's); box: own pixel only
// (gbdpt):
//   string shift "manifold"          manifold (Sec. 3.1) | halfvector (Kettunen et al. 2015)
//   bool lighttracing true           false: no light-tracing paths (t = 1 strategies are
//                                    neither sampled nor counted in any MIS weight, primal
//                                    and gradients; Table 1 "w/o LTP")
//   string mis "combined"            combined (Eq. 8) | simple (Eq. 9)
//   string manifoldsolver "newton"   newton (the direct Newton walk) | ceres (ceres::TinySolver,
//                                    Levenberg-Marquardt): the solver of the manifold walks
//   integer separatedsamples 0       K extra camera walks per camera sample for the separated
//                                    light only (DiracCameraWalk; scenes without media): the
//                                    separated estimate is the mean of the sample's and the K
//                                    walks'; primal = the rest + that mean. 0: as before
// Output layers: primal, separated, dx, dy, *_var, reconstructed_l1, reconstructed_l2,
// reconstructed_hybrid (and reconstructed_weighted). Strategies s = 0 whose camera
// vertices all scattered by Dirac lobes (an emitter seen directly or through
// mirrors and glass: DiracCameraChain) are separated light: in the primal and
// the separated layer, in no gradient, added after the reconstruction
// (gradient_film.h); G-VCM's public code (issue 59).
#pragma once
#include <memory>
#include <mutex>
#include <vector>

#include "integrators/common/bidir_family.h"
#include "integrators/gbdpt/gbdpt_shift.h"
#include "integrators/gradient/gradient_film.h"
#include "integrators/gradient/gradient_params.h"
#include "integrators/gradient/gradient_family.h"
#include "render/integrator.h"
#include "lights/light_sampler.h"

namespace gradus {

template <class S>
class ParamTable;

// Every field is set by the parameter table (gbdpt.cpp).
struct GBDPTSettings : BidirSettings, GradientSettings {
    enum class MIS { Combined, Simple };
    bool manifold;  // shift "manifold" (else "halfvector")
    ManifoldSolver solver;
    bool lightTracing;
    MIS mis;
    int separatedSamples;  // extra Dirac-only camera walks per camera sample (separated light)
};

// gbdpt's parameter table (gvcm appends it to its own).
ParamTable<GBDPTSettings> GBDPTParamTable();

class GBDPTIntegrator : public PixelSampleIntegrator, public GradientFamily {
  public:
    using MIS = GBDPTSettings::MIS;
    explicit GBDPTIntegrator(const EntityDesc &desc);
    ~GBDPTIntegrator() override;
    std::string name() const override { return "gbdpt"; }
    bool rendersMedia() const override { return true; }  // "Participating media" above
    void preprocess(const Scene &scene, Film &film) override;
    void estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    double finishEstimate() const override { return reconstructionEstimate(set_.norm, set_.alpha); }
    std::string statistics() const override;

    // One camera sample without a film (tests): camera-side primal and
    // differences, and the light-tracing splats (values before the splat scale).
    GradientSample sample(const CameraSample &cs, Sampler &sampler, Arena &arena, const bool inside[kNumNeighbours],
                          std::vector<GradientSplat> *splats) const;
    const SubpathShiftContext &shiftContext() const { return sctx_; }
    const BidirContext &bidirContext() const { return bctx_; }
    Float splatScale() const { return splatScale_; }
    int maxDepth() const { return set_.maxDepth; }

  protected:
    // For G-VCM (integrators/gvcm/): its own parameter table around gbdpt's.
    GBDPTIntegrator(const EntityDesc &desc, const GBDPTSettings &set);
    // What a camera sample hands to addStrategies after G-BDPT's connections:
    // the prepared base camera subpath and its shifts (index k valid where inside[k]).
    struct CameraState {
        const ShiftSubpath *cam;
        const CameraShift *shifts;
        const bool *inside;
        Float w;  // camera ray weight
        Arena *arena;
        Sampler *sampler;
    };
    // More strategies of the same camera sample (G-VCM's merges): add their
    // primal and differences to *out.
    virtual void addStrategies(const CameraState &, GradientSample *) const {}
    // false: no light subpath per camera sample and no connections (G-PM).
    bool connections_ = true;

    GBDPTSettings set_;
    FileLoc loc_;
    LightSampler lightSampler_;
    BidirContext bctx_;
    std::unique_ptr<EmbreeManifoldScene> mscene_;
    SubpathShiftContext sctx_;
    Float splatScale_ = 1;

  private:
    // Per-thread statistics (summed by statistics()).
    struct ThreadState;
    struct Store;
    struct SampleRun;  // the stages of one camera sample (sample())
    std::unique_ptr<Store> store_;
    ThreadState &local() const;
};

}  // namespace gradus
