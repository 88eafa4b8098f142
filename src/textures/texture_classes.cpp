// Procedural and image textures (pbrt-v3 parameter names and defaults).
#include <cmath>
#include <mutex>

#include "image/image.h"
#include "textures/gltf_texture.h"
#include "textures/textures.h"

namespace gradus {

// ---------------------------------------------------------------- mappings
TextureMapping2D TextureMapping2D::MakeUV(Float su, Float sv, Float du, Float dv) {
    TextureMapping2D m;
    m.kind_ = UV;
    m.su_ = su;
    m.sv_ = sv;
    m.du_ = du;
    m.dv_ = dv;
    return m;
}

TextureMapping2D TextureMapping2D::FromParams(const ParamSet &p, const Transform &worldFromTexture,
                                              const FileLoc &loc) {
    std::string type = p.getString("mapping", "uv");
    TextureMapping2D m;
    m.textureFromWorld_ = worldFromTexture.inverse();
    if (type == "uv") {
        m = MakeUV(p.getFloat("uscale", 1), p.getFloat("vscale", 1), p.getFloat("udelta", 0), p.getFloat("vdelta", 0));
    } else if (type == "spherical") {
        m.kind_ = Spherical;
    } else if (type == "cylindrical") {
        m.kind_ = Cylindrical;
    } else if (type == "planar") {
        m.kind_ = Planar;
        m.vs_ = p.getVector3("v1", Vec3(1, 0, 0));
        m.vt_ = p.getVector3("v2", Vec3(0, 1, 0));
        m.du_ = p.getFloat("udelta", 0);
        m.dv_ = p.getFloat("vdelta", 0);
    } else {
        throw Error(p.locOf("mapping", loc),
                    "unknown texture mapping \"" + type + "\" (known: uv, spherical, cylindrical, planar)");
    }
    return m;
}

Point2 TextureMapping2D::map(const SurfaceInteraction &si) const {
    switch (kind_) {
    case UV: return {su_ * si.uv.x + du_, sv_ * si.uv.y + dv_};
    case Spherical: {
        Vec3 v = Normalize(textureFromWorld_.applyPoint(si.p));
        return {SphericalTheta(v) * InvPi, SphericalPhi(v) * Inv2Pi};
    }
    case Cylindrical: {
        Vec3 v = Normalize(textureFromWorld_.applyPoint(si.p));
        return {(Pi + std::atan2(v.y, v.x)) * Inv2Pi, v.z};
    }
    case Planar: return {du_ + Dot(si.p, vs_), dv_ + Dot(si.p, vt_)};
    }
    return si.uv;
}

// ---------------------------------------------------------------- noise
namespace {
struct PermTable {
    int p[512];
    PermTable() {
        // Fisher-Yates shuffle of 0..255 driven by a fixed 64-bit LCG (Knuth's MMIX constants).
        int v[256];
        for (int i = 0; i < 256; ++i) v[i] = i;
        uint64_t s = 0x9E3779B97F4A7C15ull;
        for (int i = 255; i > 0; --i) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            int j = int((s >> 33) % uint64_t(i + 1));
            std::swap(v[i], v[j]);
        }
        for (int i = 0; i < 512; ++i) p[i] = v[i & 255];
    }
};
const PermTable &Perm() {
    static const PermTable t;
    return t;
}
inline Float Fade(Float t) { return t * t * t * (t * (t * 6 - 15) + 10); }
// Dot product of (x, y, z) with one of 12 edge-midpoint gradients of the cube.
inline Float Grad(int h, Float x, Float y, Float z) {
    switch (h % 12) {
    case 0: return x + y;
    case 1: return -x + y;
    case 2: return x - y;
    case 3: return -x - y;
    case 4: return x + z;
    case 5: return -x + z;
    case 6: return x - z;
    case 7: return -x - z;
    case 8: return y + z;
    case 9: return -y + z;
    case 10: return y - z;
    default: return -y - z;
    }
}
}  // namespace

Float Noise(Float x, Float y, Float z) {
    const int *P = Perm().p;
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return 0;
    Float fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    // Lattice cells modulo 256, reduced in floating point first: a coordinate
    // beyond the int64 range (a texture scale of 1e30, fuzz_scene) made the
    // conversion undefined. The same cells as int64(f) & 255 where that exists.
    auto cell = [](Float f) { return int(int64_t(std::fmod(f, 256.0)) & 255); };
    int ix = cell(fx), iy = cell(fy), iz = cell(fz);
    Float dx = x - fx, dy = y - fy, dz = z - fz;
    auto h = [&](int a, int b, int c) { return P[P[P[(ix + a) & 255] + ((iy + b) & 255)] + ((iz + c) & 255)]; };
    Float u = Fade(dx), v = Fade(dy), w = Fade(dz);
    Float x00 = Lerp(u, Grad(h(0, 0, 0), dx, dy, dz), Grad(h(1, 0, 0), dx - 1, dy, dz));
    Float x10 = Lerp(u, Grad(h(0, 1, 0), dx, dy - 1, dz), Grad(h(1, 1, 0), dx - 1, dy - 1, dz));
    Float x01 = Lerp(u, Grad(h(0, 0, 1), dx, dy, dz - 1), Grad(h(1, 0, 1), dx - 1, dy, dz - 1));
    Float x11 = Lerp(u, Grad(h(0, 1, 1), dx, dy - 1, dz - 1), Grad(h(1, 1, 1), dx - 1, dy - 1, dz - 1));
    return Lerp(w, Lerp(v, x00, x10), Lerp(v, x01, x11));
}

Float FBm(const Point3 &p, Float omega, int octaves) {
    Float sum = 0, lambda = 1, o = 1;
    for (int i = 0; i < octaves; ++i) {
        sum += o * Noise(p * lambda);
        lambda *= 1.99;  // not exactly 2: keeps lattice zeros of the octaves apart
        o *= omega;
    }
    return sum;
}

Float Turbulence(const Point3 &p, Float omega, int octaves) {
    Float sum = 0, lambda = 1, o = 1;
    for (int i = 0; i < octaves; ++i) {
        sum += o * std::abs(Noise(p * lambda));
        lambda *= 1.99;
        o *= omega;
    }
    return sum;
}

// ---------------------------------------------------------------- image texels
namespace {
int Wrap(int i, int n, WrapMode mode, bool *black) {
    *black = false;
    if (i >= 0 && i < n) return i;
    switch (mode) {
    case WrapMode::Repeat: return ((i % n) + n) % n;
    case WrapMode::Clamp: return Clamp(i, 0, n - 1);
    default: *black = true; return 0;
    }
}
}  // namespace

Spectrum TexelGrid::texel(int x, int y, WrapMode wrap) const {
    bool bx, by;
    x = Wrap(x, w_, wrap, &bx);
    y = Wrap(y, h_, wrap, &by);
    if (bx || by || w_ == 0) return Spectrum(0);
    return texels_[size_t(y) * w_ + x];
}

Spectrum TexelGrid::bilerp(Point2 st, WrapMode wrap) const {
    if (w_ == 0 || h_ == 0) return Spectrum(0);
    // Continuous texel coordinates; t = 0 is the last (bottom) row of the file.
    Float x = st.x * w_ - 0.5, y = (1 - st.y) * h_ - 0.5;
    if (!std::isfinite(x) || !std::isfinite(y)) return Spectrum(0);
    Float fx = std::floor(x), fy = std::floor(y);
    Float ax = x - fx, ay = y - fy;
    // Into int range before the cast (huge st from texture mappings): repeat reduces
    // modulo the size; clamp and black give the same texels two or more texels outside.
    auto toIndex = [wrap](Float f, int n) {
        return int(wrap == WrapMode::Repeat ? f - n * std::floor(f / n) : Clamp(f, Float(-2), Float(n + 1)));
    };
    int x0 = toIndex(fx, w_), y0 = toIndex(fy, h_);
    return texel(x0, y0, wrap) * ((1 - ax) * (1 - ay)) + texel(x0 + 1, y0, wrap) * (ax * (1 - ay)) +
           texel(x0, y0 + 1, wrap) * ((1 - ax) * ay) + texel(x0 + 1, y0 + 1, wrap) * (ax * ay);
}

namespace {
std::string LowerExt(const std::string &f) {
    auto dot = f.find_last_of('.');
    if (dot == std::string::npos) return "";
    std::string e = f.substr(dot + 1);
    for (char &c : e) c = char(std::tolower((unsigned char)c));
    return e;
}
bool IsEightBitFormat(const std::string &filename) {
    std::string e = LowerExt(filename);
    return e == "png" || e == "tga" || e == "jpg" || e == "jpeg" || e == "bmp" || e == "gif";
}
}  // namespace

std::shared_ptr<const TexelGrid> LoadTexelGrid(const std::string &filename, bool gamma, const FileLoc &loc) {
    static std::mutex mutex;
    static std::map<std::pair<std::string, bool>, std::shared_ptr<const TexelGrid>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto key = std::make_pair(filename, gamma);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    Image img;
    try {
        img = ReadImage(filename);
    } catch (const Error &e) {
        throw Error(loc, std::string("cannot read image texture: ") + e.what());
    }
    // ReadImage decodes 8-bit files to linear; "gamma" false keeps the stored values.
    auto grid = MakeTexelGrid(img, IsEightBitFormat(filename) && !gamma);
    cache[key] = grid;
    return grid;
}

std::shared_ptr<const TexelGrid> MakeTexelGrid(const Image &img, bool storedValues) {
    Image rgb = img.layerRGB(DefaultRGBLayer(img));
    std::vector<Spectrum> texels(size_t(rgb.width()) * rgb.height());
    for (int y = 0; y < rgb.height(); ++y)
        for (int x = 0; x < rgb.width(); ++x) {
            Spectrum &t = texels[size_t(y) * rgb.width() + x];
            for (int c = 0; c < 3; ++c) {
                float v = rgb.at(x, y, c);
                if (storedValues) v = LinearToSRGB(v);
                t[c] = v;
            }
        }
    return std::make_shared<const TexelGrid>(rgb.width(), rgb.height(), std::move(texels));
}

// ---------------------------------------------------------------- texture classes
namespace {

template <typename T>
class ScaleTexture : public Texture<T> {
  public:
    ScaleTexture(std::shared_ptr<Texture<T>> a, std::shared_ptr<Texture<T>> b) : a_(a), b_(b) {}
    T evaluate(const SurfaceInteraction &si) const override { return a_->evaluate(si) * b_->evaluate(si); }
    bool isConstant() const override { return a_->isConstant() && b_->isConstant(); }

  private:
    std::shared_ptr<Texture<T>> a_, b_;
};

template <typename T>
class MixTexture : public Texture<T> {
  public:
    MixTexture(std::shared_ptr<Texture<T>> a, std::shared_ptr<Texture<T>> b, std::shared_ptr<FloatTexture> amt)
        : a_(a), b_(b), amt_(amt) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Float t = amt_->evaluate(si);
        return a_->evaluate(si) * (1 - t) + b_->evaluate(si) * t;
    }
    bool isConstant() const override { return a_->isConstant() && b_->isConstant() && amt_->isConstant(); }

  private:
    std::shared_ptr<Texture<T>> a_, b_;
    std::shared_ptr<FloatTexture> amt_;
};

template <typename T>
class BilerpTexture : public Texture<T> {
  public:
    BilerpTexture(TextureMapping2D m, T v00, T v01, T v10, T v11)
        : m_(m), v00_(v00), v01_(v01), v10_(v10), v11_(v11) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Point2 st = m_.map(si);
        return v00_ * ((1 - st.x) * (1 - st.y)) + v01_ * ((1 - st.x) * st.y) + v10_ * (st.x * (1 - st.y)) +
               v11_ * (st.x * st.y);
    }

  private:
    TextureMapping2D m_;
    T v00_, v01_, v10_, v11_;
};

class UVTexture : public SpectrumTexture {
  public:
    explicit UVTexture(TextureMapping2D m) : m_(m) {}
    Spectrum evaluate(const SurfaceInteraction &si) const override {
        Point2 st = m_.map(si);
        return {st.x - std::floor(st.x), st.y - std::floor(st.y), 0};
    }

  private:
    TextureMapping2D m_;
};

// Parity of a sum of cell indices, in floating point: an integer cast of huge
// coordinates would be undefined (fuzz finding); every double beyond 2^53 is even.
inline bool EvenCell(double k) { return !(std::fabs(std::fmod(k, 2.0)) == 1.0); }

// Point-sampled checkerboard (pbrt-v3's closed-form box filter needs ray
// differentials, which Gradus does not track; with zero footprint it reduces to this).
template <typename T>
class Checkerboard2D : public Texture<T> {
  public:
    Checkerboard2D(TextureMapping2D m, std::shared_ptr<Texture<T>> a, std::shared_ptr<Texture<T>> b)
        : m_(m), a_(a), b_(b) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Point2 st = m_.map(si);
        return EvenCell(std::floor(st.x) + std::floor(st.y)) ? a_->evaluate(si) : b_->evaluate(si);
    }

  private:
    TextureMapping2D m_;
    std::shared_ptr<Texture<T>> a_, b_;
};

template <typename T>
class Checkerboard3D : public Texture<T> {
  public:
    Checkerboard3D(TextureMapping3D m, std::shared_ptr<Texture<T>> a, std::shared_ptr<Texture<T>> b)
        : m_(m), a_(a), b_(b) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Point3 p = m_.map(si);
        return EvenCell(std::floor(p.x) + std::floor(p.y) + std::floor(p.z)) ? a_->evaluate(si) : b_->evaluate(si);
    }

  private:
    TextureMapping3D m_;
    std::shared_ptr<Texture<T>> a_, b_;
};

// Polka dots: one dot of radius 0.35 in about half the unit cells, jittered by noise.
template <typename T>
class DotsTexture : public Texture<T> {
  public:
    DotsTexture(TextureMapping2D m, std::shared_ptr<Texture<T>> in, std::shared_ptr<Texture<T>> out)
        : m_(m), in_(in), out_(out) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Point2 st = m_.map(si);
        Float sc = std::floor(st.x + 0.5), tc = std::floor(st.y + 0.5);
        if (Noise(sc + 0.5, tc + 0.5) > 0) {
            const Float r = 0.35, maxShift = 0.5 - r;
            Float cs = sc + maxShift * Noise(sc + 1.5, tc + 2.8);
            Float ct = tc + maxShift * Noise(sc + 4.5, tc + 9.8);
            if (Sqr(st.x - cs) + Sqr(st.y - ct) < r * r) return in_->evaluate(si);
        }
        return out_->evaluate(si);
    }

  private:
    TextureMapping2D m_;
    std::shared_ptr<Texture<T>> in_, out_;
};

template <typename T>
T FromFloat(Float v);
template <>
Float FromFloat<Float>(Float v) { return v; }
template <>
Spectrum FromFloat<Spectrum>(Float v) { return Spectrum(v); }

enum class NoiseKind { FBm, Wrinkled, Windy };
template <typename T>
class NoiseTexture : public Texture<T> {
  public:
    NoiseTexture(NoiseKind k, TextureMapping3D m, Float omega, int octaves)
        : k_(k), m_(m), omega_(omega), octaves_(octaves) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Point3 p = m_.map(si);
        switch (k_) {
        case NoiseKind::FBm: return FromFloat<T>(FBm(p, omega_, octaves_));
        case NoiseKind::Wrinkled: return FromFloat<T>(Turbulence(p, omega_, octaves_));
        default: {
            // Wind strength varies slowly; wave height is detailed (pbrt-v3 "windy").
            Float wind = FBm(p * 0.1, 0.5, 3), wave = FBm(p, 0.5, 6);
            return FromFloat<T>(std::abs(wind) * wave);
        }
        }
    }

  private:
    NoiseKind k_;
    TextureMapping3D m_;
    Float omega_;
    int octaves_;
};

// Marble: sine bands perturbed by fBm, coloured through a uniform cubic B-spline
// over a small palette of our own (light stone to dark veins).
class MarbleTexture : public SpectrumTexture {
  public:
    MarbleTexture(TextureMapping3D m, int octaves, Float omega, Float scale, Float variation)
        : m_(m), octaves_(octaves), omega_(omega), scale_(scale), variation_(variation) {}
    Spectrum evaluate(const SurfaceInteraction &si) const override {
        Point3 p = m_.map(si) * scale_;
        Float marble = p.y + variation_ * FBm(p, omega_, octaves_);
        Float t = 0.5 + 0.5 * std::sin(marble);
        static const Spectrum palette[] = {{0.62, 0.60, 0.56}, {0.80, 0.78, 0.74}, {0.88, 0.86, 0.82},
                                           {0.55, 0.50, 0.46}, {0.30, 0.26, 0.24}, {0.70, 0.67, 0.62},
                                           {0.86, 0.84, 0.80}};
        const int nSeg = int(sizeof(palette) / sizeof(palette[0])) - 3;
        Float x = Clamp<Float>(t, 0, 1) * nSeg;
        int i = std::min(int(x), nSeg - 1);
        Float u = x - i;
        // Uniform cubic B-spline basis.
        Float b0 = (1 - u) * (1 - u) * (1 - u) / 6, b1 = (3 * u * u * u - 6 * u * u + 4) / 6;
        Float b2 = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6, b3 = u * u * u / 6;
        return palette[i] * b0 + palette[i + 1] * b1 + palette[i + 2] * b2 + palette[i + 3] * b3;
    }

  private:
    TextureMapping3D m_;
    int octaves_;
    Float omega_, scale_, variation_;
};

template <typename T>
class ImageTexture : public Texture<T> {
  public:
    ImageTexture(TextureMapping2D m, std::shared_ptr<const TexelGrid> g, WrapMode w, Float scale, bool invert)
        : m_(m), g_(std::move(g)), wrap_(w), scale_(scale), invert_(invert) {}
    T evaluate(const SurfaceInteraction &si) const override {
        Spectrum v = g_->bilerp(m_.map(si), wrap_) * scale_;
        if (invert_) v = {std::max(0.0, 1 - v.r), std::max(0.0, 1 - v.g), std::max(0.0, 1 - v.b)};
        return convert(v);
    }

  private:
    static T convert(const Spectrum &s);
    TextureMapping2D m_;
    std::shared_ptr<const TexelGrid> g_;
    WrapMode wrap_;
    Float scale_;
    bool invert_;
};
template <>
Spectrum ImageTexture<Spectrum>::convert(const Spectrum &s) { return s; }
template <>
Float ImageTexture<Float>::convert(const Spectrum &s) { return s.y(); }

// Typed lookup of texture parameters ("tex1" etc.).
template <typename T>
std::shared_ptr<Texture<T>> GetTex(const ParamSet &p, const std::string &n, Float def, const NamedTextures &t,
                                   const FileLoc &loc);
template <>
std::shared_ptr<FloatTexture> GetTex<Float>(const ParamSet &p, const std::string &n, Float def,
                                            const NamedTextures &t, const FileLoc &loc) {
    return GetFloatTexture(p, n, def, t, loc);
}
template <>
std::shared_ptr<SpectrumTexture> GetTex<Spectrum>(const ParamSet &p, const std::string &n, Float def,
                                                  const NamedTextures &t, const FileLoc &loc) {
    return GetSpectrumTexture(p, n, Spectrum(def), t, loc);
}

template <typename T>
T GetValue(const ParamSet &p, const std::string &n, Float def);
template <>
Float GetValue<Float>(const ParamSet &p, const std::string &n, Float def) { return p.getFloat(n, def); }
template <>
Spectrum GetValue<Spectrum>(const ParamSet &p, const std::string &n, Float def) {
    return p.getSpectrum(n, Spectrum(def));
}

WrapMode ParseWrap(const ParamSet &p, const FileLoc &loc) {
    std::string w = p.getString("wrap", "repeat");
    if (w == "repeat") return WrapMode::Repeat;
    if (w == "black") return WrapMode::Black;
    if (w == "clamp") return WrapMode::Clamp;
    throw Error(p.locOf("wrap", loc), "unknown wrap mode \"" + w + "\" (known: repeat, black, clamp)");
}

template <typename T>
std::shared_ptr<Texture<T>> MakeTexture(const TextureDesc &d, const SceneDesc &scene, const NamedTextures &tex) {
    const ParamSet &p = d.params;
    const FileLoc &loc = d.loc;
    const std::string &type = d.type;
    if (type == "constant") return std::make_shared<ConstantTexture<T>>(GetValue<T>(p, "value", 1));
    if (type == "scale") return std::make_shared<ScaleTexture<T>>(GetTex<T>(p, "tex1", 1, tex, loc), GetTex<T>(p, "tex2", 1, tex, loc));
    if (type == "mix")
        return std::make_shared<MixTexture<T>>(GetTex<T>(p, "tex1", 0, tex, loc), GetTex<T>(p, "tex2", 1, tex, loc),
                                               GetFloatTexture(p, "amount", 0.5, tex, loc));
    if (type == "bilerp") {
        auto m = TextureMapping2D::FromParams(p, d.worldFromTexture, loc);
        return std::make_shared<BilerpTexture<T>>(m, GetValue<T>(p, "v00", 0), GetValue<T>(p, "v01", 1),
                                                  GetValue<T>(p, "v10", 0), GetValue<T>(p, "v11", 1));
    }
    if (type == "checkerboard") {
        int dim = p.getInt("dimension", 2);
        std::string aa = p.getString("aamode", "closedform");
        if (aa != "closedform" && aa != "none")
            throw Error(p.locOf("aamode", loc), "unknown checkerboard aamode \"" + aa + "\" (known: closedform, none)");
        auto a = GetTex<T>(p, "tex1", 1, tex, loc), b = GetTex<T>(p, "tex2", 0, tex, loc);
        if (dim == 2)
            return std::make_shared<Checkerboard2D<T>>(TextureMapping2D::FromParams(p, d.worldFromTexture, loc), a, b);
        if (dim == 3) return std::make_shared<Checkerboard3D<T>>(TextureMapping3D(d.worldFromTexture), a, b);
        throw Error(p.locOf("dimension", loc), "checkerboard dimension must be 2 or 3");
    }
    if (type == "dots") {
        auto m = TextureMapping2D::FromParams(p, d.worldFromTexture, loc);
        return std::make_shared<DotsTexture<T>>(m, GetTex<T>(p, "inside", 1, tex, loc),
                                                GetTex<T>(p, "outside", 0, tex, loc));
    }
    if (type == "fbm" || type == "wrinkled")
        return std::make_shared<NoiseTexture<T>>(type == "fbm" ? NoiseKind::FBm : NoiseKind::Wrinkled,
                                                 TextureMapping3D(d.worldFromTexture), p.getFloat("roughness", 0.5),
                                                 p.getInt("octaves", 8));
    if (type == "windy") return std::make_shared<NoiseTexture<T>>(NoiseKind::Windy, TextureMapping3D(d.worldFromTexture), 0.5, 6);
    if (type == "imagemap") {
        std::string fn = p.getString("filename", "");
        if (fn.empty()) throw Error(loc, "\"imagemap\" texture needs \"string filename\"");
        // Mip-map filtering options are accepted; lookups are bilinear (no ray differentials).
        p.getFloat("maxanisotropy", 8);
        p.getBool("trilinear", false);
        WrapMode wrap = ParseWrap(p, loc);
        Float scale = p.getFloat("scale", 1);
        bool invert = p.getBool("invert", false);
        bool gamma = p.getBool("gamma", IsEightBitFormat(fn));
        auto m = TextureMapping2D::FromParams(p, d.worldFromTexture, loc);
        auto grid = LoadTexelGrid(scene.resolve(fn), gamma, p.locOf("filename", loc));
        return std::make_shared<ImageTexture<T>>(m, grid, wrap, scale, invert);
    }
    if (type == "ptex") throw UnsupportedError(loc, "texture \"ptex\"");
    return nullptr;
}

}  // namespace

std::shared_ptr<FloatTexture> MakeFloatTexture(const TextureDesc &d, const SceneDesc &scene,
                                               const NamedTextures &tex) {
    if (d.type == "uv" || d.type == "marble")
        throw Error(d.loc, "texture \"" + d.type + "\" is a spectrum texture and cannot be declared \"float\"");
    if (d.type == "gltfimage") return MakeGltfFloatTexture(d, scene);
    auto t = MakeTexture<Float>(d, scene, tex);
    if (!t)
        throw Error(d.loc, "unknown texture type \"" + d.type +
                               "\" (known: constant, scale, mix, bilerp, imagemap, checkerboard, dots, fbm, "
                               "wrinkled, windy, uv, marble, gltfimage)");
    return t;
}

std::shared_ptr<SpectrumTexture> MakeSpectrumTexture(const TextureDesc &d, const SceneDesc &scene,
                                                     const NamedTextures &tex) {
    const ParamSet &p = d.params;
    if (d.type == "uv") return std::make_shared<UVTexture>(TextureMapping2D::FromParams(p, d.worldFromTexture, d.loc));
    if (d.type == "marble")
        return std::make_shared<MarbleTexture>(TextureMapping3D(d.worldFromTexture), p.getInt("octaves", 8),
                                               p.getFloat("roughness", 0.5), p.getFloat("scale", 1),
                                               p.getFloat("variation", 0.2));
    if (d.type == "gltfimage") return MakeGltfSpectrumTexture(d, scene);
    auto t = MakeTexture<Spectrum>(d, scene, tex);
    if (!t)
        throw Error(d.loc, "unknown texture type \"" + d.type +
                               "\" (known: constant, scale, mix, bilerp, imagemap, checkerboard, dots, fbm, "
                               "wrinkled, windy, uv, marble, gltfimage)");
    return t;
}

}  // namespace gradus
