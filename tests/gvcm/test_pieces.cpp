// Tests of G-VCM's estimator pieces (integrators/gvcm; gradient-domain-vcm.md)
// on random paths of a small box (matte walls, a glossy plastic back wall, an
// area light, a glass and a mirror sphere), each against an evaluation that
// does not go through the code under test: the offsets' values f(x')|T'|/p(x*),
// as ratios to the base's Eq. 5 value, and their rho = |T'| p(x')/p(x*), case 1
// (Eqs. 16-17) and case 2 (Eqs. 18-20, empty and specular chains), from the
// paths re-evaluated from their vertex positions (BSDF values and densities,
// emission, cosines, distances) in the measure of the film point and the areas
// of the connectable vertices, where the camera shift (the film point moved by
// one pixel) has Jacobian 1; the camera's film-to-direction map and a specular
// chain's solid angle per area from finite differences, the offset's specular
// chain from an own Newton search on the emission direction. The merges' MIS
// weights (Eq. 13 for the base, Eq. 22's for the offset) against every
// strategy's density of the path enumerated explicitly, and the pair's Eq. 23
// weights with all other strategies' summing to one.
// Tolerances, per path: positions are Embree's single-precision hits (errors
// below 1e-6 in this box) and the reference takes directions from positions
// where the code keeps sampled directions, so a direction differs by up to
// 1e-6 / d and a cosine relatively by 1e-6 / (d |cos|), summed over the
// path's edges (Tolerance); a chain's finite differences add their noise and
// truncation (Case2Reference).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "gbdpt_test_util.h"
#include "integrators/gradient/camera_shift.h"
#include "integrators/gvcm/gvcm.h"
#include "lights/light.h"
#include "materials/material.h"

namespace gradus {

// The estimator's private pieces (gvcm.h's friend).
struct GVCMTestAccess {
    using Offset = GVCMIntegrator::Offset;
    using Case2Base = GVCMIntegrator::Case2Base;
    static void begin(GVCMIntegrator &g, const Scene &scene, const MergeKernel &k) {
        g.scene_ = &scene;
        g.kernel_ = k;
    }
    static Float mergeWeight(const VCMCameraTerms &t, const PathVertex &z, const PathVertex &zPrev, const BSDF &bz,
                             const LightVertex &lv, const VCMWeights &W) {
        return GVCMIntegrator::mergeWeight(t, z, zPrev, bz, lv, W);
    }
    static VCMWeights weights(const GVCMIntegrator &g) { return {&g.kernel_, true, g.set_.lightTracing, false, true}; }
    static bool case1(const GVCMIntegrator &g, const CameraShift &sh, int u, const BSDF &bu, const LightVertex &lv,
                      const Spectrum &f, Float etaX, const VCMCameraTerms *terms, Offset *o) {
        return g.case1(sh, u, bu, lv, f, 1, etaX, terms, weights(g), o);
    }
    static bool case2(const GVCMIntegrator &g, const ShiftSubpath &L, int m, const CameraShift &sh, int u,
                      const LightVertex &lv, const VCMCameraTerms *terms, Float etaX, Arena &arena, Offset *o) {
        Case2Base cb;
        g.case2Base(L, m, arena, &cb);
        return g.case2(L, cb, sh, u, lv, terms, etaX, arena, o);
    }
};

namespace {

using Offset = GVCMTestAccess::Offset;
constexpr int kW = 64, kH = 48;

std::string BoxText() {
    const char *matte = "Material \"matte\" \"rgb Kd\" [0.65 0.6 0.55]";
    return test::TestSceneHeader("0 1.1 -3.4  0 0.8 0  0 1 0", 45, kW, kH,
                                 "Integrator \"gvcm\" \"float radius\" [0.02]") +
           "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [6 6 6]\n" +
           test::Quad("Material \"matte\" \"rgb Kd\" [0 0 0]", "-0.4 1.95 -0.1  0.4 1.95 -0.1  0.4 1.95 0.6  -0.4 1.95 0.6") +
           "AttributeEnd\n" + test::Quad(matte, "-1.2 0 -1.5  1.2 0 -1.5  1.2 0 1.2  -1.2 0 1.2") +
           test::Quad(matte, "-1.2 2 -1.5  -1.2 2 1.2  1.2 2 1.2  1.2 2 -1.5") +
           test::Quad("Material \"plastic\" \"rgb Kd\" [0.3 0.35 0.4] \"rgb Ks\" [0.4 0.4 0.4] \"float roughness\" [0.15]",
                      "-1.2 0 1.2  1.2 0 1.2  1.2 2 1.2  -1.2 2 1.2") +
           test::Quad("Material \"matte\" \"rgb Kd\" [0.6 0.2 0.15]", "-1.2 0 -1.5  -1.2 0 1.2  -1.2 2 1.2  -1.2 2 -1.5") +
           test::Quad("Material \"matte\" \"rgb Kd\" [0.15 0.5 0.2]", "1.2 0 -1.5  1.2 2 -1.5  1.2 2 1.2  1.2 0 1.2") +
           "AttributeBegin\nMaterial \"glass\"\nTranslate 0.35 0.4 0.1\nShape \"sphere\" \"float radius\" [0.4]\n"
           "AttributeEnd\nAttributeBegin\nMaterial \"mirror\"\nTranslate -0.5 0.35 0.5\n"
           "Shape \"sphere\" \"float radius\" [0.35]\nAttributeEnd\nWorldEnd\n";
}

enum class KernelKind { Fixed, Footprint };

struct Fixture {
    RenderJob job;
    GVCMIntegrator *g = nullptr;
    const BidirContext *bc = nullptr;
    const SubpathShiftContext *sc = nullptr;
    std::unique_ptr<Sampler> sampler;
    VCMWeights W;
    explicit Fixture(KernelKind kind = KernelKind::Fixed) : job(gbdpttest::MakeJob(BoxText(), 1, 0)) {
        job.integrator->preprocess(*job.scene, *job.film);
        g = dynamic_cast<GVCMIntegrator *>(job.integrator.get());
        // eta = pi r^2 N with r = 0.02 and N = the film's pixels: ~0.54, of the
        // order of the box's area densities, so that merges and connections
        // share the weights. Footprint: G-VCM Sec. 6's per-path radius (about
        // r = 0.02 at the first connectable vertex) shrunk by 0.25^tau per vertex.
        MergeKernel k;
        k.piN = Pi * kW * kH;
        k.r2 = 0.02 * 0.02;
        if (kind == KernelKind::Footprint) {
            k.footprint2 = 0.02;
            k.r2Max = 1;
            k.shrink = 1;
            k.pixels = kW * kH;
            k.camera = job.scene->camera.get();
        }
        GVCMTestAccess::begin(*g, *job.scene, k);
        bc = &g->bidirContext();
        sc = &g->shiftContext();
        sampler = job.sampler->clone();
        W = GVCMTestAccess::weights(*g);
    }
    const Camera &camera() const { return *job.scene->camera; }
};

ShiftSubpath ArenaSubpath(Arena &arena, int n) {
    ShiftSubpath p;
    p.v = new (arena.alloc(sizeof(PathVertex) * n, alignof(PathVertex))) PathVertex[n];
    p.b = new (arena.alloc(sizeof(BSDF) * n, alignof(BSDF))) BSDF[n];
    p.deltaSample = static_cast<uint8_t *>(arena.alloc(n));
    return p;
}

// A camera subpath through an interior pixel (its neighbours inside the film)
// and its shift by `off` pixels.
struct CameraPath {
    CameraSample cs;
    Point2i off;
    ShiftSubpath x;
    CameraShift sh;
};
bool TraceCamera(Fixture &f, int trial, int maxV, Arena &arena, CameraPath *c) {
    const Point2i px{1 + trial % (kW - 2), 1 + (trial / (kW - 2)) % (kH - 2)};
    f.sampler->startPixelSample(px, trial);
    c->cs = {Point2(px.x + f.sampler->get1D(), px.y + f.sampler->get1D()), f.sampler->get2D()};
    c->off = trial % 2 ? Point2i{1, 0} : Point2i{0, 1};
    Ray ray;
    if (f.camera().generateRay(c->cs, &ray) == 0) return false;
    c->x = ArenaSubpath(arena, maxV);
    c->x.n = GenerateCameraSubpath(*f.bc, ray, *f.sampler, arena, maxV, c->x.v, c->x.b);
    PrepareSubpath(*f.sc, &c->x);
    SubpathShiftStats st;
    ShiftCameraSubpath(*f.sc, c->x, c->cs, c->off, arena, &c->sh, &st);
    return true;
}

// A light subpath (prepared: specular vertices marked).
ShiftSubpath TraceLight(Fixture &f, int maxV, Arena &arena) {
    ShiftSubpath L = ArenaSubpath(arena, maxV);
    L.n = GenerateLightSubpath(*f.bc, *f.sampler, arena, maxV, L.v, L.b);
    PrepareSubpath(*f.sc, &L);
    return L;
}

// Vertices closer than 0.05 (box corners): single-precision hits dominate their directions.
bool HasCorner(const ShiftSubpath &x, int n) {
    for (int k = 1; k + 1 < n; ++k)
        if (Distance(x.v[k].p, x.v[k + 1].p) < 0.05) return true;
    return false;
}

Vec3 Dir(const Point3 &from, const Point3 &to) { return Normalize(to - from); }
double Lum(const Spectrum &s) { return (s.r + s.g + s.b) / 3; }

// |cos| / d^2 at `to` (geometric normal n) seen from `from`.
double AreaFactor(const Point3 &from, const Point3 &to, const Vec3 &n) {
    const Vec3 d = to - from;
    return AbsDot(Normalize(d), n) / d.lengthSquared();
}

// The camera's importance and density per film area at film point p (pixel
// units): We cos(theta) |d omega / d p| and p_dir |d omega / d p|, the solid
// angle per film area by central differences of the camera rays (double
// precision; 1e-3 pixel steps).
struct FilmFactors {
    double we = 0, pdf = 0;
};
FilmFactors Film(const Camera &cam, Point2 p, Point2 lens) {
    const double h = 1e-3;
    auto dir = [&](double dx, double dy) {
        Ray r;
        cam.generateRay({Point2(p.x + dx, p.y + dy), lens}, &r);
        return Normalize(r.d);
    };
    const Vec3 dwx = (dir(h, 0) - dir(-h, 0)) / (2 * h), dwy = (dir(0, h) - dir(0, -h)) / (2 * h);
    const double dOmega = Cross(dwx, dwy).length();
    Ray r;
    cam.generateRay({p, lens}, &r);
    Point2 raster;
    const Spectrum We = cam.We(r, &raster);
    Float pdfPos, pdfDir;
    cam.pdfWe(r, &pdfPos, &pdfDir);
    return {Lum(We) * AbsDot(Normalize(r.d), Vec3(cam.lensNormal())) * dOmega, pdfDir * dOmega};
}

// f|cos| and the lobe probability of the specular lobe of b scattering wo into
// wi (the lobe found by sampling with a few random numbers).
bool SpecularLobe(const BSDF &b, const Vec3 &wo, const Vec3 &wi, TransportMode mode, Spectrum *fcos, double *prob) {
    for (Float uc : {0.02, 0.5, 0.98})
        for (Float u0 : {0.02, 0.5, 0.98}) {
            BSDFSample s;
            if (!b.sample(wo, uc, Point2(u0, 0.5), mode, &s) || !s.isSpecular()) continue;
            if (Dot(Normalize(s.wi), wi) > 1 - 1e-7) {
                *fcos = s.f * AbsDot(s.wi, Vec3(b.ns()));
                *prob = s.pdf;
                return true;
            }
        }
    return false;
}

// d |cos| at both ends of the edge a - b (normals na, nb; zero: none).
double DCos(const Point3 &a, const Vec3 &na, const Point3 &b, const Vec3 &nb) {
    const Vec3 w = Dir(a, b);
    const double d = Distance(a, b);
    return std::min(na.lengthSquared() == 0 ? 1.0 : d * AbsDot(w, na), nb.lengthSquared() == 0 ? 1.0 : d * AbsDot(w, nb));
}

// The camera part z_0 .. z_b (z_1 .. z_{b-1} specular) in the film measure:
// f = We cos |dw/dp| prod R_i, p = p_dir |dw/dp| prod prob_i; *sens gets the
// edges' 1 / (d |cos|) (directions from positions: Tolerance).
bool FirstChain(const Fixture &f, const ShiftSubpath &z, Point2 pFilm, Point2 lens, int b, Spectrum *F, double *P,
                double *sens) {
    const FilmFactors ff = Film(f.camera(), pFilm, lens);
    *F = Spectrum(ff.we);
    *P = ff.pdf;
    for (int i = 1; i <= b; ++i)
        *sens += 1 / DCos(z.v[i - 1].p, i > 1 ? Vec3(z.v[i - 1].ns) : Vec3(0, 0, 0), z.v[i].p, Vec3(z.v[i].ns));
    for (int i = 1; i < b; ++i) {
        Spectrum R;
        double prob;
        if (!SpecularLobe(z.b[i], Dir(z.v[i].p, z.v[i - 1].p), Dir(z.v[i].p, z.v[i + 1].p), TransportMode::Radiance, &R,
                          &prob))
            return false;
        *F *= R;
        *P *= prob;
    }
    return true;
}

// A vertex at unit distance from p in direction d facing p (densities per solid angle).
PathVertex DirPoint(const Point3 &p, const Vec3 &d) {
    PathVertex v;
    v.p = p + d;
    v.ng = v.ns = -d;
    return v;
}

// E(y_d -> dir): emission times the emitter's cosine at the light origin (d = 0),
// else the BSDF (importance) times the shading cosine; and p_omega(y_d -> dir).
Spectrum Emit(const Fixture &f, const ShiftSubpath &L, int d, const Vec3 &dir, double *pdf) {
    const PathVertex &y = L.v[d];
    const PathVertex t = DirPoint(y.p, dir);
    *pdf = PdfArea(*f.bc, y, &L.b[d], d > 0 ? &L.v[d - 1] : nullptr, t, TransportMode::Importance);
    if (d == 0) return EmittedRadiance(*f.bc, y, t) * AbsDot(Vec3(y.ng), dir);
    return L.b[d].f(Dir(y.p, L.v[d - 1].p), dir, TransportMode::Importance) * AbsDot(Vec3(y.ns), dir);
}

// The light prefix y_0 .. y_{m-1} of L and a photon y_m at p on the surface of
// camera vertex z (BSDF zb), with the densities the light subpath would have
// given it (and the reverse density of y_{m-2} through it); lv its record. False
// when y_{m-1} cannot send light to p (specular, occluded, black).
bool SyntheticPhoton(const Fixture &f, const ShiftSubpath &L, int m, const PathVertex &z, const BSDF &zb,
                     const Point3 &p, Arena &arena, ShiftSubpath *Lp, LightVertex *lv) {
    const PathVertex &yp = L.v[m - 1];
    if (yp.delta() || yp.isDeltaLight() || (m >= 2 && (yp.type != VertexType::Surface || !L.b[m - 1]))) return false;
    *Lp = ArenaSubpath(arena, m + 1);
    for (int i = 0; i < m; ++i) Lp->v[i] = L.v[i], Lp->b[i] = L.b[i], Lp->deltaSample[i] = L.deltaSample[i];
    PathVertex &y = Lp->v[m];
    y = z;
    y.p = p;
    y.flags = 0;
    y.rrScale = 1;
    y.wo = Dir(p, yp.p);
    y.setThroughput(Spectrum(0.5, 0.6, 0.7));  // cancels in every ratio here
    Lp->b[m] = zb;
    Lp->deltaSample[m] = 0;
    Lp->n = m + 1;
    if (!EdgeConnectible(*f.bc, yp, y) || !f.job.scene->unoccluded(AsInteraction(yp), AsInteraction(y))) return false;
    y.pdfFwd = PdfArea(*f.bc, yp, &L.b[m - 1], m >= 2 ? &L.v[m - 2] : nullptr, y, TransportMode::Importance);
    if (m >= 2) Lp->v[m - 2].pdfRev = PdfArea(*f.bc, yp, &L.b[m - 1], &y, L.v[m - 2], TransportMode::Radiance);
    double pdf;
    if (!(y.pdfFwd > 0) || Emit(f, *Lp, m - 1, Dir(yp.p, p), &pdf).isBlack()) return false;
    std::vector<LightVertex> recs;
    VCMLightVertices(*f.bc, Lp->v, Lp->b, m + 1, f.W, &recs);
    if (recs.empty() || recs.back().depth != m) return false;
    *lv = recs.back();
    return true;
}

// The first connectable camera vertex b (z_1 .. z_{b-1} specular), or -1.
int FirstConnectable(const Fixture &f, const ShiftSubpath &x) {
    for (int i = 1; i < x.n; ++i) {
        if (x.v[i].type != VertexType::Surface || !x.b[i]) return -1;
        if (!x.v[i].delta()) return f.W.mergeable(x.v[i], &x.b[i]) ? i : -1;
        if (!x.deltaSample[i]) return -1;  // near-specular glossy: not in this box
    }
    return -1;
}

// The base's eta_u and the camera terms of z_u of a camera subpath (as addStrategies computes them).
VCMCameraTerms Terms(const Fixture &f, const ShiftSubpath &z, int n, int u, Arena &arena, Float *etaU) {
    Float *eta = static_cast<Float *>(arena.alloc(sizeof(Float) * n, alignof(Float)));
    Float *B = static_cast<Float *>(arena.alloc(sizeof(Float) * n, alignof(Float)));
    VCMCameraEta(f.W, z.v, z.b, n, eta);
    VCMCameraB(*f.bc, z.v, z.b, n, f.W, eta, B);
    *etaU = eta[u];
    return VCMCameraAt(*f.bc, z.v, z.b, u, B[u], eta, f.W);
}

// Component-wise |a / b - 1| (components of b above 1e-3 of its largest).
double RelErr(const Spectrum &a, const Spectrum &b) {
    const double m = std::max({b.r, b.g, b.b});
    double e = 0;
    for (int c = 0; c < 3; ++c)
        if (b[c] > 1e-3 * m) e = std::max(e, std::abs(a[c] / b[c] - 1));
    return e;
}

// The tolerance of a value whose reference takes the directions of edges
// from their end points: hits are single precision (|p| < 3, rays < 6 long:
// position errors below 1e-6), so an edge's direction moves by up to 1e-6 / d
// and a cosine at its ends relatively by 1e-6 / (d |cos|), a BSDF value (the
// plastic's lobe) or density by at most twice that; sens = sum over the edges
// of 1 / (d |cos|) (the smaller end's). 1e-5 for the rest (the camera's film
// factors by differences, float-packed throughputs and normals).
double Tolerance(double sens) { return 1e-5 + 2e-6 * sens; }

struct ErrStats {
    int n = 0;
    double max = 0;
    void add(double e) {
        ++n;
        max = std::max(max, e);
    }
};

// ---------------------------------------------------------------- case 1
// Merges at z_u past the reconnection vertex r = b + 1 (empty second chain)
// with photons at z_u from random light prefixes. In the film + area measure
// the shift keeps the film point's offset (Jacobian 1) and z_r, so
//   o.f / f_x = [F(z') g(z'_b, z_r) f(z'_b -> z_r -> next)] / [the same for z]
// with F the first chain's film-measure factor (FirstChain), g = f(z_{b-1} ->
// z_b -> z_r) |cos_b| |cos_r| / d^2 the reconnection, `next` z_{r+1} or, at
// u = r, the photon's y_{m-1}; every factor after z_r is shared. rho: the same
// with densities (film density, lobe probabilities, p_omega(z_b) |cos_r| / d^2,
// and p_omega(z_r -> z_{r+1}) for u > r).
void CheckCase1(KernelKind kind) {
    Fixture f(kind);
    Arena arena;
    ErrStats ef, er;
    int atR = 0, pastR = 0, firstChains = 0, ownKernel = 0;
    for (int trial = 0; trial < 30000 && (ef.n < 300 || firstChains < 60); ++trial) {
        arena.reset();
        CameraPath c;
        if (!TraceCamera(f, trial, 6, arena, &c)) continue;
        const ShiftSubpath &x = c.x, &y = c.sh.y;
        const int b = FirstConnectable(f, x), r = c.sh.r;
        if (b < 1 || r != b + 1 || c.sh.validUpTo < r || HasCorner(x, c.sh.validUpTo + 1) || HasCorner(y, r)) continue;
        if (b == 1 && ef.n >= 300) continue;  // then only offsets through specular first chains
        ShiftSubpath L = TraceLight(f, 4, arena);
        for (int u = r; u <= c.sh.validUpTo; ++u) {
            if (x.v[u].type != VertexType::Surface || !x.b[u] || !f.W.mergeable(x.v[u], &x.b[u])) continue;
            ShiftSubpath Lp;
            LightVertex lv;
            const int m = 1 + trial % L.n;
            if (!SyntheticPhoton(f, L, m, x.v[u], x.b[u], x.v[u].p, arena, &Lp, &lv)) continue;
            Float etaX, etaY;
            const int ny = std::min(y.n, c.sh.validUpTo + 1);
            Terms(f, x, x.n, u, arena, &etaX);
            const VCMCameraTerms ty = Terms(f, y, ny, u, arena, &etaY);
            const Spectrum fu = x.b[u].f(Vec3(x.v[u].wo), lv.wo, TransportMode::Radiance);
            Offset o;
            if (!GVCMTestAccess::case1(*f.g, c.sh, u, x.b[u], lv, fu, etaX, &ty, &o)) continue;
            const Spectrum fx = x.v[u].throughput() * fu * lv.throughput() / etaX;
            // The reference.
            Spectrum Fx, Fy;
            double Px, Py, sens = 0;
            const Point2 pY(c.cs.pFilm.x + c.off.x, c.cs.pFilm.y + c.off.y);
            if (!FirstChain(f, x, c.cs.pFilm, c.cs.pLens, b, &Fx, &Px, &sens) ||
                !FirstChain(f, y, pY, c.cs.pLens, b, &Fy, &Py, &sens))
                continue;
            const Point3 &zr = x.v[r].p;
            const Vec3 nr(x.v[r].ng);
            const Point3 next = u > r ? x.v[r + 1].p : Lp.v[m - 1].p;
            for (int side = 0; side < 2; ++side) {
                const ShiftSubpath &z = side ? y : x;
                const Vec3 wo = Dir(z.v[b].p, z.v[b - 1].p), wi = Dir(z.v[b].p, zr);
                Spectrum &F = side ? Fy : Fx;
                double &P = side ? Py : Px;
                F *= z.b[b].f(wo, wi, TransportMode::Radiance) * AbsDot(wi, Vec3(z.v[b].ns)) *
                     AreaFactor(z.v[b].p, zr, nr) * x.b[r].f(-wi, Dir(zr, next), TransportMode::Radiance);
                P *= z.b[b].pdf(wo, wi, TransportMode::Radiance) * AreaFactor(z.v[b].p, zr, nr);
                if (u > r) P *= x.b[r].pdf(-wi, Dir(zr, next), TransportMode::Radiance);
                sens += 1 / DCos(z.v[b].p, Vec3(z.v[b].ns), zr, nr) + 1 / DCos(zr, nr, next, Vec3(0, 0, 0));
            }
            const Spectrum ratio = SafeDiv(o.f, fx), ref = SafeDiv(Fy, Fx);
            // rho = |T'| p_VM(y) / p_VM(x), each merge's density with its own kernel (Eq. 22).
            const double rhoRef = (Py / Px) * (etaY / etaX);
            const double eF = RelErr(ratio, ref), eR = std::abs(o.rho / rhoRef - 1);
            const double tol = Tolerance(sens);
            EXPECT_LT(eF, tol) << "u " << u << " r " << r << " b " << b << " trial " << trial << ": o.f / f_x "
                                << ratio.r << " " << ratio.g << " " << ratio.b << ", reference " << ref.r << " "
                                << ref.g << " " << ref.b;
            EXPECT_LT(eR, tol) << "u " << u << " r " << r << " b " << b << " trial " << trial << ": rho " << o.rho
                                << ", reference " << rhoRef;
            ef.add(eF);
            er.add(eR);
            atR += u == r;
            pastR += u > r;
            firstChains += b > 1;
            ownKernel += std::abs(etaY / etaX - 1) > 1e-3;
        }
    }
    EXPECT_GE(atR, 100);
    EXPECT_GE(pastR, 100);
    EXPECT_GE(firstChains, 60) << "offsets whose first chain holds specular vertices";
    if (kind == KernelKind::Footprint) {
        EXPECT_GE(ownKernel, 200) << "offsets whose own kernel differs from the base's";
    }
    std::printf("case 1 (%s kernel): %d offsets (%d at u = r, %d past r, %d through specular first chains); max "
                "relative error of the value %.2e, of rho %.2e\n",
                kind == KernelKind::Fixed ? "fixed" : "footprint", ef.n, atR, pastR, firstChains, ef.max, er.max);
}

// ---------------------------------------------------------------- case 2
// The offset of a merge at z_b is the connected path y_0 .. y_d, y'_{d+1} ..
// y'_{m-1}, z'_b .. z'_0 (Eqs. 18-19: f(x') / p'(x*), the base's photon density
// and kernel). Relative to the base's Eq. 5 value:
//   o.f / f_x = [E(y_d -> w') R' G'] / [E(y_d -> w) R G]
//               x f(z'_{b-1} -> z'_b -> y'_{m-1}) / f(z_{b-1} -> z_b -> y_{m-1}) x F(z') / F(z)
// with E the emission (times its cosine) or the BSDF (times the shading
// cosine) at y_d, R the chain's specular f|cos| (1 for an empty chain), G the
// solid angle at y_d per area at the chain's end (|cos| / d^2 for an empty
// chain) and F the camera's first chain in the film measure; rho likewise with
// p_omega(y_d) G prod(lobe probabilities) and the camera's film densities.

// A specular chain traced from o (normal on) along dir, each vertex taking the
// lobe (reflection or transmission) of `transmit`, to the next surface.
struct Chain {
    Point3 end, last;  // the end point; the last specular vertex (or o)
    Vec3 endN;
    int endGeom = -1;
    Spectrum R{1};     // prod f|cos| (importance)
    double prob = 1;   // prod of the lobe probabilities
    std::vector<PathVertex> v;  // the specular vertices (position, normals, BSDF; marked Dirac)
    std::vector<BSDF> b;
};
bool TraceChain(const Fixture &f, Arena &arena, const Point3 &o, const Vec3 &on, const Vec3 &dir,
                const std::vector<bool> &transmit, Chain *c) {
    *c = Chain();
    Point3 p = o;
    Vec3 pn = on, d = dir;
    c->last = o;
    for (size_t j = 0;; ++j) {
        SurfaceInteraction si;
        if (!f.job.scene->intersect(Interaction(p, Normal3(pn), Vec3()).spawnRay(d), &si) || !si.material) return false;
        if (j == transmit.size()) {
            c->end = si.p;
            c->endN = Vec3(si.n);
            c->endGeom = si.geomId;
            return true;
        }
        const Vec3 wo = -d;
        BSDF b = si.material->getBSDF(si, arena, TransportMode::Importance);
        if (!b || !b.isSpecular()) return false;
        bool found = false;
        for (Float uc : {0.02, 0.5, 0.98})
            for (Float u0 : {0.02, 0.5, 0.98}) {
                BSDFSample s;
                if (found || !b.sample(wo, uc, Point2(u0, 0.5), TransportMode::Importance, &s) || !s.valid() ||
                    s.isTransmission() != transmit[j])
                    continue;
                found = true;
                c->R *= s.f * AbsDot(s.wi, Vec3(b.ns()));
                c->prob *= s.pdf;
                d = Normalize(s.wi);
            }
        if (!found) return false;
        p = si.p;
        pn = Vec3(si.n);
        c->last = p;
        PathVertex pv;
        MakeSurfaceVertex(*f.bc, si, b, &pv);
        pv.flags = VERTEX_DELTA;
        c->v.push_back(pv);
        c->b.push_back(b);
    }
}

// The chain's solid angle at its start per area at its end, by central
// differences of eps rad about dir.
double ChainG(const Fixture &f, Arena &arena, const Point3 &o, const Vec3 &on, const Vec3 &dir,
              const std::vector<bool> &transmit, const Chain &c, double eps) {
    Vec3 t[2];
    CoordinateSystem(dir, &t[0], &t[1]);
    Vec3 e[2];
    for (int a = 0; a < 2; ++a) {
        Chain cp, cm;
        if (!TraceChain(f, arena, o, on, Normalize(dir + t[a] * eps), transmit, &cp) ||
            !TraceChain(f, arena, o, on, Normalize(dir - t[a] * eps), transmit, &cm) || cp.endGeom != c.endGeom ||
            cm.endGeom != c.endGeom)
            return 0;
        e[a] = (cp.end - cm.end) / (2 * eps);
    }
    return 1 / AbsDot(Cross(e[0], e[1]), c.endN);
}

// The direction at o whose chain ends at `target` (on the plane of normal tn):
// Newton on the end point's tangent coordinates, derivatives by 1e-5 rad differences.
bool SolveChain(const Fixture &f, Arena &arena, const Point3 &o, const Vec3 &on, Vec3 dir,
                const std::vector<bool> &transmit, const Point3 &target, const Vec3 &tn, int geom, Vec3 *out,
                Chain *c) {
    Vec3 s[2];
    CoordinateSystem(tn, &s[0], &s[1]);
    auto residual = [&](const Vec3 &d, double r[2], Chain *ch) {
        if (!TraceChain(f, arena, o, on, d, transmit, ch) || ch->endGeom != geom) return false;
        for (int a = 0; a < 2; ++a) r[a] = Dot(ch->end - target, s[a]);
        return true;
    };
    for (int it = 0; it < 30; ++it) {
        double r[2];
        if (!residual(dir, r, c)) return false;
        if (std::hypot(r[0], r[1]) < 1e-7) {
            *out = dir;
            return true;
        }
        Vec3 t[2];
        CoordinateSystem(dir, &t[0], &t[1]);
        double J[2][2];
        for (int a = 0; a < 2; ++a) {
            double ra[2];
            Chain ca;
            if (!residual(Normalize(dir + t[a] * 1e-5), ra, &ca)) return false;
            for (int q = 0; q < 2; ++q) J[q][a] = (ra[q] - r[q]) / 1e-5;
        }
        const double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
        if (!(std::abs(det) > 0)) return false;
        const double da = (J[1][1] * r[0] - J[0][1] * r[1]) / det, db = (J[0][0] * r[1] - J[1][0] * r[0]) / det;
        // Damped: halve the step until the chain still ends on the target's
        // surface closer to it.
        bool better = false;
        for (double step = 1; step > 1e-3 && !better; step /= 2) {
            const Vec3 next = Normalize(dir - (t[0] * da + t[1] * db) * step);
            double rn[2];
            Chain cn;
            if (residual(next, rn, &cn) && std::hypot(rn[0], rn[1]) < std::hypot(r[0], r[1])) {
                dir = next;
                better = true;
            }
        }
        if (!better) return false;
    }
    return false;
}

// The reference of a case-2 offset: value ratio and rho (above). L holds the
// light subpath to the photon y_m, z and y the base and offset camera subpaths
// with first connectable vertex b. False when the own search misses the chain.
struct Case2Ref {
    Spectrum ratio;
    double rho = 0, tol = 0;
    Chain offsetChain;  // specular chains: the offset's
};
bool Case2Reference(const Fixture &f, Arena &arena, const ShiftSubpath &L, int m, const CameraPath &c, int b,
                    Case2Ref *ref) {
    int d = m - 1;
    while (d > 0 && L.v[d].delta()) --d;
    const PathVertex &yd = L.v[d], &ym = L.v[m], &zo = c.sh.y.v[b];
    std::vector<bool> transmit;
    for (int i = d + 1; i < m; ++i)
        transmit.push_back(Transmits(Dir(L.v[i].p, L.v[i - 1].p), Dir(L.v[i].p, L.v[i + 1].p), Vec3(L.v[i].ns)));
    const Vec3 on = yd.ng.isZero() ? Dir(yd.p, L.v[d + 1].p) : Vec3(yd.ng);
    const Vec3 wX = Dir(yd.p, L.v[d + 1].p);
    Vec3 wY;
    Spectrum RX(1), RY(1);
    double gX, gY, probX = 1, probY = 1;
    Point3 lastY = yd.p;
    double sens = 0, gErr = 0;
    if (d == m - 1) {  // empty chain: connections of y_d to the photon and to z'_b
        wY = Dir(yd.p, zo.p);
        gX = AreaFactor(yd.p, ym.p, Vec3(ym.ng));
        gY = AreaFactor(yd.p, zo.p, Vec3(zo.ng));
        for (const PathVertex *e : {&ym, &zo})
            sens += 1 / DCos(yd.p, yd.ng.isZero() ? Vec3(0, 0, 0) : on, e->p, Vec3(e->ng));
    } else {
        Chain cx, cy;
        // The base chain retraced from y_d towards y_{d+1} (a direction from
        // single-precision positions, magnified along the chain) ends at y_m.
        if (!TraceChain(f, arena, yd.p, on, wX, transmit, &cx) || Distance(cx.end, ym.p) > 1e-3) return false;
        // The offset chain followed from the base's as its end moves to z'_b in
        // 16 steps along the surface (the branch a manifold walk follows).
        wY = wX;
        for (int step = 1; step <= 16; ++step) {
            const Point3 target = ym.p + (zo.p - ym.p) * (step / 16.0);
            if (!SolveChain(f, arena, yd.p, on, wY, transmit, target, Vec3(zo.ng), cx.endGeom, &wY, &cy)) return false;
        }
        // G by central differences: 1e-3 rad steps on single-precision hits
        // (~1e-6 at lengths ~1: 2e-3 relative, tests/gbdpt) and the truncation,
        // estimated by the change from twice the step (4 times the error), per
        // chain; a quarter of the step where a step leaves the end's surface.
        for (double eps : {1e-3, 2.5e-4}) {
            gX = ChainG(f, arena, yd.p, on, wX, transmit, cx, eps);
            gY = ChainG(f, arena, yd.p, on, wY, transmit, cy, eps);
            const double gX2 = ChainG(f, arena, yd.p, on, wX, transmit, cx, 2 * eps);
            const double gY2 = ChainG(f, arena, yd.p, on, wY, transmit, cy, 2 * eps);
            if (!(gX > 0) || !(gY > 0) || !(gX2 > 0) || !(gY2 > 0)) continue;
            gErr = 4e-3 * (1e-3 / eps) + std::abs(gX2 / gX - 1) / 3 + std::abs(gY2 / gY - 1) / 3;
            gX += (gX - gX2) / 3;  // Richardson: the O(eps^2) term removed (gErr bounds it before)
            gY += (gY - gY2) / 3;
            break;
        }
        if (!(gErr > 0)) return false;
        RX = cx.R, RY = cy.R, probX = cx.prob, probY = cy.prob;
        ref->offsetChain = cy;
        lastY = cy.last;
    }
    double pX, pY;
    const Spectrum EX = Emit(f, L, d, wX, &pX), EY = Emit(f, L, d, wY, &pY);
    const ShiftSubpath &x = c.x, &y = c.sh.y;
    const Spectrum fX = x.b[b].f(Dir(x.v[b].p, x.v[b - 1].p), Dir(ym.p, L.v[m - 1].p), TransportMode::Radiance);
    const Spectrum fY = y.b[b].f(Dir(zo.p, y.v[b - 1].p), Dir(zo.p, lastY), TransportMode::Radiance);
    Spectrum FX, FY;
    double PX, PY;
    const Point2 pFilmY(c.cs.pFilm.x + c.off.x, c.cs.pFilm.y + c.off.y);
    if (!FirstChain(f, x, c.cs.pFilm, c.cs.pLens, b, &FX, &PX, &sens) ||
        !FirstChain(f, y, pFilmY, c.cs.pLens, b, &FY, &PY, &sens))
        return false;
    ref->ratio = SafeDiv(EY * RY * gY * fY * FY, EX * RX * gX * fX * FX);
    ref->rho = (PY * pY * gY * probY) / (PX * pX * gX * probX);
    ref->tol = Tolerance(sens) + gErr;
    return true;
}

// Empty chains (Eq. 18) with photons from random light prefixes placed up to
// 0.015 (about the kernel's radius) from z_b on its plane, for random camera
// subpaths (z_b behind specular first chains too). Footprint kernel: the
// estimate keeps the base's (Eq. 18's pi r^2).
void CheckCase2Empty(KernelKind kind) {
    Fixture f(kind);
    Arena arena;
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-0.015, 0.015);
    ErrStats ef, er;
    int firstChains = 0, failed = 0, ownKernel = 0;
    for (int trial = 0; trial < 30000 && (ef.n < 300 || firstChains < 60); ++trial) {
        arena.reset();
        CameraPath c;
        if (!TraceCamera(f, trial, 6, arena, &c)) continue;
        const ShiftSubpath &x = c.x, &y = c.sh.y;
        const int b = FirstConnectable(f, x);
        if (b < 1 || c.sh.validUpTo < b || (c.sh.r >= 0 && b >= c.sh.r) || HasCorner(x, b + 1) || HasCorner(y, b + 1))
            continue;
        if (b == 1 && ef.n >= 300) continue;  // then only z_b behind specular first chains
        ShiftSubpath L = TraceLight(f, 4, arena), Lp;
        const int m = 1 + trial % L.n;
        Vec3 t1, t2;
        CoordinateSystem(Vec3(x.v[b].ng), &t1, &t2);
        LightVertex lv;
        const Point3 p = x.v[b].p + t1 * U(rng) + t2 * U(rng);
        if (!SyntheticPhoton(f, L, m, x.v[b], x.b[b], p, arena, &Lp, &lv)) continue;
        Float etaX, etaY;
        Terms(f, x, x.n, b, arena, &etaX);
        const VCMCameraTerms ty = Terms(f, y, std::min(y.n, c.sh.validUpTo + 1), b, arena, &etaY);
        Offset o;
        if (!GVCMTestAccess::case2(*f.g, Lp, m, c.sh, b, lv, &ty, etaX, arena, &o)) {
            ++failed;  // occluded or black
            continue;
        }
        Case2Ref ref;
        ASSERT_TRUE(Case2Reference(f, arena, Lp, m, c, b, &ref));
        const Spectrum fx = x.v[b].throughput() * x.b[b].f(Vec3(x.v[b].wo), lv.wo, TransportMode::Radiance) *
                            lv.throughput() / etaX;
        const Spectrum ratio = SafeDiv(o.f, fx);
        ref.rho *= etaY / etaX;  // each merge's density with its own kernel (Eq. 22)
        const double eF = RelErr(ratio, ref.ratio), eR = std::abs(o.rho / ref.rho - 1);
        EXPECT_LT(eF, ref.tol) << "b " << b << " m " << m << " trial " << trial << ": o.f / f_x " << ratio.r << " "
                               << ratio.g << " " << ratio.b << ", reference " << ref.ratio.r << " " << ref.ratio.g
                               << " " << ref.ratio.b;
        EXPECT_LT(eR, ref.tol) << "b " << b << " m " << m << " trial " << trial << ": rho " << o.rho
                               << ", reference " << ref.rho;
        ef.add(eF);
        er.add(eR);
        firstChains += b > 1;
        ownKernel += std::abs(etaY / etaX - 1) > 1e-3;
    }
    EXPECT_GE(ef.n, 300);
    EXPECT_GE(firstChains, 60) << "merges at z_b behind specular first chains";
    if (kind == KernelKind::Footprint) {
        EXPECT_GE(ownKernel, 200) << "offsets whose own kernel differs from the base's";
    }
    std::printf("case 2, empty chains (%s kernel): %d offsets (%d behind specular first chains, %d occluded or black); max "
                "relative error of the value %.2e, of rho %.2e\n",
                kind == KernelKind::Fixed ? "fixed" : "footprint", ef.n, firstChains, failed, ef.max, er.max);
}

// ---------------------------------------------------------------- MIS
// A full path in light order: x[0] on the light .. x[k-1] on the lens.
struct FullPath {
    std::vector<PathVertex> v;
    std::vector<const BSDF *> b;
};
// The light vertices L[0..s-1], then the camera vertices z[t-1] .. z[0].
FullPath Join(const ShiftSubpath &L, int s, const ShiftSubpath &z, int t) {
    FullPath x;
    for (int i = 0; i < s; ++i) x.v.push_back(L.v[i]), x.b.push_back(&L.b[i]);
    for (int i = t - 1; i >= 0; --i) x.v.push_back(z.v[i]), x.b.push_back(&z.b[i]);
    return x;
}

// Every strategy's density of the path, enumerated explicitly (the balance
// heuristic's weight of a strategy is its density over their sum; G-VCM Eqs.
// 12-13 and 21): p_VC,s = prod_{i<s} pL(x_i) prod_{i>=s} pC(x_i) for the
// connection (s, k - s) and p_VM,j = p_VC,j pL(x_j) eta_j for the merge at x_j,
// with pL, pC the densities of x_i from the light and the camera side
// (positions, BSDF densities, Dirac densities as 1) and eta_j the path's
// kernel. The strategies gvcm plays: emission hits, connections of two
// connectable vertices over a non-degenerate edge ((1, 1) excepted), light
// tracing (not through the filter margin), merges at every connectable surface
// vertex x_1 .. x_{k-2}. *sens gets the edges' 1 / (d |cos|) (Tolerance).
struct Densities {
    std::vector<double> vc, vm;  // by s, by j (0: not a strategy)
    double total = 0;
    double weightVM(int j) const { return vm[size_t(j)] / total; }
    double weightVC(int s) const { return vc[size_t(s)] / total; }
};
Densities Enumerate(const Fixture &f, const FullPath &x, double *sens) {
    const BidirContext &ctx = *f.bc;
    const StrategySet &set = ctx.strategies;
    const MergeKernel &kernel = *set.kernel;
    const int k = int(x.v.size());
    auto remap = [](double p) { return p != 0 ? p : 1.0; };
    std::vector<double> pL(static_cast<size_t>(k)), pC(static_cast<size_t>(k));
    for (int i = 0; i < k; ++i) {
        pL[i] = i == 0 ? PdfLightOrigin(ctx, x.v[0], x.v[1])
                       : PdfArea(ctx, x.v[i - 1], x.b[i - 1], i >= 2 ? &x.v[i - 2] : nullptr, x.v[i],
                                 TransportMode::Importance);
        pC[i] = i == k - 1 ? 1
                           : PdfArea(ctx, x.v[i + 1], x.b[i + 1], i + 2 <= k - 1 ? &x.v[i + 2] : nullptr, x.v[i],
                                     TransportMode::Radiance);
        if (i + 1 < k)
            *sens += 1 / DCos(x.v[i].p, x.v[i].onSurface() ? Vec3(x.v[i].ng) : Vec3(0, 0, 0), x.v[i + 1].p,
                              x.v[i + 1].onSurface() ? Vec3(x.v[i + 1].ng) : Vec3(0, 0, 0));
    }
    const bool marginRay = pC[k - 2] == 0;  // z_1 through the filter margin: no light tracing
    for (int i = 0; i < k; ++i) pL[i] = remap(pL[i]), pC[i] = remap(pC[i]);
    // eta_j in camera order (merge_kernel.h), the light origin excluded.
    std::vector<Float> eta(size_t(k), kernel.piN * kernel.r2);
    if (kernel.varies())
        PathMergeEta(
            kernel, k, [&](int c) -> const PathVertex & { return x.v[k - 1 - c]; },
            [&](int c) { return x.b[k - 1 - c]; },
            [&](int c) { return c + 1 < k && MergeableIn(set, x.v[k - 1 - c], x.b[k - 1 - c]); }, eta.data());
    auto prefix = [&](int s) {  // prod_{i<s} pL prod_{i>=s} pC
        double p = 1;
        for (int i = 0; i < k; ++i) p *= i < s ? pL[i] : pC[i];
        return p;
    };
    Densities D;
    D.vc.assign(size_t(k), 0);
    D.vm.assign(size_t(k), 0);
    for (int s = 0; s < k; ++s) {
        const int t = k - s;
        bool valid;
        if (s == 0)
            valid = t >= 2 && EmitterOf(ctx, x.v[0]) && !x.v[0].isDeltaLight();
        else
            valid = !(s == 1 && t == 1) && !x.v[s].delta() && (s == 1 || !x.v[s - 1].delta()) &&
                    EdgeConnectible(ctx, x.v[s - 1], x.v[s]) && (t > 1 || (set.lightTracing && !marginRay));
        if (valid) D.vc[size_t(s)] = prefix(s);
    }
    for (int j = 1; j + 1 < k; ++j)
        if (x.v[j].type == VertexType::Surface && MergeableIn(set, x.v[j], x.b[j]))
            D.vm[size_t(j)] = prefix(j) * pL[j] * eta[size_t(k - 1 - j)];
    for (double p : D.vc) D.total += p;
    for (double p : D.vm) D.total += p;
    return D;
}

// Eq. 23 for the merge at x_j of the base x and its offset y: with a_S, b_S
// the weights of every strategy S of x and of y and lambda = |T'| P(y) / P(x)
// (P: the sum of all densities), the gradient weights of S from pixel i,
// a_S / (1 + lambda), and from pixel j, lambda b_S / (1 + lambda), sum to one
// over all S. lambda from the connection (j, k - j) of the same pair (G-BDPT's
// rho of that connection: rho_VC a / b = lambda), the merge's own from gvcm:
// CombinedWeight(w_x, w_y, rho) (1 + rho) = w_x (1 + rho) / (1 + rho w_x / w_y).
double PairSum(const Densities &X, const Densities &Y, int j, double rhoVC, Float wx, Float wy, Float rho) {
    const double lambda = rhoVC * X.weightVC(j) / Y.weightVC(j);
    const double others = (1 - X.weightVM(j) + lambda * (1 - Y.weightVM(j))) / (1 + lambda);
    return others + CombinedWeight(wx, wy, rho) * (1 + rho);
}

// The first photon y_m after ideal specular vertices (k >= 1; not from a
// delta light) on the light subpath of `trial`, and a camera subpath aimed at
// it (z_1 = y_m, b = 1) with its shift; lv the photon's record.
struct ChainPhoton {
    ShiftSubpath L;
    int m = 0, d = 0;
    CameraPath c;
    LightVertex lv;
};
bool FindChainPhoton(Fixture &f, int trial, Arena &arena, ChainPhoton *p) {
    const Camera &cam = f.camera();
    f.sampler->startPixelSample({trial % kW, (trial / kW) % kH}, trial / (kW * kH));
    p->L = TraceLight(f, 6, arena);
    const ShiftSubpath &L = p->L;
    for (int m = 2; m < L.n; ++m) {
        const PathVertex &ym = L.v[m];
        if (ym.delta() || !L.v[m - 1].delta() || !f.W.mergeable(ym, &L.b[m])) continue;
        int d = m - 1;
        bool ideal = true;
        while (d > 0 && L.v[d].delta()) ideal = ideal && L.deltaSample[d--];
        CameraWiSample cws;
        if (!ideal || L.v[d].isDeltaLight() || !cam.sampleWi(AsInteraction(ym), Point2(0.5, 0.5), &cws)) continue;
        CameraPath &c = p->c;
        c.cs = {cws.pRaster, Point2(0.5, 0.5)};
        c.off = trial % 2 ? Point2i{1, 0} : Point2i{0, 1};
        Ray ray;
        if (c.cs.pFilm.x < 1 || c.cs.pFilm.x > kW - 2 || c.cs.pFilm.y < 1 || c.cs.pFilm.y > kH - 2 ||
            cam.generateRay(c.cs, &ray) == 0)
            continue;
        c.x = ArenaSubpath(arena, 4);
        c.x.n = GenerateCameraSubpath(*f.bc, ray, *f.sampler, arena, 4, c.x.v, c.x.b);
        PrepareSubpath(*f.sc, &c.x);
        if (c.x.n < 2 || Distance(c.x.v[1].p, ym.p) > 1e-4 || FirstConnectable(f, c.x) != 1) continue;
        SubpathShiftStats st;
        ShiftCameraSubpath(*f.sc, c.x, c.cs, c.off, arena, &c.sh, &st);
        std::vector<LightVertex> recs;
        VCMLightVertices(*f.bc, L.v, L.b, L.n, f.W, &recs);
        for (const LightVertex &r : recs)
            if (r.depth == m) {
                p->m = m;
                p->d = d;
                p->lv = r;
                return true;
            }
    }
    return false;
}

// The merges' weights on random paths: case-1 merges at z_u >= r (photons at
// z_u from random light prefixes), case-2 merges at z_b with empty chains
// (photons at z_b; y_{m-1} matte, where gvcm's offset weight reuses the base's
// light-side sum exactly, gvcm.h), and the base weights of specular-chain
// photons (the camera aimed at them). w_x (Eq. 13), the offset's w_y (Eq. 13
// on the offset path with its own kernel, Eq. 22) and the pair's Eq. 23 sum
// against Enumerate; tolerance as the values' (Tolerance over every edge).
void CheckMergeWeights(KernelKind kind) {
    Fixture f(kind);
    Arena arena;
    ErrStats ex, ey, ep;
    int case1 = 0, case2 = 0, chains = 0, paired = 0, glossyPrev = 0;
    double glossyPrevMax = 0;
    for (int trial = 0; trial < 40000 && (case1 < 200 || case2 < 200); ++trial) {
        arena.reset();
        CameraPath c;
        if (!TraceCamera(f, trial, 6, arena, &c)) continue;
        const ShiftSubpath &x = c.x, &y = c.sh.y;
        const int b = FirstConnectable(f, x);
        if (b < 1 || c.sh.validUpTo < b || HasCorner(x, c.sh.validUpTo + 1) || HasCorner(y, c.sh.validUpTo + 1))
            continue;
        ShiftSubpath L = TraceLight(f, 4, arena);
        const int m = 1 + trial % L.n;
        // One merge vertex per path: z_b (case 2 unless b >= r) or, for case 1, a vertex past r.
        int u = b;
        if (c.sh.r >= 0 && trial % 3 != 0) u = c.sh.r + (trial / 3) % std::max(1, c.sh.validUpTo - c.sh.r + 1);
        if (u > c.sh.validUpTo || x.v[u].type != VertexType::Surface || !x.b[u] || !f.W.mergeable(x.v[u], &x.b[u]))
            continue;
        const bool isCase1 = c.sh.r >= 0 && u >= c.sh.r;
        if ((isCase1 ? case1 : case2) >= 200) continue;
        ShiftSubpath Lp;
        LightVertex lv;
        if (!SyntheticPhoton(f, L, m, x.v[u], x.b[u], x.v[u].p, arena, &Lp, &lv)) continue;
        const int ny = std::min(y.n, c.sh.validUpTo + 1);
        Float etaX, etaY;
        const VCMCameraTerms tx = Terms(f, x, x.n, u, arena, &etaX), ty = Terms(f, y, ny, u, arena, &etaY);
        const Float wx = GVCMTestAccess::mergeWeight(tx, x.v[u], x.v[u - 1], x.b[u], lv, f.W);
        const Spectrum fu = x.b[u].f(Vec3(x.v[u].wo), lv.wo, TransportMode::Radiance);
        Offset o;
        const bool ok = isCase1 ? GVCMTestAccess::case1(*f.g, c.sh, u, x.b[u], lv, fu, etaX, &ty, &o)
                                : GVCMTestAccess::case2(*f.g, Lp, m, c.sh, u, lv, &ty, etaX, arena, &o);
        double sensX = 0, sensY = 0;
        const Densities X = Enumerate(f, Join(Lp, m, x, u + 1), &sensX);
        const double tol = Tolerance(sensX);
        const double eX = std::abs(wx / X.weightVM(m) - 1);
        EXPECT_LT(eX, tol) << "w_x " << wx << ", enumerated " << X.weightVM(m) << "; u " << u << " m " << m
                           << " trial " << trial;
        ex.add(eX);
        if (!ok) continue;
        const Densities Y = Enumerate(f, Join(Lp, m, y, u + 1), &sensY);
        const double eY = std::abs(o.w / Y.weightVM(m) - 1);
        // y_{m-1} glossy: the offset's own light-side densities differ from the photon's
        // stored B_m (case2Weight); counted apart.
        const bool matte = m == 1 || Lp.b[m - 1].flags() == (BSDF_DIFFUSE | BSDF_REFLECTION);
        if (!isCase1 && !matte) {
            ++glossyPrev;
            glossyPrevMax = std::max(glossyPrevMax, eY);
        }
        EXPECT_LT(eY, Tolerance(sensY)) << (isCase1 ? "case 1" : "case 2") << " w_y " << o.w << ", enumerated "
                                          << Y.weightVM(m) << "; u " << u << " m " << m << " trial " << trial;
        ey.add(eY);
        (isCase1 ? case1 : case2)++;
        // Eq. 23 with the connection (m, u + 1) of the same pair (y_{m-1} is connectable).
        if (X.vc[size_t(m)] > 0 && Y.vc[size_t(m)] > 0) {
            const double sum = PairSum(X, Y, m, c.sh.rho[u], wx, o.w, o.rho);
            EXPECT_NEAR(sum, 1, Tolerance(sensX + sensY)) << (isCase1 ? "case 1" : "case 2") << " u " << u << " m " << m
                                                    << " trial " << trial;
            ep.add(std::abs(sum - 1));
            ++paired;
        }
    }
    // Specular-chain photons: the base's weight (the offset's is approximate: gvcm.h).
    for (int trial = 0; trial < 200000 && chains < 100; ++trial) {
        arena.reset();
        ChainPhoton p;
        if (!FindChainPhoton(f, trial, arena, &p)) continue;
        const ShiftSubpath &z = p.c.x;
        Float etaX;
        const VCMCameraTerms tx = Terms(f, z, z.n, 1, arena, &etaX);
        const Float wx = GVCMTestAccess::mergeWeight(tx, z.v[1], z.v[0], z.b[1], p.lv, f.W);
        double sens = 0;
        const Densities X = Enumerate(f, Join(p.L, p.m, z, 2), &sens);
        const double eX = std::abs(wx / X.weightVM(p.m) - 1);
        EXPECT_LT(eX, Tolerance(sens)) << "chain photon: w_x " << wx << ", enumerated " << X.weightVM(p.m);
        ex.add(eX);
        ++chains;
    }
    EXPECT_GE(case1, 200);
    EXPECT_GE(case2, 200);
    EXPECT_GE(chains, 100);
    EXPECT_GE(paired, 300);
    std::printf("merge weights (%s kernel): w_x of %d merges (%d after specular chains), w_y of %d case-1 and %d "
                "case-2 offsets, %d Eq. 23 pair sums; max relative error w_x %.2e, w_y %.2e, max |sum - 1| %.2e; "
                "case 2 after a glossy y_{m-1}: %d, max relative error of w_y %.2e\n",
                kind == KernelKind::Fixed ? "fixed" : "footprint", ex.n, chains, case1, case2, paired, ex.max,
                ey.max, ep.max, glossyPrev, glossyPrevMax);
}

// Specular chains (Eqs. 19-20): photons of random light subpaths after ideal
// specular vertices (the glass sphere's caustics, the mirror's reflections),
// the camera aimed at them (z_1 = y_m, b = 1); the offset chain from y_d to
// z'_1 found by the reference's own Newton search.
void CheckCase2Chains() {
    Fixture f;
    Arena arena;
    ErrStats ef, er;
    int byK[4] = {}, fromLight = 0, failed = 0, missed = 0;
    std::vector<double> errs, chainW;
    for (int trial = 0; trial < 200000 && ef.n < 200; ++trial) {
        arena.reset();
        ChainPhoton p;
        if (!FindChainPhoton(f, trial, arena, &p)) continue;
        const CameraPath &c = p.c;
        const ShiftSubpath &L = p.L, &x = c.x, &y = c.sh.y;
        const int m = p.m, d = p.d;
        const LightVertex *lv = &p.lv;
        if (c.sh.validUpTo < 1 || HasCorner(y, 2)) continue;
        Float etaX, etaY;
        Terms(f, x, x.n, 1, arena, &etaX);
        const VCMCameraTerms ty = Terms(f, y, std::min(y.n, c.sh.validUpTo + 1), 1, arena, &etaY);
        Offset o;
        if (!GVCMTestAccess::case2(*f.g, L, m, c.sh, 1, *lv, &ty, etaX, arena, &o)) {
            ++failed;  // the walk failed or was not reversible, occluded
            continue;
        }
        Case2Ref ref;
        if (!Case2Reference(f, arena, L, m, c, 1, &ref)) {
            ++missed;
            continue;
        }
        const Spectrum fx = x.v[1].throughput() * x.b[1].f(Vec3(x.v[1].wo), lv->wo, TransportMode::Radiance) *
                            lv->throughput() / etaX;
        const Spectrum ratio = SafeDiv(o.f, fx);
        const double eF = RelErr(ratio, ref.ratio), eR = std::abs(o.rho / ref.rho - 1);
        EXPECT_LT(eF, ref.tol) << "k " << m - 1 - d << " trial " << trial << ": o.f / f_x " << ratio.r << " "
                               << ratio.g << " " << ratio.b << ", reference " << ref.ratio.r << " "
                               << ref.ratio.g << " " << ref.ratio.b;
        EXPECT_LT(eR, ref.tol) << "k " << m - 1 - d << " trial " << trial << ": rho " << o.rho << ", reference "
                               << ref.rho;
        ef.add(eF);
        er.add(eR);
        errs.push_back(std::max(eF, eR));
        // The offset's weight against the enumerated strategies of y_0 .. y_d,
        // y'_{d+1} .. y'_{m-1} (the reference's own chain), z'_1, z'_0; tolerance
        // as the value's plus the enumeration's edges.
        FullPath yp;
        for (int i = 0; i <= d; ++i) yp.v.push_back(L.v[i]), yp.b.push_back(&L.b[i]);
        for (size_t i = 0; i < ref.offsetChain.v.size(); ++i)
            yp.v.push_back(ref.offsetChain.v[i]), yp.b.push_back(&ref.offsetChain.b[i]);
        for (int i = 1; i >= 0; --i) yp.v.push_back(y.v[i]), yp.b.push_back(&y.b[i]);
        double sens = 0;
        const double eW = std::abs(o.w / Enumerate(f, yp, &sens).weightVM(m) - 1);
        EXPECT_LT(eW, ref.tol + Tolerance(sens)) << "k " << m - 1 - d << " trial " << trial << ": w_y " << o.w;
        chainW.push_back(eW);
        ++byK[std::min(m - 1 - d, 3)];
        fromLight += d == 0;
    }
    EXPECT_GE(ef.n, 200);
    EXPECT_GE(byK[1], 20) << "one-vertex chains (the mirror)";
    EXPECT_GE(byK[2] + byK[3], 40) << "chains through the glass sphere";
    EXPECT_LE(missed, ef.n / 20) << "chains the reference's search did not find";
    // Most chains' finite differences are far from their tolerance's truncation
    // bound: the median error is at the level of the hits' noise (1e-6 over
    // 1e-3 rad steps).
    std::sort(errs.begin(), errs.end());
    const double median = errs.empty() ? 1 : errs[errs.size() / 2];
    EXPECT_LT(median, 1e-3);
    std::sort(chainW.begin(), chainW.end());
    std::printf("case 2, specular chains: %d offsets (%d of one vertex, %d of two, %d longer; %d from the light), %d "
                "fell back, %d missed by the reference; relative errors: median %.2e, max of the value %.2e, of rho %.2e; "
                "the offsets' MIS weights relative to the enumerated: median %.2e, max %.2e\n",
                ef.n, byK[1], byK[2], byK[3], fromLight, failed, missed, median, ef.max, er.max,
                chainW.empty() ? 0.0 : chainW[chainW.size() / 2], chainW.empty() ? 0.0 : chainW.back());
}

}  // namespace
}  // namespace gradus

using namespace gradus;

TEST(GVCMPieces, Case1OffsetMatchesReevaluatedPath) { CheckCase1(KernelKind::Fixed); }
TEST(GVCMPieces, Case1OffsetKeepsTheBaseKernel) { CheckCase1(KernelKind::Footprint); }
TEST(GVCMPieces, Case2EmptyChainMatchesReevaluatedPath) { CheckCase2Empty(KernelKind::Fixed); }
TEST(GVCMPieces, Case2EmptyChainKeepsTheBaseKernel) { CheckCase2Empty(KernelKind::Footprint); }
TEST(GVCMPieces, Case2SpecularChainMatchesReevaluatedPath) { CheckCase2Chains(); }
TEST(GVCMPieces, MergeWeightsMatchEnumeratedStrategies) { CheckMergeWeights(KernelKind::Fixed); }
TEST(GVCMPieces, MergeWeightsMatchEnumeratedStrategiesFootprintKernel) { CheckMergeWeights(KernelKind::Footprint); }
