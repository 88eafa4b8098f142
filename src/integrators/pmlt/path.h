// Full light paths of path-space MLT (Veach and Guibas 1997; Veach 1997,
// Ch. 11): x_0 (the lens) ... x_{n-1} (an emitter), stored camera to light.
//
// A path is its vertices (integrators/common/path_vertex.h) plus, per vertex,
// whether the path scatters there through a specular lobe (VERTEX_DELTA).
// Evaluate() computes the measurement contribution F(x) (Veach 1997, Ch. 8, the path integral)
// and, for every vertex, the area densities with which the camera side (pE)
// and the light side (pL) of the bidirectional sampler generate it: the
// quantities every mutation's transition density is built of.
//
// Specular vertices, delta-free form. A specular vertex x_i puts one Dirac
// delta into F and one into the density of whichever neighbour is sampled
// through it, on either side. Both are written against the measure
// mu = eta^2 |cos_ns| d(omega), which specular reflection and refraction
// preserve (eta: refractive index on the side of the direction, 1 outside,
// BxDF::eta inside), so the delta is the same distribution from both sides
// and cancels between F and every density (for reflection the projected solid angle of
// Veach 1997 would do):
//   f_i   = f_lobe |cos_o,ns| eta_o^2      (f_lobe: the lobe's value, BSDFSample::f)
//   p_ω   = P_lobe |cos_o,ns| eta_o^2      (P_lobe: its discrete probability)
// for the direction o that the query generates. Then F / p_j, the ratios
// p_j / p_k of two sampling techniques and the acceptance ratios are the
// exact ones; tests check F / p_{s,t} against the bidirectional estimator's
// unweighted contribution for every strategy.
//
// Shading normals: F uses pbrt-v3's convention, in which radiance transport
// weights a scattering by |cos_ns| of the light-side direction: f_i is taken
// times |cos_ns(w_light)| / |cos_ng(w_light)| and the geometry terms use
// geometric normals (equal to BDPT's throughputs with the adjoint correction).
#pragma once
#include <vector>

#include "integrators/common/bidir.h"
#include "render/film.h"
#include "samplers/rng.h"

namespace gradus::pmlt {

// Where the sampled film positions lie and how their density relates to the
// camera's (which is normalised to the whole film).
struct FilmDomain {
    Bounds2i pixels;     // the film's pixel bounds (crop window)
    Float scale = 1;     // full-film pixels / pixel-bounds pixels
    Point2 sample(Point2 u) const {
        return Point2(pixels.pMin.x + u.x * pixels.width(), pixels.pMin.y + u.y * pixels.height());
    }
    bool contains(Point2 p) const {
        return p.x >= pixels.pMin.x && p.y >= pixels.pMin.y && p.x < pixels.pMax.x && p.y < pixels.pMax.y;
    }
};

struct Path {
    std::vector<PathVertex> v;  // camera (0) to light (size - 1)
    int size() const { return int(v.size()); }
};

// The densities and contribution of one path (Evaluate).
struct PathEval {
    Spectrum F;        // measurement contribution, delta-free
    Float I = 0;       // target function: luminance of F
    Point2 pRaster;    // film position of the edge x_0 x_1
    // Area densities of x_i sampled from the camera side (from x_{i-1}, x_{i-2})
    // and from the light side (from x_{i+1}, x_{i+2}); 0 where that side cannot
    // generate it. pE[0] = pL[0] = the lens density, pL[n-1] the emitter's
    // origin density (delta lights: the light's selection probability).
    std::vector<Float> pE, pL;
    // At a specular vertex: the discrete probability of its lobe when the
    // camera side (lobeE) or light side (lobeL) samples through it (1 elsewhere).
    std::vector<Float> lobeE, lobeL;
    // Each vertex's factor of F (the camera's We G(x_0, x_1), a scattering
    // vertex's f |cos| G to the next, the emitter's value): F is their product.
    std::vector<Spectrum> factor;
    bool complete = false;  // every field above set (Evaluate); else only F, I, pRaster and the camera side's prefix
    bool valid() const { return I > 0; }
    // Density of sampling technique t (t camera vertices, n - t light
    // vertices) over vertices [lo, hi), the others given; 0 when the technique
    // cannot generate the path (see ValidSplit).
    Float splitDensity(const Path &x, const BidirContext &ctx, int t, int lo, int hi) const;
};

// Evaluates F(x), the target and the densities. BSDFs: one per vertex (empty
// for camera and light vertices), built in Radiance mode. Returns false (and
// I = 0) when the path carries nothing or lands outside the film domain.
// Visibility is not tested: mutations trace or test every edge they create.
bool Evaluate(const BidirContext &ctx, const FilmDomain &film, const Path &x, const BSDF *bsdfs, PathEval *e);
// F(y), I, pRaster and the camera side's densities pE, lobeE on x_0 .. x_{last+2}
// of a path y that equals an evaluated path x (ex: Evaluate's) from vertex
// last + 1 on (positions, flags, BSDFs): the factors of x_0 .. x_{last+1} (and
// the emitter's, if x_{last+1} is before it) evaluated on y, the rest taken from
// ex.factor (G-MLT's shifts change only a prefix of the path). The light side
// (pL, lobeL) is not computed and complete stays false; if ex is not complete,
// a full Evaluate.
bool EvaluateChangedPrefix(const BidirContext &ctx, const FilmDomain &film, const Path &y, const BSDF *bsdfs,
                           const PathEval &ex, int last, PathEval *e);

// True when technique t (camera vertices 0..t-1, light vertices t..n-1) can
// produce the path: t = n needs an emitter the camera side can hit; otherwise
// both ends of the edge (t-1, t) must be connectible (not scattering
// specularly, not a delta-direction light) and the edge not degenerate.
bool ValidSplit(const BidirContext &ctx, const Path &x, const PathEval &e, int t);

// The lens vertex of a camera ray.
PathVertex LensVertex(const BidirContext &ctx, const Ray &ray);

// The full path of bidirectional strategy (s, t) of a light and a camera
// subpath (what ConnectBDPT evaluates), the vertex the connection samples
// (s = 1: a light point, t = 1: a lens point) drawn with the same numbers; the
// connection's ends and the path's ends are marked non-specular. False when
// that sampling fails.
bool StrategyPath(const BidirContext &ctx, SubpathView light, SubpathView camera, int s, int t,
                  const ConnectSamples &cu, Path *x);

// The specular lobe of `bsdf` scattering wo into wi: its value (BSDFSample::f)
// and discrete probability. False when no specular lobe of the BSDF does.
bool SpecularLobe(const BSDF &bsdf, const Vec3 &wo, const Vec3 &wi, TransportMode mode, Spectrum *f, Float *prob);
// Samples the specular lobe that reflects (transmit = false) or transmits wo.
bool SampleSpecularLobe(const BSDF &bsdf, const Vec3 &wo, bool transmit, TransportMode mode, BSDFSample *s);
// Unit direction between two vertices (zero for coincident ones).
Vec3 Dir(const PathVertex &from, const PathVertex &to);
// Squared refractive index on the side of w at a vertex with this BSDF (1 outside).
Float EtaSquared(const BSDF &bsdf, const Vec3 &w);
// Geometry term of an edge (geometric normals; lens normal at the camera;
// one cosine towards an infinite-light vertex).
Float GeometryTerm(const BidirContext &ctx, const PathVertex &a, const PathVertex &b);

}  // namespace gradus::pmlt
