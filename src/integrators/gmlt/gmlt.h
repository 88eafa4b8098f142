// Gradient-domain Metropolis light transport (Lehtinen et al. 2013,
// gradient-domain-mlt.md): integrator "gmlt", on pmlt's paths, mutations,
// bootstrap and chains.
//
// Extended path space (Eq. 8): a chain's state z = (x, d) is a base path x
// (pmlt/path.h) and a shift direction d in {+x, -x, +y, -y}; every mutation
// proposes a new base path by one of pmlt's mutations and a uniform new d.
// The offset path T_d(x) is pmlt's Mutator::shift (Sec. 5.1: one pixel with
// x_0 held, the eye chain re-traced, the second chain walked; Jacobian of
// Sec. 5.2 in the delta-free measure), evaluated on its changed prefix only:
// F(T_d x) takes the factors of the unchanged vertices from x's evaluation
// and no light-side densities are computed (pmlt::EvaluateChangedPrefix). Per state:
//   f*(z) = n(z) [F(T_d x) |T_d'| - F(x)]     (Eqs. 7, 9; n = 1/2 when the shift
//            succeeds with F(T_d x) > 0, 1 otherwise; failures are symmetric)
//   f(z)  = Y|f*(z)| + alpha (1/4) Y(F(x))    (Eq. 11; Y: luminance of the
//            channel-wise absolute value; alpha shared with Eq. 16)
// Splats (expected values, as pmlt): the gradient b f*(z) / f(z) into dx or dy
// with the extended filter of Eq. 10 (a negative direction lands at the
// neighbour with the sign flipped: GradientFilm's convention), the coarse
// primal (1/4) b F(x) / f(z) (Sec. 4.3); b = the bootstrap's estimate of the
// integral of f over the extended space: each bdpt strategy's contribution
// C is weighted 4 f(x, d) / Y(F(x)) with one uniform d per strategy (an
// unbiased estimate of the sum over the four directions), and chains start at
// candidates drawn in proportion (no start-up bias); b converges with the
// render as pmlt's (independent bidirectional samples weighed as the
// bootstrap's), and the film keeps the splats without b: the gradients and
// the coarse primal are scaled by the same current b before the
// reconstruction. Candidates below the mean
// luminance tau of a 4096-sample pilot go through Russian roulette first
// (kept with probability lum / tau, weight tau / lum): the shift of every
// candidate tripled pmlt's bootstrap time (glass cube: 1.05 s -> 3.8 s).
// The screened-Poisson reconstruction (Eq. 16, reconstruction/) runs in finish.
// Separated light (as gpt, gbdpt, gvcm: gradient_film.h): a path whose
// vertices between the camera and the emitter all scatter through Dirac
// lobes (an emitter seen directly, in a mirror, through glass) splats no
// gradient (its target f stays Eq. 11's); its coarse primal also lands in a
// layer of its own, which the reconstruction adds after the solve (the
// screened Poisson solve neither spreads nor loses those pixels). The shift
// keeps Dirac vertices' lobes, so such a path and its offsets are separated
// alike: leaving out both halves of its gradient keeps the estimator, for the
// image without that light.
// directsamples N > 0 (Sec. 7): paths of at most one scattering vertex by
// G-PT (gpt, maxdepth 1, box filter, the same shiftthreshold) with N samples
// per pixel in the first pass: its primal and gradients (G-PT's shift) are
// added to the chains' (times b) before the reconstruction, which sees one
// image; emitters seen directly or through Dirac vertices only are G-PT's
// separated light (no gradients, added after the solve).
//
// Parameters (pmlt's, pmlt.h):
//   integer maxdepth 5                 maximum path depth (edges - 1)
//   integer bootstrapsamples 100000    bidirectional samples of the bootstrap (b, chain starts)
//   integer bootstrapconnections 0     cap on the bootstrap's connections (0: none)
//   integer chains 1000                Markov chains
//   integer mutationsperpixel 100      mutations per pixel when --spp is not given
//   integer directsamples 0            direct light by the path tracer (above); 0: the chains
//   float normalizationsamples 0.005   bidirectional samples per mutation that refine b (pmlt.h),
//                                        weighed to f as the bootstrap's
//   integer rrdepth 3                  Russian roulette in the bootstrap's subpaths (-1: off)
//   float bidirectional 1              selection weights of the mutations (the shift walks
//   float lens 1                         second chains whatever the manifold weight)
//   float caustic 1
//   float multichain 1
//   float manifold 1
// (gradient family, gradient_params.h):
//   float shiftthreshold 0.001       roughness below which a non-Dirac vertex is near-specular for
//                                    the shift (Fig. 5a; pmlt::ShiftClassOf)
//   string reconstruction "hybrid"   hybrid | l1 | l2 | weighted: the image in the unprefixed R,G,B
//   float alpha 0.2                  Eq. 11's and Eq. 16's alpha
//   string pixelfilter "box"         splats land in the pixel of their raster point (as pmlt's)
// (gmlt):
//   bool separated true              separated light (above) goes around the reconstruction
//                                    (false: it is shifted and takes gradients like the rest)
//   bool statelayers false           layers "density" (chain states per pixel per mutation
//                                    per pixel, Fig. 8b) and "irreversible" (those whose
//                                    shift has n = 1, Fig. 8f)
// Specular for the shift (Fig. 5a): vertices that scatter through a Dirac lobe
// (pmlt's VERTEX_DELTA) and near-specular ones (a BSDF roughness in
// (0, shiftthreshold)); the eye chain copies the latter's half vectors and the
// manifold walk keeps them in second chains (pmlt::Mutator::shift).
#pragma once
#include <atomic>
#include <memory>
#include <string>

#include "integrators/gradient/gradient_family.h"
#include "integrators/gradient/gradient_params.h"
#include "integrators/pmlt/pmlt.h"

namespace gradus {

struct GMLTSettings : PMLTSettings, GradientSettings {
    bool stateLayers;
    bool separated;
};

class GMLTIntegrator : public PMLTIntegrator, public GradientFamily {
  public:
    explicit GMLTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "gmlt"; }
    void preprocess(const Scene &scene, Film &film) override;
    void finish(const Film &film, const RenderStats &stats, Image *out) override;
    double finishEstimate() const override { return reconstructionEstimate(gset_.norm, gset_.alpha); }
    std::string statistics() const override;

    // One extended state's shift and target (tests).
    struct Target {
        pmlt::Mutator::ShiftStatus status = pmlt::Mutator::ShiftStatus::Blocked;
        double jacobian = 0;
        Spectrum offset{0};  // F(T_d x) |T_d'| (0 when the shift fails)
        Spectrum diff{0};    // f*(z) of Eq. 9 before the sign of d: n (offset - F(x))
        Float n = 1;
        double f = 0;        // Eq. 11
        bool separated = false;  // an emitter seen through Dirac vertices only: no gradient splat (header)
    };
    // After preprocess.
    Target evaluate(const pmlt::State &x, int dir, Arena &arena, pmlt::MutationStats *stats = nullptr) const;
    const pmlt::Mutator &mutator() const { return *mut_; }
    const BidirContext &bidirContext() const { return ctx_; }
    const pmlt::FilmDomain &filmDomain() const { return film_; }
    const GMLTSettings &gsettings() const { return gset_; }
    int64_t shiftCount(pmlt::Mutator::ShiftStatus s) const { return shiftCounts_[int(s)].load(); }
    int64_t nearSpecularShifts() const { return nNearSpecular_.load(); }

  protected:
    double candidateWeight(const Sample &smp, int64_t k, int s, int t, const ConnectSamples &cu, double lum,
                           uint64_t key, Arena &arena) const override;
    void prepareBootstrap(PassContext &ctx, uint64_t key) override;
    EntityDesc directDesc() const override;
    // The roulette threshold tau (the independent samples after a resume weigh with it).
    void saveCounters(std::string *s) const override;
    bool loadCounters(const std::string &s, size_t *at) override;
    int64_t runMutations(Chain &ch, int64_t count, pmlt::State &x, Arena &cur, RNG &rng, SampleRecorder &rec,
                         Worker &wk) override;

  private:
    static constexpr int kShiftStatuses = 6;
    // Cost per phase of the chains' mutations (--stats), in timestamp-counter
    // ticks: the proposal, the shift (those that walked a second chain and
    // those that joined x_b' to x_{b+1}), the rest (acceptance, splats, step).
    struct Phases {
        uint64_t propose = 0, shiftWalk = 0, shiftJoin = 0, rest = 0;
        int64_t nWalkShifts = 0, nJoinShifts = 0, nWalkShiftFailures = 0, nSeparated = 0;
    };
    struct AtomicPhases {
        std::atomic<uint64_t> propose{0}, shiftWalk{0}, shiftJoin{0}, rest{0};
        std::atomic<int64_t> nWalkShifts{0}, nJoinShifts{0}, nWalkShiftFailures{0}, nMutations{0};
    };
    // One chain's extended state z = (x, d) during a pass (x: the chain's
    // rebuilt state, y: the proposal's), with its counts.
    struct ChainWalk {
        explicit ChainWalk(pmlt::State &x) : xs(x) {}
        pmlt::State &xs;
        pmlt::State ys;
        Target tx;
        int dx = 0;
        pmlt::MutationStats mst;
        ItemCounts cnt;
        int64_t shifts[kShiftStatuses] = {};
        Phases ph;
    };
    // One mutation of the walk: proposal (base path and direction),
    // acceptance on the extended space, splats, the step.
    void mutate(ChainWalk &w, Sampler &u, RNG &rng, SampleRecorder &rec, Arena &cur, Arena &arena) const;
    // Splats of state s with direction dir and weight w (expected values).
    void splatState(SampleRecorder &rec, const pmlt::State &s, int dir, const Target &t, double w) const;

    GMLTIntegrator(const EntityDesc &desc, const GMLTSettings &s);
    GMLTSettings gset_;
    mutable std::atomic<int64_t> shiftCounts_[kShiftStatuses] = {};
    mutable std::atomic<int64_t> nBootstrapDropped_{0}, nBootstrapShifted_{0}, nRouletteDropped_{0};
    std::atomic<int64_t> nNearSpecular_{0};  // chain shifts that moved a near-specular vertex
    mutable AtomicPhases phases_;
    uint64_t ticks0_ = 0;  // the counter and the clock at preprocess (ticks per second at statistics)
    double clock0_ = 0;
    double tau_ = 0;  // candidate roulette threshold (prepareBootstrap)
    int densityLayer_ = -1, irreversibleLayer_ = -1;
    int separatedLayer_ = -1;  // the chains' separated light (splats, without b)
    mutable std::atomic<int64_t> nSeparated_{0};  // proposals of separated light
    GradientFilm directFilm_;  // directsamples: the layers of the G-PT direct pass (read in finish)
};

}  // namespace gradus
