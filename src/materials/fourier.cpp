#include "materials/fourier.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/error.h"
#include "materials/bssrdf.h"  // Catmull-Rom weights, integration and 2-D sampling
#include "materials/bxdf_util.h"
#include "materials/material_util.h"

namespace gradus {
namespace {

// Header of a .bsdf file (layerlab's storage format, version 1): 8 identifier bytes
// "SCATFUN" + version, then little-endian int32 flags, nMu, nCoeffs, mMax, nChannels,
// nBases, nMetadataBytes, nParameters, nParameterValues, float32 eta, 4 reserved int32.
constexpr size_t kHeaderBytes = 64;

class ByteReader {
  public:
    explicit ByteReader(const std::string &d) : d_(d) {}
    uint32_t u32() {
        uint32_t v = 0;
        for (int k = 0; k < 4; ++k) v |= uint32_t(uint8_t(d_[pos_ + k])) << (8 * k);
        pos_ += 4;
        return v;
    }
    int32_t i32() {
        uint32_t u = u32();
        int32_t v;
        std::memcpy(&v, &u, 4);
        return v;
    }
    float f32() {
        uint32_t u = u32();
        float v;
        std::memcpy(&v, &u, 4);
        return v;
    }
    size_t pos() const { return pos_; }
    void seek(size_t p) { pos_ = p; }

  private:
    const std::string &d_;
    size_t pos_ = 0;
};

// Sign of a node including the sign of zero: layerlab tables list -0 and +0 as the
// grazing limits of the two hemispheres.
int SideOf(Float mu) { return std::signbit(mu) ? -1 : 1; }

// cos of the azimuth difference of a and b; 1 when either has no azimuth (pbrt-v3's choice).
Float CosDPhi(const Vec3 &a, const Vec3 &b) {
    Float d = (a.x * a.x + a.y * a.y) * (b.x * b.x + b.y * b.y);
    if (!(d > 0)) return 1;
    return Clamp<Float>((a.x * b.x + a.y * b.y) / std::sqrt(d), -1, 1);
}

// sum_k a[k] cos(k phi) by the Chebyshev recurrence cos(k phi) = 2 cos(phi) cos((k-1) phi) - cos((k-2) phi).
double Series(const double *a, int m, double cosPhi) {
    double sum = 0, ck = 1, ckm1 = cosPhi;
    for (int k = 0; k < m; ++k) {
        sum += a[k] * ck;
        double next = 2 * cosPhi * ck - ckm1;
        ckm1 = ck;
        ck = next;
    }
    return sum;
}

// Samples phi in [0, 2 pi) proportionally to Y(phi) = sum_k a_k cos(k phi) (assumed
// non-negative). Y is even, so phi is found in [0, pi] by inverting the integral
// F(phi) = a_0 phi + sum_{k>=1} a_k sin(k phi) / k with safeguarded Newton steps, and
// reflected to (pi, 2 pi) for half of the u range (the idea of pbrt-v3's SampleFourier).
bool SampleFourierPhi(const double *a, int m, Float u, Float *phiOut) {
    if (m < 1 || !(a[0] > 0)) return false;
    bool flip = u >= 0.5;
    u = flip ? 2 * u - 1 : 2 * u;
    double target = std::min<double>(u, 1) * Pi * a[0];
    double lo = 0, hi = Pi, phi = u * Pi;
    for (int it = 0; it < 100; ++it) {
        if (!(phi >= lo && phi <= hi)) phi = 0.5 * (lo + hi);
        double c = std::cos(phi), s = std::sin(phi);
        // F and F' = Y together: cos(k phi), sin(k phi) by the same recurrence.
        double F = a[0] * phi, Y = a[0];
        double ckm1 = 1, ck = c, skm1 = 0, sk = s;
        for (int k = 1; k < m; ++k) {
            F += a[k] * sk / k;
            Y += a[k] * ck;
            double cn = 2 * c * ck - ckm1, sn = 2 * c * sk - skm1;
            ckm1 = ck, ck = cn, skm1 = sk, sk = sn;
        }
        double err = F - target;
        if (std::abs(err) < 1e-12 * Pi * a[0] || hi - lo < 1e-13) break;
        if (err < 0) lo = phi; else hi = phi;
        phi = Y > 0 ? phi - err / Y : 0.5 * (lo + hi);
    }
    phi = Clamp<double>(phi, 0, Pi);
    *phiOut = flip ? 2 * Pi - phi : phi;
    return true;
}

// The mu_o nodes a query at mu_o interpolates between: those of wo's hemisphere
// (sign of zero included) when each side has at least two, else all of them. The
// tabulated function jumps at mu_o = 0 (reflection above, transmission below); a
// Catmull-Rom stencil across the jump mixes the two tables and can go negative near
// grazing angles, where sample() and pdf() would then disagree. pbrt-v3 interpolates
// across it; Gradus differs only for |mu_o| below the first node of a side, where the
// side's nearest node row is used.
struct RowRange {
    int start, count;
    Float muO;  // mu_o clamped to the range
};
RowRange RowsFor(const FourierTable &t, Float muO) {
    RowRange r{0, t.nMu, muO};
    int neg = t.posStart, pos = t.nMu - t.posStart;
    if (neg >= 2 && pos >= 2) {
        if (std::signbit(muO)) r.count = neg;
        else r.start = neg, r.count = pos;
        r.muO = Clamp<Float>(muO, t.mu[r.start], t.mu[r.start + r.count - 1]);
    }
    return r;
}

// Catmull-Rom weights of both cosines (Jakob et al. 2014, Sec. 6: the coefficients
// are splines in mu_i and mu_o); false when either lies outside the node range.
struct Weights {
    int offI, offO;  // offO is absolute (row index into the tables)
    Float wI[4], wO[4];
};
bool MuOWeights(const FourierTable &t, Float muO, Weights *w) {
    RowRange r = RowsFor(t, muO);
    if (!CatmullRomWeights(r.count, t.mu.data() + r.start, r.muO, &w->offO, w->wO)) return false;
    w->offO += r.start;
    // Nodes outside the side get weight 0 (as outside the table).
    for (int b = 0; b < 4; ++b) {
        int o = w->offO + b;
        if (o < r.start || o >= r.start + r.count) w->wO[b] = 0;
    }
    return true;
}
bool LookupWeights(const FourierTable &t, Float muI, Float muO, Weights *w) {
    return CatmullRomWeights(t.nMu, t.mu.data(), muI, &w->offI, w->wI) && MuOWeights(t, muO, w);
}

// Per-thread scratch space for interpolated coefficients (the order is only known per file).
double *Scratch(size_t n) {
    thread_local std::vector<double> buf;
    if (buf.size() < n) buf.resize(n);
    return buf.data();
}

// Interpolated series a_k(mu_i, mu_o) of the first nCh channels into ak (channel c at
// ak + c * t.mMax); returns the number of orders present.
int Interpolate(const FourierTable &t, const Weights &w, int nCh, double *ak) {
    std::fill(ak, ak + size_t(nCh) * t.mMax, 0.0);
    int m = 0;
    for (int b = 0; b < 4; ++b) {
        int o = w.offO + b;
        if (w.wO[b] == 0 || o < 0 || o >= t.nMu) continue;
        for (int a = 0; a < 4; ++a) {
            int i = w.offI + a;
            if (w.wI[a] == 0 || i < 0 || i >= t.nMu) continue;
            double weight = w.wI[a] * w.wO[b];
            size_t e = size_t(o) * t.nMu + i;
            int len = t.length[e];
            const Float *src = t.coeffs.data() + t.offset[e];
            m = std::max(m, len);
            for (int c = 0; c < nCh; ++c)
                for (int k = 0; k < len; ++k) ak[size_t(c) * t.mMax + k] += weight * src[size_t(c) * len + k];
        }
    }
    return m;
}

// Whether the table scatters between these cosines: a file with no coefficients on one
// side (e.g. an opaque layer stack) keeps the spline's leakage near grazing angles out.
bool Allowed(const FourierTable &t, Float muI, Float muO) {
    return muI * muO > 0 ? t.transmits : t.reflects;
}

// 1/|mu_i| (the table stores f |mu_i|) times pbrt-v3's transmission scaling for
// radiance: (1/eta)^2 when light comes from inside (mu_i > 0), eta^2 from outside.
Float Scale(const FourierTable &t, Float muI, Float muO, TransportMode mode) {
    if (muI == 0) return 0;
    Float s = 1 / std::abs(muI);
    if (mode == TransportMode::Radiance && muI * muO > 0) {
        Float e = muI > 0 ? 1 / t.eta : t.eta;
        s *= e * e;
    }
    return s;
}

// Integral over mu_i of the interpolated a_0 row at mu_o (the normalisation of sampling).
Float RowIntegral(const FourierTable &t, const Weights &w) {
    Float total = 0;
    for (int b = 0; b < 4; ++b) {
        int o = w.offO + b;
        if (w.wO[b] == 0 || o < 0 || o >= t.nMu) continue;
        total += w.wO[b] * t.cdf[size_t(o) * t.nMu + t.nMu - 1];
    }
    return total;
}

std::string Fmt(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

}  // namespace

std::shared_ptr<const FourierTable> FourierTable::Read(const std::string &path, const FileLoc &loc) {
    const std::string where = "bsdffile \"" + path + "\"";
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(loc, "cannot open " + where);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw Error(loc, "cannot read " + where);
    auto fail = [&](const std::string &msg) { return Error(loc, where + ": " + msg); };

    if (data.size() < kHeaderBytes)
        throw fail("file of " + std::to_string(data.size()) + " bytes is too short for a .bsdf header (" +
                   std::to_string(kHeaderBytes) + " bytes)");
    if (data.compare(0, 7, "SCATFUN") != 0) throw fail("not a tabulated BSDF file (identifier is not \"SCATFUN\")");
    if (uint8_t(data[7]) != 1) throw fail("unsupported .bsdf version " + std::to_string(uint8_t(data[7])) + " (need 1)");
    ByteReader r(data);
    r.seek(8);
    int32_t flags = r.i32(), nMu = r.i32(), nCoeffs = r.i32(), mMax = r.i32(), nChannels = r.i32(),
            nBases = r.i32(), nMetadata = r.i32(), nParameters = r.i32(), nParameterValues = r.i32();
    float eta = r.f32();
    if (!(flags & 1)) throw fail("the file does not hold a BSDF (flags " + std::to_string(flags) + ")");
    if (flags & 2) throw fail("harmonic extrapolation (flags & 2) is not supported, as in pbrt-v3");
    if (flags != 1) throw fail("unknown flags " + std::to_string(flags));
    if (nChannels != 1 && nChannels != 3) throw fail("nChannels is " + std::to_string(nChannels) + " (need 1 or 3)");
    if (nBases != 1 || nParameters != 0 || nParameterValues != 0)
        throw fail("textured (parametric) BSDF files are not supported (nBases " + std::to_string(nBases) +
                   ", nParameters " + std::to_string(nParameters) + "), as in pbrt-v3");
    if (nMu < 2 || nMu > 65536) throw fail("nMu is " + std::to_string(nMu) + " (need 2..65536)");
    if (nCoeffs < 0 || mMax < 0 || nMetadata < 0)
        throw fail("negative size in the header (nCoeffs " + std::to_string(nCoeffs) + ", mMax " +
                   std::to_string(mMax) + ", metadata " + std::to_string(nMetadata) + ")");
    if (!(std::isfinite(eta) && eta > 0)) throw fail("eta is " + Fmt(eta) + " (need a finite positive number)");

    const int64_t n = nMu, n2 = n * n;
    const int64_t expected = int64_t(kHeaderBytes) + 4 * n + 4 * n2 + 8 * n2 + 4 * int64_t(nCoeffs) + nMetadata;
    if (int64_t(data.size()) != expected)
        throw fail("file holds " + std::to_string(data.size()) + " bytes but its header (nMu " + std::to_string(nMu) +
                   ", nCoeffs " + std::to_string(nCoeffs) + ", metadata " + std::to_string(nMetadata) + ") describes " +
                   std::to_string(expected) + (int64_t(data.size()) < expected ? " (truncated)" : ""));

    auto t = std::make_shared<FourierTable>();
    t->eta = eta;
    t->nMu = nMu;
    t->nChannels = nChannels;
    r.seek(kHeaderBytes);
    t->mu.resize(n);
    for (auto &m : t->mu) m = r.f32();
    for (int64_t i = 0; i < n; ++i)
        if (!(std::isfinite(t->mu[i]) && std::abs(t->mu[i]) <= 1))
            throw fail("mu node " + std::to_string(i) + " is " + Fmt(t->mu[i]) + " (need a cosine in [-1, 1])");
    // Non-decreasing; a node may repeat once (the +-0 pair) but the end segments and
    // every Catmull-Rom tangent span must have positive width.
    for (int64_t i = 0; i + 1 < n; ++i) {
        bool ok = t->mu[i] <= t->mu[i + 1] && (i + 2 >= n || t->mu[i] < t->mu[i + 2]);
        if (!ok || t->mu[0] >= t->mu[1] || t->mu[n - 2] >= t->mu[n - 1])
            throw fail("mu nodes are not increasing at node " + std::to_string(i + 1));
    }
    for (int64_t i = 0; i + 1 < n; ++i)
        if (std::signbit(t->mu[i + 1]) && !std::signbit(t->mu[i]))
            throw fail("mu node " + std::to_string(i + 1) + " (-0) follows +0");
    t->posStart = int(std::count_if(t->mu.begin(), t->mu.end(), [](Float m) { return std::signbit(m); }));
    for (int64_t i = 0; i < n2; ++i) {
        float c = r.f32();
        if (!std::isfinite(c)) throw fail("cdf entry " + std::to_string(i) + " is not finite");
    }
    t->offset.resize(n2);
    t->length.resize(n2);
    for (int64_t e = 0; e < n2; ++e) {
        int32_t off = r.i32(), len = r.i32();
        if (off < 0 || len < 0 || len > mMax || int64_t(off) + int64_t(len) * nChannels > nCoeffs)
            throw fail("series " + std::to_string(e) + " (offset " + std::to_string(off) + ", length " +
                       std::to_string(len) + ") lies outside the " + std::to_string(nCoeffs) +
                       " coefficients or exceeds mMax " + std::to_string(mMax));
        t->offset[e] = off;
        t->length[e] = len;
        t->mMax = std::max<int>(t->mMax, len);
    }
    t->coeffs.resize(size_t(nCoeffs));
    for (int32_t i = 0; i < nCoeffs; ++i) {
        t->coeffs[i] = r.f32();
        if (!std::isfinite(t->coeffs[i])) throw fail("coefficient " + std::to_string(i) + " is not finite");
    }
    // Derived tables: a_0 of the luminance, and which sides carry any scattering.
    t->a0.assign(n2, 0);
    for (int64_t o = 0; o < n; ++o)
        for (int64_t i = 0; i < n; ++i) {
            size_t e = size_t(o * n + i);
            int len = t->length[e];
            if (len == 0) continue;
            const Float *a = t->coeffs.data() + t->offset[e];
            t->a0[e] = a[0];
            bool nonzero = std::any_of(a, a + size_t(len) * nChannels, [](Float v) { return v != 0; });
            if (!nonzero) continue;
            // Reflection when the two cosines have opposite signs (mu_i = cos(-wi)).
            if (SideOf(t->mu[o]) != SideOf(t->mu[i])) t->reflects = true; else t->transmits = true;
        }
    // The sampling cdf is recomputed from a_0 with the very spline that sampling
    // inverts, so that sample() and pdf() agree for any file (layerlab's stored cdf is
    // the same integral; it is only checked for finiteness above).
    t->cdf.assign(n2, 0);
    for (int64_t o = 0; o < n; ++o)
        IntegrateCatmullRom(nMu, t->mu.data(), &t->a0[size_t(o * n)], &t->cdf[size_t(o * n)]);
    return t;
}

FourierBxDF::FourierBxDF(const FourierTable *t)
    : BxDF((t->reflects || !t->transmits ? unsigned(BSDF_REFLECTION) : 0u) |
           (t->transmits ? unsigned(BSDF_TRANSMISSION) : 0u) | BSDF_GLOSSY),
      t_(t) {}

Float FourierBxDF::roughness() const { return t_->mMax <= 1 ? 1 : std::min<Float>(1, Pi / t_->mMax); }

Spectrum FourierBxDF::f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const {
    const FourierTable &t = *t_;
    Float muI = -wi.z, muO = wo.z;
    Weights w;
    if (!Allowed(t, muI, muO) || !LookupWeights(t, muI, muO, &w)) return Spectrum(0);
    double *ak = Scratch(size_t(t.nChannels) * t.mMax);
    int m = Interpolate(t, w, t.nChannels, ak);
    Float cosPhi = CosDPhi(-wi, wo);
    Float Y = std::max<double>(0, Series(ak, m, cosPhi));
    Float scale = Scale(t, muI, muO, mode);
    Spectrum s;
    if (t.nChannels == 1) {
        s = Spectrum(Y * scale);
    } else {
        // Channels are luminance, red, blue; green follows from the luminance
        // weights of Spectrum::y().
        Float R = Series(ak + t.mMax, m, cosPhi), B = Series(ak + 2 * size_t(t.mMax), m, cosPhi);
        Float G = (Y - 0.212671 * R - 0.072169 * B) / 0.715160;
        s = matutil::ClampNeg(Spectrum(R, G, B) * scale);
    }
    return s.isFinite() ? s : Spectrum(0);
}

Float FourierBxDF::pdf(const Vec3 &wo, const Vec3 &wi, TransportMode) const {
    const FourierTable &t = *t_;
    Float muI = -wi.z, muO = wo.z;
    Weights w;
    if (!Allowed(t, muI, muO) || !LookupWeights(t, muI, muO, &w)) return 0;
    double *ak = Scratch(t.mMax);
    int m = Interpolate(t, w, 1, ak);
    Float Y = Series(ak, m, CosDPhi(-wi, wo));
    // Density over (mu_i, phi), i.e. solid angle: a_0 / integral times Y / (2 pi a_0).
    Float rho = 2 * Pi * RowIntegral(t, w);
    Float p = rho > 0 && Y > 0 ? Y / rho : 0;
    return std::isfinite(p) ? p : 0;
}

bool FourierBxDF::sample(const Vec3 &wo, Float, Point2 u, TransportMode mode, BSDFSample *s) const {
    const FourierTable &t = *t_;
    Float muO = wo.z;
    // mu_i from the Catmull-Rom spline of a_0 over mu_i at mu_o (the row's integral must
    // be positive: SampleCatmullRom2D's failure value -1 is also a valid cosine).
    Weights w;
    if (!MuOWeights(t, muO, &w) || !(RowIntegral(t, w) > 0)) return false;
    RowRange rows = RowsFor(t, muO);
    const size_t first = size_t(rows.start) * t.nMu;
    Float pdfMu = 0;
    Float muI = SampleCatmullRom2D(rows.count, t.nMu, t.mu.data() + rows.start, t.mu.data(), t.a0.data() + first,
                                   t.cdf.data() + first, rows.muO, u[1], nullptr, &pdfMu);
    if (!(pdfMu > 0) || !Allowed(t, muI, muO) || !LookupWeights(t, muI, muO, &w)) return false;
    // phi from the luminance series at (mu_i, mu_o).
    double *ak = Scratch(t.mMax);
    int m = Interpolate(t, w, 1, ak);
    Float phi;
    if (!SampleFourierPhi(ak, m, u[0], &phi)) return false;
    // -wi: zenith cosine mu_i, azimuth phi from wo's.
    Float ox = wo.x, oy = wo.y, len = std::sqrt(ox * ox + oy * oy);
    if (len > 0) ox /= len, oy /= len; else ox = 1, oy = 0;
    Float sinI = SafeSqrt(1 - muI * muI), c = std::cos(phi), sn = std::sin(phi);
    Vec3 wi = -Normalize(Vec3(sinI * (c * ox - sn * oy), sinI * (sn * ox + c * oy), muI));
    if (wi.z == 0) return false;
    bool transmit = wi.z * wo.z < 0;
    unsigned lobe = (transmit ? BSDF_TRANSMISSION : BSDF_REFLECTION) | BSDF_GLOSSY;
    return bxdfutil::SampleFromEval(*this, wo, wi, mode, lobe, transmit ? (wo.z > 0 ? t.eta : 1 / t.eta) : 1, s);
}

namespace {

class FourierMaterial : public matutil::BumpMaterial {
  public:
    FourierMaterial(std::shared_ptr<const FourierTable> t, std::shared_ptr<FloatTexture> bump)
        : BumpMaterial(std::move(bump)), t_(std::move(t)) {}
    const BxDF *build(const SurfaceInteraction &, Arena &arena, TransportMode) const override {
        return arena.make<FourierBxDF>(t_.get());
    }
    Float minRoughness() const override { return FourierBxDF(t_.get()).roughness(); }
    bool texturesVary() const override { return false; }

  private:
    std::shared_ptr<const FourierTable> t_;
};

}  // namespace

std::shared_ptr<Material> CreateFourierMaterial(const ParamSet &p, const SceneDesc *scene, const FileLoc &loc,
                                                std::shared_ptr<FloatTexture> bump) {
    std::string file = p.getString("bsdffile", "");
    FileLoc at = p.locOf("bsdffile", loc);
    if (file.empty()) throw Error(at, "\"fourier\" material needs \"string bsdffile\"");
    std::string path = scene ? scene->resolve(file) : file;
    return std::make_shared<FourierMaterial>(FourierTable::Read(path, at), std::move(bump));
}

}  // namespace gradus
