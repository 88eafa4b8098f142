#include <atomic>
#include <cmath>
#include <cstring>

#include "core/error.h"
#include "image/image.h"
#include "lights/light.h"
#include "samplers/sampling.h"

namespace gradus {

// ---------------------------------------------------------------- area light
bool AreaLight::sampleLi(const Interaction &ref, Point2 u, LightLiSample *s) const {
    Float pdf;
    Interaction p = shape_->sampleFrom(ref, u, &pdf);
    Vec3 d = p.p - ref.p;
    Float len2 = d.lengthSquared();
    if (pdf == 0 || len2 == 0) return false;
    s->wi = d / std::sqrt(len2);
    s->pdf = pdf;
    s->pLight = p;
    s->L = L(p, -s->wi);
    return !s->L.isBlack();
}

bool AreaLight::sampleLe(Point2 u1, Point2 u2, LightLeSample *s) const {
    Float pdfPos;
    Interaction p = shape_->sampleArea(u1, &pdfPos);
    Vec3 wLocal;
    Float pdfDir;
    if (twoSided_) {
        // Choose a side with u2.x, then cosine-sample that hemisphere.
        Point2 v = u2;
        bool back = v.x < 0.5;
        v.x = back ? v.x * 2 : (v.x - 0.5) * 2;
        v.x = std::min(v.x, 1 - 1e-12);
        wLocal = SampleCosineHemisphere(v);
        if (back) wLocal.z = -wLocal.z;
        pdfDir = 0.5 * CosineHemispherePdf(std::abs(wLocal.z));
    } else {
        wLocal = SampleCosineHemisphere(u2);
        pdfDir = CosineHemispherePdf(wLocal.z);
    }
    if (pdfPos == 0 || pdfDir == 0) return false;
    Frame f(p.n);
    Vec3 w = f.toWorld(wLocal);
    s->ray = p.spawnRay(w);
    s->p = p.p;
    s->nLight = p.n;
    s->pdfPos = pdfPos;
    s->pdfDir = pdfDir;
    s->L = L(p, w);
    return !s->L.isBlack();
}

void AreaLight::pdfLe(const Ray &ray, const Normal3 &n, Float *pdfPos, Float *pdfDir) const {
    *pdfPos = shape_->pdfArea(Interaction(ray.o, n, Vec3(0, 0, 0)));
    Float c = Dot(n, ray.d);
    *pdfDir = twoSided_ ? 0.5 * CosineHemispherePdf(std::abs(c)) : (c > 0 ? CosineHemispherePdf(c) : 0);
}

namespace {

// Lights at a point: the direction from ref (s->wi, pdf 1, s->pLight) and the
// squared distance; false at the light's own position.
bool PointLiGeometry(const Point3 &pos, const Interaction &ref, LightLiSample *s, Float *d2) {
    const Vec3 d = pos - ref.p;
    *d2 = d.lengthSquared();
    if (*d2 == 0) return false;
    s->wi = d / std::sqrt(*d2);
    s->pdf = 1;
    s->pLight = Interaction(pos, Normal3(0, 0, 0), -s->wi);
    return true;
}
// Lights at a point: an emitted ray from pos along w (unit) with solid-angle density pdfDir.
void PointLeRecord(const Point3 &pos, const Vec3 &w, Float pdfDir, const Spectrum &L, LightLeSample *s) {
    s->ray = Ray(pos, w);
    s->p = pos;
    s->nLight = Normal3(0, 0, 0);
    s->pdfPos = 1;
    s->pdfDir = pdfDir;
    s->L = L;
}

// ---------------------------------------------------------------- point light
class PointLight : public Light {
  public:
    PointLight(const Transform &w, const Spectrum &I)
        : Light(LIGHT_DELTA_POSITION, w), pos_(w.applyPoint(Point3(0, 0, 0))), I_(I) {}
    Spectrum power() const override { return I_ * (4 * Pi); }
    bool sampleLi(const Interaction &ref, Point2, LightLiSample *s) const override {
        Float d2;
        if (!PointLiGeometry(pos_, ref, s, &d2)) return false;
        s->L = I_ / d2;
        return true;
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        PointLeRecord(pos_, SampleUniformSphere(u1), UniformSpherePdf(), I_, s);
        return true;
    }
    void pdfLe(const Ray &, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfPos = 0;
        *pdfDir = UniformSpherePdf();
    }

  private:
    Point3 pos_;
    Spectrum I_;
};

// ---------------------------------------------------------------- spot light
// The map of a goniometric or projection light as pbrt-v3 builds and reads it
// (lights/goniometric.h, lights/projection.cpp): the file's stored values
// (8-bit PNG/TGA as value / 255, no sRGB decoding: imageio.cpp, ReadImagePNG),
// the finest level of a MIPMap (sides not powers of two resampled up to them,
// see ResampleToPowerOfTwo), looked up bilinearly at (s, t) in [0,1]^2 with
// texel centres at (i + 1/2) / n and coordinates wrapping (MIPMap::Lookup with
// width 0, ImageWrap::Repeat). Row 0 (the file's top row) is t = 0.
class LightImage {
  public:
    // Reads the map with pbrt-v3's pixel encoding.
    static std::unique_ptr<LightImage> Read(const std::string &filename) {
        return std::make_unique<LightImage>(ReadImage(filename, IntegerPixels::Stored));
    }
    explicit LightImage(const Image &file) : fileW_(file.width()), fileH_(file.height()) {
        const Image img = ResampleToPowerOfTwo(file);
        w_ = img.width();
        h_ = img.height();
        Image rgb = img.layerRGB("");
        texels_.resize(size_t(w_) * h_);
        for (int y = 0; y < h_; ++y)
            for (int x = 0; x < w_; ++x) {
                Spectrum v(rgb.at(x, y, 0), rgb.at(x, y, 1), rgb.at(x, y, 2));
                texels_[size_t(y) * w_ + x] = v;
                sum_ += v;
            }
    }
    int width() const { return w_; }
    int height() const { return h_; }
    // The file's aspect ratio (before resampling).
    Float aspect() const { return Float(fileW_) / fileH_; }
    Spectrum average() const { return sum_ / Float(size_t(w_) * h_); }
    Spectrum lookup(Point2 st) const {
        const Float x = st.x * w_ - 0.5, y = st.y * h_ - 0.5;
        const Float fx = std::floor(x), fy = std::floor(y);
        const Float dx = x - fx, dy = y - fy;
        const int x0 = int(fx), y0 = int(fy);
        return texel(x0, y0) * ((1 - dx) * (1 - dy)) + texel(x0 + 1, y0) * (dx * (1 - dy)) +
               texel(x0, y0 + 1) * ((1 - dx) * dy) + texel(x0 + 1, y0 + 1) * (dx * dy);
    }

  private:
    Spectrum texel(int x, int y) const {
        x = ((x % w_) + w_) % w_;
        y = ((y % h_) + h_) % h_;
        return texels_[size_t(y) * w_ + x];
    }
    int fileW_, fileH_, w_ = 0, h_ = 0;
    std::vector<Spectrum> texels_;
    Spectrum sum_;
};

// A point light whose intensity I * S(w) varies over directions (delta position):
// goniometric and projection lights share everything but S and its support.
class DirectionalPointLight : public Light {
  public:
    DirectionalPointLight(const Transform &w, const Spectrum &I)
        : Light(LIGHT_DELTA_POSITION, w), pos_(w.applyPoint(Point3(0, 0, 0))), lightFromWorld_(w.inverse()), I_(I) {}
    // The scale of the intensity towards world direction w (unit).
    virtual Spectrum scale(const Vec3 &wLight) const = 0;
    // Emission sampling: a direction in light space and its solid-angle pdf.
    virtual Vec3 sampleDirection(Point2 u, Float *pdf) const = 0;
    virtual Float directionPdf(const Vec3 &wLight) const = 0;
    Spectrum intensity(const Vec3 &wWorld) const {
        return I_ * scale(Normalize(lightFromWorld_.applyVector(wWorld)));
    }
    bool sampleLi(const Interaction &ref, Point2, LightLiSample *s) const override {
        Float d2;
        if (!PointLiGeometry(pos_, ref, s, &d2)) return false;
        s->L = intensity(-s->wi) / d2;
        return !s->L.isBlack();
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        Float pdf;
        const Vec3 wl = sampleDirection(u1, &pdf);
        if (!(pdf > 0)) return false;
        PointLeRecord(pos_, Normalize(worldFromLight.applyVector(wl)), pdf, I_ * scale(wl), s);
        return !s->L.isBlack();
    }
    void pdfLe(const Ray &ray, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfPos = 0;
        *pdfDir = directionPdf(Normalize(lightFromWorld_.applyVector(ray.d)));
    }

  protected:
    Point3 pos_;
    Transform lightFromWorld_;
    Spectrum I_;
};

// pbrt-v3's "goniometric" light: S(w) from a lat-long image over the light's
// sphere with its +y axis as the pole (theta = 0 at image row 0, phi =
// atan2(z, x) across the columns); emission sampled uniformly over the sphere.
class GoniometricLight : public DirectionalPointLight {
  public:
    GoniometricLight(const Transform &w, const Spectrum &I, std::unique_ptr<LightImage> map)
        : DirectionalPointLight(w, I), map_(std::move(map)) {}
    Spectrum scale(const Vec3 &wl) const override {
        if (!map_) return Spectrum(1);
        const Float theta = std::acos(std::clamp<Float>(wl.y, -1, 1));
        Float phi = std::atan2(wl.z, wl.x);
        if (phi < 0) phi += 2 * Pi;
        return map_->lookup(Point2(phi / (2 * Pi), theta / Pi));
    }
    Vec3 sampleDirection(Point2 u, Float *pdf) const override {
        *pdf = UniformSpherePdf();
        return SampleUniformSphere(u);
    }
    Float directionPdf(const Vec3 &) const override { return UniformSpherePdf(); }
    // The integral of I S over the sphere: texel values times their solid angles.
    Spectrum power() const override {
        if (!map_) return I_ * (4 * Pi);
        const int w = map_->width(), h = map_->height();
        Spectrum sum;
        for (int y = 0; y < h; ++y) {
            const Float t0 = Pi * y / h, t1 = Pi * (y + 1) / h;
            const Float dOmega = (std::cos(t0) - std::cos(t1)) * 2 * Pi / w;
            for (int x = 0; x < w; ++x) sum += map_->lookup(Point2((x + 0.5) / w, (y + 0.5) / h)) * dOmega;
        }
        return I_ * sum;
    }

  private:
    std::unique_ptr<LightImage> map_;
};

// pbrt-v3's "projection" light: a pinhole projector along the light's +z with
// field of view `fov` over the image's shorter side; S(w) is the image at the
// projected screen point, with screen y = -1 (the light's -y side) at image
// row 0, as pbrt-v3 reads the map (no flip). Emission is sampled uniformly in
// the cone through the screen's corners.
class ProjectionLight : public DirectionalPointLight {
  public:
    ProjectionLight(const Transform &w, const Spectrum &I, std::unique_ptr<LightImage> map, Float fovDeg)
        : DirectionalPointLight(w, I), map_(std::move(map)) {
        const Float aspect = map_ ? map_->aspect() : 1;
        sx_ = aspect > 1 ? aspect : 1;
        sy_ = aspect > 1 ? 1 : 1 / aspect;
        tanHalf_ = std::tan(Radians(fovDeg) / 2);
        // Corner of the screen at z = 1: (sx tan, sy tan, 1).
        const Float cx = sx_ * tanHalf_, cy = sy_ * tanHalf_;
        cosTotal_ = 1 / std::sqrt(1 + cx * cx + cy * cy);
    }
    Spectrum scale(const Vec3 &wl) const override {
        if (wl.z < 1e-3 * wl.length()) return Spectrum(0);  // behind the projector's near plane
        const Float x = wl.x / (wl.z * tanHalf_), y = wl.y / (wl.z * tanHalf_);
        if (x < -sx_ || x > sx_ || y < -sy_ || y > sy_) return Spectrum(0);
        if (!map_) return Spectrum(1);
        return map_->lookup(Point2((x + sx_) / (2 * sx_), (y + sy_) / (2 * sy_)));
    }
    Vec3 sampleDirection(Point2 u, Float *pdf) const override {
        *pdf = UniformConePdf(cosTotal_);
        return SampleUniformCone(u, cosTotal_);
    }
    Float directionPdf(const Vec3 &wl) const override { return wl.z >= cosTotal_ ? UniformConePdf(cosTotal_) : 0; }
    // The integral of I S over the screen's solid angle (midpoint rule per texel:
    // dOmega = cos^3 dA at unit distance).
    Spectrum power() const override {
        const int w = map_ ? map_->width() : 64, h = map_ ? map_->height() : 64;
        Spectrum sum;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const Float sx = -sx_ + 2 * sx_ * (x + 0.5) / w, sy = -sy_ + 2 * sy_ * (y + 0.5) / h;
                const Float px = sx * tanHalf_, py = sy * tanHalf_;
                const Float dA = (2 * sx_ * tanHalf_ / w) * (2 * sy_ * tanHalf_ / h);
                const Float c = 1 / std::sqrt(1 + px * px + py * py);
                sum += (map_ ? map_->lookup(Point2((x + 0.5) / w, (y + 0.5) / h)) : Spectrum(1)) * (c * c * c * dA);
            }
        return I_ * sum;
    }

  private:
    std::unique_ptr<LightImage> map_;
    Float sx_, sy_, tanHalf_, cosTotal_;
};

class SpotLight : public Light {
  public:
    // gltfFalloff: KHR_lights_punctual's recommended attenuation instead of pbrt-v3's.
    SpotLight(const Transform &w, const Spectrum &I, Float coneAngle, Float coneDelta, bool gltfFalloff = false)
        : Light(LIGHT_DELTA_POSITION, w), pos_(w.applyPoint(Point3(0, 0, 0))), I_(I), gltf_(gltfFalloff) {
        dir_ = Normalize(w.applyVector(Vec3(0, 0, 1)));
        frame_ = Frame(dir_);
        cosTotal_ = std::cos(Radians(coneAngle));
        cosFalloffStart_ = std::cos(Radians(coneAngle - coneDelta));
    }
    // pbrt-v3's smooth falloff: ((cos - cosTotal) / (cosStart - cosTotal))^4; glTF
    // (KHR_lights_punctual, "Inner and Outer Cone Angles"): the same ratio squared.
    Float falloff(const Vec3 &w) const {
        Float c = Dot(w, dir_);
        if (c < cosTotal_) return 0;
        if (c >= cosFalloffStart_) return 1;
        Float delta = (c - cosTotal_) / (cosFalloffStart_ - cosTotal_);
        return gltf_ ? delta * delta : (delta * delta) * (delta * delta);
    }
    // Exact integral of I falloff over the sphere: the ramp delta^k integrates to
    // (cosStart - cosTotal) / (k + 1) in cos(theta) (pbrt-v3 used a midpoint approximation).
    Spectrum power() const override {
        Float ramp = (cosFalloffStart_ - cosTotal_) / (gltf_ ? 3 : 5);
        return I_ * (2 * Pi * ((1 - cosFalloffStart_) + ramp));
    }
    bool sampleLi(const Interaction &ref, Point2, LightLiSample *s) const override {
        Float d2;
        if (!PointLiGeometry(pos_, ref, s, &d2)) return false;
        s->L = I_ * (falloff(-s->wi) / d2);
        return !s->L.isBlack();
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        Vec3 wl = SampleUniformCone(u1, cosTotal_);
        const Vec3 w = frame_.toWorld(wl);
        PointLeRecord(pos_, w, UniformConePdf(cosTotal_), I_ * falloff(w), s);
        return !s->L.isBlack();
    }
    void pdfLe(const Ray &ray, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfPos = 0;
        *pdfDir = Dot(ray.d, dir_) >= cosTotal_ ? UniformConePdf(cosTotal_) : 0;
    }

  private:
    Point3 pos_;
    Vec3 dir_;
    Frame frame_;
    Spectrum I_;
    Float cosTotal_, cosFalloffStart_;
    bool gltf_;
};

// -------------------------------------------------------------- distant light
class DistantLight : public Light {
  public:
    DistantLight(const Transform &w, const Spectrum &L, const Vec3 &wLight)
        : Light(LIGHT_DELTA_DIRECTION, w), L_(L), w_(Normalize(w.applyVector(wLight))) {}
    void preprocess(const Bounds3 &b) override { b.boundingSphere(&center_, &radius_); }
    Spectrum power() const override { return L_ * (Pi * radius_ * radius_); }
    bool sampleLi(const Interaction &ref, Point2, LightLiSample *s) const override {
        s->wi = w_;
        s->pdf = 1;
        s->pLight = Interaction(ref.p + w_ * (2 * radius_), Normal3(0, 0, 0), -w_);
        s->L = L_;
        return true;
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        Frame f(w_);
        Point2 cd = SampleUniformDiskConcentric(u1);
        Point3 pDisk = center_ + (f.s * cd.x + f.t * cd.y) * radius_;
        s->ray = Ray(pDisk + w_ * radius_, -w_);
        s->p = s->ray.o;
        s->nLight = Normal3(0, 0, 0);
        s->pdfPos = 1 / (Pi * radius_ * radius_);
        s->pdfDir = 1;
        s->L = L_;
        return true;
    }
    void pdfLe(const Ray &, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfPos = 1 / (Pi * radius_ * radius_);
        *pdfDir = 0;
    }

  private:
    Spectrum L_;
    Vec3 w_;  // towards the light
    Point3 center_;
    Float radius_ = 1;
};

// ---------------------------------------------------------- infinite light
// sin x and cos x in one libm call where there is one (glibc's sincos gives
// the values of its sin and cos).
inline void SinCos(Float x, Float *s, Float *c) {
#if defined(__GLIBC__)
    ::sincos(x, s, c);
#else
    *s = std::sin(x);
    *c = std::cos(x);
#endif
}

// Constant or lat-long mapped environment, importance-sampled by luminance
// (pdf over (u,v) converted to solid angle with 1 / (2 pi^2 sin theta)).
class InfiniteLight : public Light {
  public:
    InfiniteLight(const Transform &w, const Spectrum &L, const Image *map)
        : Light(LIGHT_INFINITE, w), Lscale_(L), objectFromWorld_(w.inverse()) {
        if (map) {
            w_ = map->width();
            h_ = map->height();
            Image rgb = map->layerRGB("");
            texels_.resize(size_t(w_) * h_);
            for (int y = 0; y < h_; ++y)
                for (int x = 0; x < w_; ++x)
                    texels_[size_t(y) * w_ + x] = {rgb.at(x, y, 0), rgb.at(x, y, 1), rgb.at(x, y, 2)};
        } else {
            w_ = h_ = 1;
            texels_.assign(1, {1, 1, 1});
            constant_ = true;
        }
        std::vector<Float> f(size_t(w_) * h_);
        for (int y = 0; y < h_; ++y) {
            Float sinTheta = std::sin(Pi * (y + 0.5) / h_);
            for (int x = 0; x < w_; ++x) f[size_t(y) * w_ + x] = lookupTexel(x, y).y() * sinTheta;
        }
        dist_ = Distribution2D(f.data(), w_, h_);
    }
    void preprocess(const Bounds3 &b) override { b.boundingSphere(&center_, &radius_); }
    Spectrum lookupTexel(int x, int y) const {
        x = Clamp(x, 0, w_ - 1);
        y = Clamp(y, 0, h_ - 1);
        const RGB32 &t = texels_[size_t(y) * w_ + x];
        return Spectrum(t.r, t.g, t.b);
    }
    // Bilinear lookup at (u, v) in [0,1]^2 (u wraps).
    Spectrum lookup(Point2 st) const {
        Float x = st.x * w_ - 0.5, y = st.y * h_ - 0.5;
        // A non-finite direction (a degenerate ray) has no texel: no radiance
        // (fuzz_scene: NaN reached the int conversion below).
        if (!std::isfinite(x) || !std::isfinite(y)) return Spectrum(0);
        int x0 = int(std::floor(x)), y0 = int(std::floor(y));
        Float dx = x - x0, dy = y - y0;
        // Columns wrap (u in [0, 1] gives x0 in [-1, w - 1]: no division then).
        auto wrap = [&](int xi) { return xi >= 0 && xi < w_ ? xi : ((xi % w_) + w_) % w_; };
        int xa = wrap(x0), xb = wrap(x0 + 1);
        return lookupTexel(xa, y0) * ((1 - dx) * (1 - dy)) + lookupTexel(xb, y0) * (dx * (1 - dy)) +
               lookupTexel(xa, y0 + 1) * ((1 - dx) * dy) + lookupTexel(xb, y0 + 1) * (dx * dy);
    }
    // Spherical angles (theta, phi) of a world direction in the map's frame.
    // A path that escapes asks Le and then pdfLi of the same direction: each
    // thread keeps the last direction's angles (keyed by the light's serial
    // number and the direction's bits), which halves the acos/atan2 calls.
    struct Angles {
        Float theta, phi;
    };
    Angles anglesOf(const Vec3 &wWorld) const {
        struct Memo {
            uint64_t serial = 0;
            uint64_t bits[3] = {};
            Angles a{};
        };
        thread_local Memo memo;
        const uint64_t bits[3] = {FloatBits(wWorld.x), FloatBits(wWorld.y), FloatBits(wWorld.z)};
        if (memo.serial == serial_ && memo.bits[0] == bits[0] && memo.bits[1] == bits[1] && memo.bits[2] == bits[2])
            return memo.a;
        Vec3 wl = Normalize(objectFromWorld_.applyVector(wWorld));
        memo.serial = serial_;
        std::memcpy(memo.bits, bits, sizeof bits);
        memo.a = {SphericalTheta(wl), SphericalPhi(wl)};
        return memo.a;
    }
    // Radiance at map coordinates st; a constant environment (no map) is L
    // exactly, without a lookup.
    Spectrum radianceAt(Point2 st) const { return constant_ ? Lscale_ : Lscale_ * lookup(st); }
    Spectrum radiance(const Vec3 &wWorld) const {
        if (constant_)  // a non-finite direction has no radiance (as lookup gives it)
            return std::isfinite(wWorld.x + wWorld.y + wWorld.z) ? Lscale_ : Spectrum(0);
        Angles a = anglesOf(wWorld);
        return radianceAt(Point2(a.phi * Inv2Pi, a.theta * InvPi));
    }
    Spectrum Le(const Ray &r) const override { return radiance(r.d); }
    // Flux through the scene's bounding disk: pi r^2 times the integral of L
    // over directions (texels weighted by their solid angle).
    Spectrum power() const override {
        Spectrum sum(0);
        for (int y = 0; y < h_; ++y) {
            Float dOmega = (2 * Pi / w_) * (std::cos(Pi * y / h_) - std::cos(Pi * (y + 1) / h_));
            for (int x = 0; x < w_; ++x) sum += lookupTexel(x, y) * dOmega;
        }
        return Lscale_ * sum * (Pi * radius_ * radius_);
    }
    // A sampled direction and its pdf; *st receives its map coordinates, at
    // which the caller looks the radiance up (as pbrt-v3 does: no round trip
    // through the direction, its transform and acos/atan2).
    Vec3 directionFrom(Point2 uv, Float *pdf, Point2 *stOut) const {
        Float mapPdf;
        Point2 st = dist_.sampleContinuous(uv, &mapPdf);
        *stOut = st;
        Float theta = st.y * Pi, phi = st.x * 2 * Pi;
        Float sinTheta, cosTheta, sinPhi, cosPhi;
        SinCos(theta, &sinTheta, &cosTheta);
        SinCos(phi, &sinPhi, &cosPhi);
        // SphericalDirection(sinTheta, cosTheta, phi), with phi's sine and cosine from one call.
        Float st1 = Clamp<Float>(sinTheta, -1, 1);
        Vec3 wl(st1 * cosPhi, st1 * sinPhi, Clamp<Float>(cosTheta, -1, 1));
        *pdf = (sinTheta == 0 || mapPdf == 0) ? 0 : mapPdf / (2 * Pi * Pi * sinTheta);
        return Normalize(worldFromLight.applyVector(wl));
    }
    Float pdfDirection(const Vec3 &wWorld) const {
        Angles a = anglesOf(wWorld);
        Float theta = a.theta, phi = a.phi;
        Float sinTheta = std::sin(theta);
        if (!(sinTheta > 0)) return 0;  // the poles, and non-finite directions
        return dist_.pdf(Point2(phi * Inv2Pi, theta * InvPi)) / (2 * Pi * Pi * sinTheta);
    }
    bool sampleLi(const Interaction &ref, Point2 u, LightLiSample *s) const override {
        Float pdf;
        Point2 st;
        Vec3 wi = directionFrom(u, &pdf, &st);
        if (pdf == 0) return false;
        s->wi = wi;
        s->pdf = pdf;
        s->pLight = Interaction(ref.p + wi * (2 * radius_), Normal3(0, 0, 0), -wi);
        s->L = radianceAt(st);
        return !s->L.isBlack();
    }
    Float pdfLi(const Interaction &, const Vec3 &wi) const override { return pdfDirection(wi); }
    bool sampleLe(Point2 u1, Point2 u2, LightLeSample *s) const override {
        Float pdfDir;
        Point2 st;
        Vec3 wi = directionFrom(u1, &pdfDir, &st);  // direction towards the light
        if (pdfDir == 0) return false;
        Vec3 d = -wi;
        Frame f(d);
        Point2 cd = SampleUniformDiskConcentric(u2);
        Point3 pDisk = center_ + (f.s * cd.x + f.t * cd.y) * radius_;
        s->ray = Ray(pDisk - d * radius_, d);
        s->p = s->ray.o;
        s->nLight = d;
        s->pdfPos = 1 / (Pi * radius_ * radius_);
        s->pdfDir = pdfDir;
        s->L = radianceAt(st);
        return !s->L.isBlack();
    }
    void pdfLe(const Ray &ray, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfDir = pdfDirection(-ray.d);
        *pdfPos = 1 / (Pi * radius_ * radius_);
    }
    Float pdfLePosition(const Ray &, const Normal3 &) const override { return 1 / (Pi * radius_ * radius_); }

  private:
    Spectrum Lscale_;
    Transform objectFromWorld_;
    int w_ = 1, h_ = 1;
    bool constant_ = false;  // no map: L in every direction
    // The map's float texels as stored (half the bytes of Spectrum's doubles;
    // the conversion to double is exact).
    struct RGB32 {
        float r, g, b;
    };
    std::vector<RGB32> texels_;
    Distribution2D dist_;
    // Distinct for every InfiniteLight ever made (never 0): the memo of anglesOf.
    const uint64_t serial_ = NextSerial();
    static uint64_t NextSerial() {
        static std::atomic<uint64_t> next{1};
        return next.fetch_add(1, std::memory_order_relaxed);
    }
    Point3 center_;
    Float radius_ = 1;
};

}  // namespace

std::shared_ptr<Light> CreateInfiniteLight(const Transform &worldFromLight, const Spectrum &L, const Image *map) {
    return std::make_shared<InfiniteLight>(worldFromLight, L, map);
}

std::shared_ptr<Light> CreateLight(const LightDesc &desc, const SceneDesc &scene) {
    const ParamSet &ps = desc.params;
    Spectrum scale = ps.getSpectrum("scale", Spectrum(1));
    const std::string &t = desc.type;
    std::shared_ptr<Light> light;
    if (t == "point") {
        Spectrum I = ps.getSpectrum("I", Spectrum(1), SpectrumKind::Illuminant) * scale;
        Point3 from = ps.getPoint3("from", Point3(0, 0, 0));
        light = std::make_shared<PointLight>(desc.worldFromLight * Translate(from), I);
    } else if (t == "spot") {
        Spectrum I = ps.getSpectrum("I", Spectrum(1), SpectrumKind::Illuminant) * scale;
        Float cone = ps.getFloat("coneangle", 30), delta = ps.getFloat("conedeltaangle", 5);
        Point3 from = ps.getPoint3("from", Point3(0, 0, 0)), to = ps.getPoint3("to", Point3(0, 0, 1));
        Vec3 dir = to - from;
        if (!(dir.length() > 0)) throw Error(desc.loc, "spot light: \"from\" and \"to\" coincide");
        // Light space: +z along (to - from).
        Frame f(Normalize(dir));
        Matrix4 m(f.s.x, f.t.x, f.n.x, from.x, f.s.y, f.t.y, f.n.y, from.y, f.s.z, f.t.z, f.n.z, from.z, 0, 0, 0, 1);
        std::string fo = ps.getString("falloff", "pbrt");
        if (fo != "pbrt" && fo != "gltf")
            throw Error(ps.locOf("falloff", desc.loc), "spot light: unknown \"falloff\" \"" + fo + "\" (known: pbrt, gltf)");
        light = std::make_shared<SpotLight>(desc.worldFromLight * Transform(m), I, cone, delta, fo == "gltf");
    } else if (t == "distant") {
        Spectrum L = ps.getSpectrum("L", Spectrum(1), SpectrumKind::Illuminant) * scale;
        Point3 from = ps.getPoint3("from", Point3(0, 0, 0)), to = ps.getPoint3("to", Point3(0, 0, 1));
        if (!((from - to).length() > 0)) throw Error(desc.loc, "distant light: \"from\" and \"to\" coincide");
        light = std::make_shared<DistantLight>(desc.worldFromLight, L, from - to);
    } else if (t == "infinite" || t == "exinfinite") {
        Spectrum L = ps.getSpectrum("L", Spectrum(1), SpectrumKind::Illuminant) * scale;
        // pbrt-v3's "samples" (alias "nsamples"): light samples per hit of directlighting's "all" strategy.
        const int nSamples = ps.getInt("samples", ps.getInt("nsamples", 1));
        std::string map = ps.getString("mapname", "");
        if (desc.map) {
            light = std::make_shared<InfiniteLight>(desc.worldFromLight, L, desc.map.get());
        } else if (!map.empty()) {
            Image img;
            try {
                // 8-bit files as stored (code / 255), as pbrt-v3's InfiniteAreaLight reads them
                // (imageio.cpp: no sRGB decoding for lights).
                img = ReadImage(scene.resolve(map), IntegerPixels::Stored);
            } catch (const Error &e) {
                throw Error(ps.locOf("mapname", desc.loc), e.what());
            }
            light = std::make_shared<InfiniteLight>(desc.worldFromLight, L, &img);
        } else {
            light = std::make_shared<InfiniteLight>(desc.worldFromLight, L, nullptr);
        }
        light->nSamples = std::max(1, nSamples);
    } else if (t == "goniometric" || t == "projection") {
        Spectrum I = ps.getSpectrum("I", Spectrum(1), SpectrumKind::Illuminant) * scale;
        const std::string map = ps.getString("mapname", "");
        std::unique_ptr<LightImage> img;
        if (!map.empty()) {
            try {
                img = LightImage::Read(scene.resolve(map));
            } catch (const Error &e) {
                throw Error(ps.locOf("mapname", desc.loc), e.what());
            }
        }
        // pbrt-v3's goniometric light space: +y is the pole of the map (its
        // Frame rotation); the projector looks along +z.
        if (t == "goniometric") {
            light = std::make_shared<GoniometricLight>(desc.worldFromLight, I, std::move(img));
        } else {
            const Float fov = ps.getFloat("fov", 45);
            if (!(fov > 0 && fov < 180))
                throw Error(ps.locOf("fov", desc.loc), "projection light: \"fov\" must lie in (0, 180) degrees");
            light = std::make_shared<ProjectionLight>(desc.worldFromLight, I, std::move(img), fov);
        }
    } else {
        throw Error(desc.loc, "unknown light type \"" + t +
                                  "\" (valid: point, spot, distant, infinite, goniometric, projection)");
    }
    desc.params.checkUnused("LightSource \"" + t + "\"");
    return light;
}

}  // namespace gradus
