#include "media/medium.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "parser/scene_desc.h"

namespace gradus {

// ---------------------------------------------------------------- phase function
Float HenyeyGreenstein(Float cosTheta, Float g) {
    // cosTheta: between the propagation direction and the scattered one.
    const Float denom = 1 + g * g - 2 * g * cosTheta;
    return (1 - g * g) / (4 * Pi * denom * std::sqrt(std::max<Float>(denom, 0)));
}

Float HGPhase::p(const Vec3 &wo, const Vec3 &wi) const {
    // wo points back along the arriving ray: the propagation direction is -wo.
    return HenyeyGreenstein(-Dot(wo, wi), g);
}

Float HGPhase::sample(const Vec3 &wo, Point2 u, Vec3 *wi) const {
    // Inverse of the HG cdf in cos(theta) (Henyey & Greenstein 1941; isotropic below |g| 1e-3).
    Float cosTheta;
    if (std::abs(g) < 1e-3) {
        cosTheta = 1 - 2 * u.x;
    } else {
        const Float s = (1 - g * g) / (1 - g + 2 * g * u.x);
        cosTheta = std::clamp<Float>((1 + g * g - s * s) / (2 * g), -1, 1);
    }
    const Float sinTheta = std::sqrt(std::max<Float>(0, 1 - cosTheta * cosTheta));
    const Float phi = 2 * Pi * u.y;
    const Vec3 fwd = -wo;
    Vec3 s, t;
    CoordinateSystem(fwd, &s, &t);
    *wi = s * (sinTheta * std::cos(phi)) + t * (sinTheta * std::sin(phi)) + fwd * cosTheta;
    return HenyeyGreenstein(cosTheta, g);
}

void Medium::ScatterAt(const Ray &ray, Float dist, Float len, MediumInteraction *mi) const {
    mi->p = ray.o + ray.d * (dist / len);
    mi->n = Normal3(0, 0, 0);
    mi->wo = -ray.d / len;
    mi->medium = this;
    mi->phase = phase;
}

// ---------------------------------------------------------------- homogeneous
HomogeneousMedium::HomogeneousMedium(const Spectrum &sa, const Spectrum &ss, Float g)
    : sigmaA(sa), sigmaS(ss), sigmaT(sa + ss) {
    phase.g = g;
}

bool HomogeneousMedium::greySigmaT() const { return sigmaT.r == sigmaT.g && sigmaT.g == sigmaT.b; }

namespace {
// Distance in world units, capped so that 0 * distance stays 0.
Float CappedDistance(const Ray &ray) { return std::min<Float>(ray.tMax * ray.d.length(), 1e300); }
Spectrum ExpNeg(const Spectrum &sigma, Float d) {
    return Spectrum(std::exp(-sigma.r * d), std::exp(-sigma.g * d), std::exp(-sigma.b * d));
}
}  // namespace

Spectrum HomogeneousMedium::Tr(const Ray &ray, UniformSource) const { return ExpNeg(sigmaT, CappedDistance(ray)); }

bool HomogeneousMedium::support(const Ray &ray, Float *t0, Float *t1) const {
    *t0 = 0;
    *t1 = ray.tMax * ray.d.length();
    return sigmaT.maxComponent() > 0;
}

// Spectral MIS distance sampling (pbrt-v3 Sec. 15.2.1): a channel chosen
// uniformly, the distance from its exponential; the pdf is the average over
// channels (the one-sample MIS of the three exponentials).
Spectrum HomogeneousMedium::sample(const Ray &ray, UniformSource rng, MediumInteraction *mi) const {
    const Float len = ray.d.length();
    const int ch = std::min(int(rng.uniform() * 3), 2);
    const Float dist = sigmaT[ch] > 0 ? -std::log(1 - rng.uniform()) / sigmaT[ch] : Infinity;
    const Float tWorldMax = CappedDistance(ray);
    const bool scattered = dist < tWorldMax;
    const Float d = scattered ? dist : tWorldMax;
    const Spectrum tr = ExpNeg(sigmaT, d);
    const Spectrum density = scattered ? sigmaT * tr : tr;
    const Float pdf = density.average();
    if (pdf <= 0) return Spectrum(0);
    if (scattered) {
        ScatterAt(ray, d, len, mi);
        return tr * sigmaS / pdf;
    }
    return tr / pdf;
}

// ---------------------------------------------------------------- grid
GridMedium::GridMedium(const Spectrum &sa, const Spectrum &ss, Float g, const Transform &worldFromMedium, Point3 p0,
                       Point3 p1, int nx, int ny, int nz, std::vector<Float> density)
    : sigmaA_(sa), sigmaS_(ss), sigmaT_((sa + ss).r), p0_(p0), p1_(p1), nx_(nx), ny_(ny), nz_(nz),
      density_(std::move(density)) {
    phase.g = g;
    // Grid space: the unit cube spanning [p0, p1] of the medium's space.
    const Transform worldFromGrid =
        worldFromMedium * Translate(Vec3(p0.x, p0.y, p0.z)) * Scale(p1.x - p0.x, p1.y - p0.y, p1.z - p0.z);
    mediumFromWorld_ = worldFromGrid.inverse();
    for (Float v : density_) maxDensity_ = std::max(maxDensity_, v);
    // Majorant cells: the density at p reads voxels floor(p n - 1/2) and the
    // next one on each axis, so a cell [lo, hi] depends on voxels
    // floor(lo n - 1/2) .. floor(hi n - 1/2) + 1 (clamped to the grid).
    const int n[3] = {nx_, ny_, nz_};
    int lo[3][16], hi[3][16];
    for (int a = 0; a < 3; ++a) {
        m_[a] = std::min(n[a], 16);
        for (int c = 0; c < m_[a]; ++c) {
            lo[a][c] = std::max(0, int(std::floor(Float(c) / m_[a] * n[a] - 0.5)));
            hi[a][c] = std::min(n[a] - 1, int(std::floor(Float(c + 1) / m_[a] * n[a] - 0.5)) + 1);
        }
    }
    majorant_.assign(size_t(m_[0]) * m_[1] * m_[2], 0);
    for (int cz = 0; cz < m_[2]; ++cz)
        for (int cy = 0; cy < m_[1]; ++cy)
            for (int cx = 0; cx < m_[0]; ++cx) {
                Float mx = 0;
                for (int z = lo[2][cz]; z <= hi[2][cz]; ++z)
                    for (int y = lo[1][cy]; y <= hi[1][cy]; ++y)
                        for (int x = lo[0][cx]; x <= hi[0][cx]; ++x) mx = std::max(mx, d(x, y, z));
                majorant_[(size_t(cz) * m_[1] + cy) * m_[0] + cx] = mx;
            }
}

// 3-D DDA over the majorant cells (Amanatides & Woo 1987).
template <class Visit>
void GridMedium::traverse(const Ray &local, Float t0, Float t1, Visit &&visit) const {
    const Point3 p = local(t0);
    int cell[3], step[3];
    Float tNext[3], tDelta[3];
    for (int a = 0; a < 3; ++a) {
        cell[a] = std::clamp(int(p[a] * m_[a]), 0, m_[a] - 1);
        const Float dir = local.d[a];
        if (dir > 0) {
            step[a] = 1;
            tNext[a] = t0 + (Float(cell[a] + 1) / m_[a] - p[a]) / dir;
            tDelta[a] = 1 / (m_[a] * dir);
        } else if (dir < 0) {
            step[a] = -1;
            tNext[a] = t0 + (Float(cell[a]) / m_[a] - p[a]) / dir;
            tDelta[a] = -1 / (m_[a] * dir);
        } else {
            step[a] = 0;
            tNext[a] = Infinity;
            tDelta[a] = Infinity;
        }
    }
    Float t = t0;
    for (;;) {
        const int a = tNext[0] < tNext[1] ? (tNext[0] < tNext[2] ? 0 : 2) : (tNext[1] < tNext[2] ? 1 : 2);
        const Float tb = std::min(tNext[a], t1);
        if (tb > t && !visit(majorant_[(size_t(cell[2]) * m_[1] + cell[1]) * m_[0] + cell[0]], t, tb)) return;
        if (tb >= t1) return;
        t = tb;
        cell[a] += step[a];
        if (cell[a] < 0 || cell[a] >= m_[a]) return;
        tNext[a] += tDelta[a];
    }
}

Float GridMedium::d(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= nx_ || y >= ny_ || z >= nz_) return 0;
    return density_[(size_t(z) * ny_ + y) * nx_ + x];
}

// Trilinear interpolation of the voxel-centre values; p in grid space [0,1]^3.
Float GridMedium::density(const Point3 &p) const {
    const Float gx = p.x * nx_ - 0.5, gy = p.y * ny_ - 0.5, gz = p.z * nz_ - 0.5;
    const Float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    const int ix = int(fx), iy = int(fy), iz = int(fz);
    const Float tx = gx - fx, ty = gy - fy, tz = gz - fz;
    auto lerp = [](Float t, Float a, Float b) { return (1 - t) * a + t * b; };
    const Float d00 = lerp(tx, d(ix, iy, iz), d(ix + 1, iy, iz));
    const Float d10 = lerp(tx, d(ix, iy + 1, iz), d(ix + 1, iy + 1, iz));
    const Float d01 = lerp(tx, d(ix, iy, iz + 1), d(ix + 1, iy, iz + 1));
    const Float d11 = lerp(tx, d(ix, iy + 1, iz + 1), d(ix + 1, iy + 1, iz + 1));
    return lerp(tz, lerp(ty, d00, d10), lerp(ty, d01, d11));
}

// The ray with a unit world direction, in grid space (t stays world distance),
// clipped to the unit cube and to [0, tMax]. False when it misses.
bool GridMedium::clip(const Ray &ray, Ray *local, Float *t0, Float *t1) const {
    const Float len = ray.d.length();
    if (!(len > 0)) return false;
    local->o = mediumFromWorld_.applyPoint(ray.o);
    local->d = mediumFromWorld_.applyVector(ray.d / len);
    Float lo = 0, hi = std::min<Float>(ray.tMax * len, 1e300);
    for (int a = 0; a < 3; ++a) {
        const Float o = local->o[a], dir = local->d[a];
        if (dir == 0) {
            if (o < 0 || o > 1) return false;
            continue;
        }
        Float ta = (0 - o) / dir, tb = (1 - o) / dir;
        if (ta > tb) std::swap(ta, tb);
        lo = std::max(lo, ta);
        hi = std::min(hi, tb);
        if (lo > hi) return false;
    }
    *t0 = lo;
    *t1 = hi;
    return true;
}

Spectrum GridMedium::sigmaTAt(const Point3 &pWorld) const {
    const Point3 p = mediumFromWorld_.applyPoint(pWorld);
    if (p.x < 0 || p.y < 0 || p.z < 0 || p.x > 1 || p.y > 1 || p.z > 1) return Spectrum(0);
    return Spectrum(sigmaT_ * density(p));
}

bool GridMedium::support(const Ray &ray, Float *t0, Float *t1) const {
    Ray local;
    return maxDensity_ > 0 && sigmaT_ > 0 && clip(ray, &local, t0, t1);
}

// Ratio tracking (Novak et al. 2014, Sec. 4.2) against the cells' majorants
// sigma_t * max d (the exponential steps restart at each cell boundary: memoryless).
Spectrum GridMedium::Tr(const Ray &ray, UniformSource rng) const {
    Ray local;
    Float t0, t1;
    if (maxDensity_ <= 0 || sigmaT_ <= 0 || !clip(ray, &local, &t0, &t1)) return Spectrum(1);
    Float tr = 1;
    traverse(local, t0, t1, [&](Float maxD, Float ta, Float tb) {
        if (maxD <= 0) return true;
        const Float invMajorant = 1 / (sigmaT_ * maxD);
        for (Float t = ta;;) {
            t -= std::log(1 - rng.uniform()) * invMajorant;
            if (t >= tb) return true;
            tr *= 1 - std::max<Float>(0, density(local(t)) / maxD);
            if (tr <= 0) return false;
        }
    });
    return Spectrum(std::max<Float>(tr, 0));
}

// Delta tracking (Woodcock et al. 1965; Novak et al. 2014, Sec. 4.1) against
// the cells' majorants: a tentative collision is real with probability
// d(p) / max d of its cell; a real one scatters with the albedo
// sigma_s / sigma_t as throughput factor (absorption folded in).
Spectrum GridMedium::sample(const Ray &ray, UniformSource rng, MediumInteraction *mi) const {
    Ray local;
    Float t0, t1;
    if (maxDensity_ <= 0 || sigmaT_ <= 0 || !clip(ray, &local, &t0, &t1)) return Spectrum(1);
    Float tHit = -1;
    traverse(local, t0, t1, [&](Float maxD, Float ta, Float tb) {
        if (maxD <= 0) return true;
        const Float invMajorant = 1 / (sigmaT_ * maxD);
        for (Float t = ta;;) {
            t -= std::log(1 - rng.uniform()) * invMajorant;
            if (t >= tb) return true;
            if (density(local(t)) / maxD > rng.uniform()) {
                tHit = t;
                return false;
            }
        }
    });
    if (tHit < 0) return Spectrum(1);
    ScatterAt(ray, tHit, ray.d.length(), mi);
    return sigmaS_ / sigmaT_;
}

// ---------------------------------------------------------------- creation
namespace {
void CheckCoefficient(const ParamSet &ps, const char *name, const Spectrum &s, const FileLoc &loc) {
    for (int c = 0; c < 3; ++c)
        if (!std::isfinite(s[c]) || s[c] < 0)
            throw Error(ps.locOf(name, loc), std::string("medium parameter \"") + name +
                                                 "\" must be finite and non-negative");
}
}  // namespace

std::shared_ptr<Medium> CreateMedium(const MediumDesc &desc) {
    const ParamSet &ps = desc.params;
    const FileLoc &loc = desc.loc;
    const std::string what = "MakeNamedMedium \"" + desc.name + "\"";
    // pbrt-v3's defaults (whole milk, mm^-1).
    Spectrum sa(0.0011, 0.0024, 0.014), ss(2.55, 3.21, 3.77);
    const std::string preset = ps.getString("preset", "");
    if (!preset.empty()) {
        if (!MediumPreset(preset, &sa, &ss))
            throw Error(ps.locOf("preset", loc), what + ": unknown preset \"" + preset + "\"");
    } else {
        sa = ps.getSpectrum("sigma_a", sa);
        ss = ps.getSpectrum("sigma_s", ss);
        CheckCoefficient(ps, "sigma_a", sa, loc);
        CheckCoefficient(ps, "sigma_s", ss, loc);
    }
    const Float scale = ps.getFloat("scale", 1);
    if (!std::isfinite(scale) || scale < 0)
        throw Error(ps.locOf("scale", loc), what + ": \"scale\" must be finite and non-negative");
    const Float g = ps.getFloat("g", 0);
    if (!(std::abs(g) < 1))
        throw Error(ps.locOf("g", loc), what + ": \"g\" must lie in (-1, 1)");
    sa = sa * scale;
    ss = ss * scale;
    std::shared_ptr<Medium> m;
    if (desc.type == "homogeneous") {
        m = std::make_shared<HomogeneousMedium>(sa, ss, g);
    } else if (desc.type == "heterogeneous") {
        const int nx = ps.getInt("nx", 1), ny = ps.getInt("ny", 1), nz = ps.getInt("nz", 1);
        for (const char *n : {"nx", "ny", "nz"})
            if (ps.getInt(n, 1) < 1) throw Error(ps.locOf(n, loc), what + ": \"" + n + "\" must be at least 1");
        const Point3 p0 = ps.getPoint3("p0", Point3(0, 0, 0)), p1 = ps.getPoint3("p1", Point3(1, 1, 1));
        if (!(p1.x > p0.x && p1.y > p0.y && p1.z > p0.z))
            throw Error(ps.locOf("p1", loc), what + ": \"p1\" must exceed \"p0\" in every coordinate");
        std::vector<Float> density = ps.getFloats("density");
        const size_t want = size_t(nx) * ny * nz;
        if (density.size() != want)
            throw Error(ps.locOf("density", loc), what + ": \"density\" has " + std::to_string(density.size()) +
                                                      " values, nx*ny*nz = " + std::to_string(want));
        for (Float v : density)
            if (!std::isfinite(v) || v < 0)
                throw Error(ps.locOf("density", loc), what + ": \"density\" values must be finite and non-negative");
        const Spectrum st = sa + ss;
        if (!(st.r == st.g && st.g == st.b))
            throw Error(ps.locOf(preset.empty() ? "sigma_a" : "preset", loc),
                        what + ": a heterogeneous medium needs a spectrally uniform sigma_t = sigma_a + sigma_s "
                               "(delta tracking against one majorant), got (" +
                            std::to_string(st.r) + ", " + std::to_string(st.g) + ", " + std::to_string(st.b) + ")");
        m = std::make_shared<GridMedium>(sa, ss, g, desc.worldFromMedium, p0, p1, nx, ny, nz, std::move(density));
    } else {
        throw Error(loc, what + ": unknown medium type \"" + desc.type + "\" (homogeneous, heterogeneous)");
    }
    m->name = desc.name;
    return m;
}

}  // namespace gradus
