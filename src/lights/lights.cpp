#include <cmath>

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

// ---------------------------------------------------------------- point light
class PointLight : public Light {
  public:
    PointLight(const Transform &w, const Spectrum &I)
        : Light(LIGHT_DELTA_POSITION, w), pos_(w.applyPoint(Point3(0, 0, 0))), I_(I) {}
    Spectrum power() const override { return I_ * (4 * Pi); }
    bool sampleLi(const Interaction &ref, Point2, LightLiSample *s) const override {
        Vec3 d = pos_ - ref.p;
        Float d2 = d.lengthSquared();
        if (d2 == 0) return false;
        s->wi = d / std::sqrt(d2);
        s->pdf = 1;
        s->pLight = Interaction(pos_, Normal3(0, 0, 0), -s->wi);
        s->L = I_ / d2;
        return true;
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        s->ray = Ray(pos_, SampleUniformSphere(u1));
        s->p = pos_;
        s->nLight = Normal3(0, 0, 0);
        s->pdfPos = 1;
        s->pdfDir = UniformSpherePdf();
        s->L = I_;
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
        Vec3 d = pos_ - ref.p;
        Float d2 = d.lengthSquared();
        if (d2 == 0) return false;
        s->wi = d / std::sqrt(d2);
        s->pdf = 1;
        s->pLight = Interaction(pos_, Normal3(0, 0, 0), -s->wi);
        s->L = I_ * (falloff(-s->wi) / d2);
        return !s->L.isBlack();
    }
    Float pdfLi(const Interaction &, const Vec3 &) const override { return 0; }
    bool sampleLe(Point2 u1, Point2, LightLeSample *s) const override {
        Vec3 wl = SampleUniformCone(u1, cosTotal_);
        Vec3 w = frame_.toWorld(wl);
        s->ray = Ray(pos_, w);
        s->p = pos_;
        s->nLight = Normal3(0, 0, 0);
        s->pdfPos = 1;
        s->pdfDir = UniformConePdf(cosTotal_);
        s->L = I_ * falloff(w);
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
                    texels_[size_t(y) * w_ + x] = Spectrum(rgb.at(x, y, 0), rgb.at(x, y, 1), rgb.at(x, y, 2));
        } else {
            w_ = h_ = 1;
            texels_.assign(1, Spectrum(1));
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
        return texels_[size_t(y) * w_ + x];
    }
    // Bilinear lookup at (u, v) in [0,1]^2 (u wraps).
    Spectrum lookup(Point2 st) const {
        Float x = st.x * w_ - 0.5, y = st.y * h_ - 0.5;
        // A non-finite direction (a degenerate ray) has no texel: no radiance
        // (fuzz_scene: NaN reached the int conversion below).
        if (!std::isfinite(x) || !std::isfinite(y)) return Spectrum(0);
        int x0 = int(std::floor(x)), y0 = int(std::floor(y));
        Float dx = x - x0, dy = y - y0;
        auto tex = [&](int xi, int yi) { return lookupTexel(((xi % w_) + w_) % w_, yi); };
        return tex(x0, y0) * ((1 - dx) * (1 - dy)) + tex(x0 + 1, y0) * (dx * (1 - dy)) +
               tex(x0, y0 + 1) * ((1 - dx) * dy) + tex(x0 + 1, y0 + 1) * (dx * dy);
    }
    Spectrum radiance(const Vec3 &wWorld) const {
        Vec3 wl = Normalize(objectFromWorld_.applyVector(wWorld));
        Point2 st(SphericalPhi(wl) * Inv2Pi, SphericalTheta(wl) * InvPi);
        return Lscale_ * lookup(st);
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
    Vec3 directionFrom(Point2 uv, Float *pdf) const {
        Float mapPdf;
        Point2 st = dist_.sampleContinuous(uv, &mapPdf);
        Float theta = st.y * Pi, phi = st.x * 2 * Pi;
        Float sinTheta = std::sin(theta);
        Vec3 wl = SphericalDirection(sinTheta, std::cos(theta), phi);
        *pdf = (sinTheta == 0 || mapPdf == 0) ? 0 : mapPdf / (2 * Pi * Pi * sinTheta);
        return Normalize(worldFromLight.applyVector(wl));
    }
    Float pdfDirection(const Vec3 &wWorld) const {
        Vec3 wl = Normalize(objectFromWorld_.applyVector(wWorld));
        Float theta = SphericalTheta(wl), phi = SphericalPhi(wl);
        Float sinTheta = std::sin(theta);
        if (!(sinTheta > 0)) return 0;  // the poles, and non-finite directions
        return dist_.pdf(Point2(phi * Inv2Pi, theta * InvPi)) / (2 * Pi * Pi * sinTheta);
    }
    bool sampleLi(const Interaction &ref, Point2 u, LightLiSample *s) const override {
        Float pdf;
        Vec3 wi = directionFrom(u, &pdf);
        if (pdf == 0) return false;
        s->wi = wi;
        s->pdf = pdf;
        s->pLight = Interaction(ref.p + wi * (2 * radius_), Normal3(0, 0, 0), -wi);
        s->L = radiance(wi);
        return !s->L.isBlack();
    }
    Float pdfLi(const Interaction &, const Vec3 &wi) const override { return pdfDirection(wi); }
    bool sampleLe(Point2 u1, Point2 u2, LightLeSample *s) const override {
        Float pdfDir;
        Vec3 wi = directionFrom(u1, &pdfDir);  // direction towards the light
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
        s->L = radiance(wi);
        return !s->L.isBlack();
    }
    void pdfLe(const Ray &ray, const Normal3 &, Float *pdfPos, Float *pdfDir) const override {
        *pdfDir = pdfDirection(-ray.d);
        *pdfPos = 1 / (Pi * radius_ * radius_);
    }

  private:
    Spectrum Lscale_;
    Transform objectFromWorld_;
    int w_ = 1, h_ = 1;
    std::vector<Spectrum> texels_;
    Distribution2D dist_;
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
        ps.getInt("nsamples", 1);  // accepted: Gradus sets light samples in the integrator
        std::string map = ps.getString("mapname", "");
        if (!map.empty()) {
            Image img;
            try {
                img = ReadImage(scene.resolve(map));
            } catch (const Error &e) {
                throw Error(ps.locOf("mapname", desc.loc), e.what());
            }
            light = std::make_shared<InfiniteLight>(desc.worldFromLight, L, &img);
        } else {
            light = std::make_shared<InfiniteLight>(desc.worldFromLight, L, nullptr);
        }
    } else if (t == "goniometric" || t == "projection") {
        throw UnsupportedError(desc.loc, "LightSource \"" + t + "\"");
    } else {
        throw Error(desc.loc, "unknown light type \"" + t +
                                  "\" (valid: point, spot, distant, infinite, goniometric, projection)");
    }
    desc.params.checkUnused("LightSource \"" + t + "\"");
    return light;
}

}  // namespace gradus
