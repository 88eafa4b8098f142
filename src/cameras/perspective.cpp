#include "cameras/camera.h"
#include "core/error.h"
#include "samplers/sampling.h"

namespace gradus {

Transform RasterFromScreen(Point2i res, const Float sw[4]) {
    return Scale(res.x, res.y, 1) * Scale(1 / (sw[1] - sw[0]), 1 / (sw[2] - sw[3]), 1) *
           Translate(Vec3(-sw[0], -sw[3], 0));
}

PerspectiveCamera::PerspectiveCamera(const Transform &worldFromCamera, Point2i res, const Float sw[4], Float fov,
                                     Float lensRadius, Float focalDistance)
    : worldFromCamera_(worldFromCamera),
      cameraFromWorld_(worldFromCamera.inverse()),
      lensRadius_(lensRadius),
      focalDistance_(focalDistance) {
    fullResolution = res;
    // pbrt-v3: screen -> raster maps the screen window onto the full resolution, y flipped.
    Transform screenFromCamera = Perspective(fov, 1e-2, 1000);
    rasterFromCamera_ = RasterFromScreen(res, sw) * screenFromCamera;
    cameraFromRaster_ = rasterFromCamera_.inverse();
    Point3 pMin = cameraFromRaster_.applyPoint(Point3(0, 0, 0));
    Point3 pMax = cameraFromRaster_.applyPoint(Point3(res.x, res.y, 0));
    pMin = pMin / pMin.z;
    pMax = pMax / pMax.z;
    imagePlaneArea_ = std::abs((pMax.x - pMin.x) * (pMax.y - pMin.y));
    viewDir_ = Normalize(worldFromCamera_.applyVector(Vec3(0, 0, 1)));
}

Float PerspectiveCamera::generateRay(const CameraSample &s, Ray *ray) const {
    Point3 pCam = cameraFromRaster_.applyPoint(Point3(s.pFilm.x, s.pFilm.y, 0));
    Vec3 d = Normalize(pCam);
    Point3 o(0, 0, 0);
    if (lensRadius_ > 0) {
        Point2 pl = SampleUniformDiskConcentric(s.pLens) * lensRadius_;
        Float ft = focalDistance_ / d.z;
        Point3 pFocus = d * ft;
        o = Point3(pl.x, pl.y, 0);
        d = Normalize(pFocus - o);
    }
    *ray = Ray(worldFromCamera_.applyPoint(o), Normalize(worldFromCamera_.applyVector(d)));
    return 1;
}

bool PerspectiveCamera::rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const {
    const Vec3 d = Normalize(Vec3(cameraFromRaster_.applyPoint(Point3(pFilm.x, pFilm.y, 0))));
    if (lensRadius_ <= 0) {
        *ray = Ray(worldFromCamera_.applyPoint(Point3(0, 0, 0)), Normalize(worldFromCamera_.applyVector(d)));
        return true;
    }
    // Thin lens: every ray through the film point meets the focal plane at the
    // point the chief ray (through the lens centre) meets it.
    const Point3 pFocus = worldFromCamera_.applyPoint(Point3(d * (focalDistance_ / d.z)));
    const Vec3 w = pFocus - lensPoint;
    if (!(w.lengthSquared() > 0)) return false;
    *ray = Ray(lensPoint, Normalize(w));
    return true;
}

// We of pbrt-v3's perspective camera: 1 / (A * lensArea * cos^4 theta) inside the image.
Spectrum PerspectiveCamera::We(const Ray &ray, Point2 *pRaster) const {
    Float cosTheta = Dot(ray.d, viewDir_);
    if (cosTheta <= 0) return Spectrum(0);
    Point3 pFocus = ray(((lensRadius_ > 0) ? focalDistance_ : 1) / cosTheta);
    Point3 pr = rasterFromCamera_.applyPoint(cameraFromWorld_.applyPoint(pFocus));
    if (pRaster) *pRaster = Point2(pr.x, pr.y);
    if (pr.x < 0 || pr.x >= fullResolution.x || pr.y < 0 || pr.y >= fullResolution.y) return Spectrum(0);
    Float lensArea = lensRadius_ > 0 ? Pi * lensRadius_ * lensRadius_ : 1;
    Float cos2 = cosTheta * cosTheta;
    return Spectrum(1 / (imagePlaneArea_ * lensArea * cos2 * cos2));
}

void PerspectiveCamera::pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const {
    Float cosTheta = Dot(ray.d, viewDir_);
    *pdfPos = *pdfDir = 0;
    if (cosTheta <= 0) return;
    Point3 pFocus = ray(((lensRadius_ > 0) ? focalDistance_ : 1) / cosTheta);
    Point3 pr = rasterFromCamera_.applyPoint(cameraFromWorld_.applyPoint(pFocus));
    if (pr.x < 0 || pr.x >= fullResolution.x || pr.y < 0 || pr.y >= fullResolution.y) return;
    Float lensArea = lensRadius_ > 0 ? Pi * lensRadius_ * lensRadius_ : 1;
    *pdfPos = 1 / lensArea;
    *pdfDir = 1 / (imagePlaneArea_ * cosTheta * cosTheta * cosTheta);
}

bool PerspectiveCamera::sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const {
    Point2 pl = SampleUniformDiskConcentric(u) * lensRadius_;
    Point3 pLensW = worldFromCamera_.applyPoint(Point3(pl.x, pl.y, 0));
    Vec3 wi = pLensW - ref.p;
    Float dist2 = wi.lengthSquared();
    if (dist2 == 0) return false;
    Float dist = std::sqrt(dist2);
    wi = wi / dist;
    s->pLens = Interaction(pLensW, viewDir_, Vec3(0, 0, 0));
    Float lensArea = lensRadius_ > 0 ? Pi * lensRadius_ * lensRadius_ : 1;
    Float cosL = AbsDot(viewDir_, wi);
    if (cosL == 0) return false;
    s->pdf = dist2 / (cosL * lensArea);
    s->wi = wi;
    s->We = We(Ray(pLensW, -wi), &s->pRaster);
    return !s->We.isBlack();
}

void ReadScreenWindow(const ParamSet &ps, const FileLoc &loc, Point2i res, Float sw[4]) {
    Float aspect = ps.getFloat("frameaspectratio", Float(res.x) / Float(res.y));
    if (!(aspect > 0) || !std::isfinite(aspect))
        throw Error(ps.locOf("frameaspectratio", loc), "\"frameaspectratio\" must be > 0 and finite");
    if (aspect > 1) {
        sw[0] = -aspect; sw[1] = aspect; sw[2] = -1; sw[3] = 1;
    } else {
        sw[0] = -1; sw[1] = 1; sw[2] = -1 / aspect; sw[3] = 1 / aspect;
    }
    std::vector<Float> swp = ps.getFloats("screenwindow");
    if (!swp.empty()) {
        if (swp.size() != 4) throw Error(ps.locOf("screenwindow", loc), "\"screenwindow\" needs 4 values");
        for (int i = 0; i < 4; ++i) sw[i] = swp[i];
        if (!(std::isfinite(sw[0] + sw[1] + sw[2] + sw[3]) && sw[0] != sw[1] && sw[2] != sw[3]))
            throw Error(ps.locOf("screenwindow", loc), "\"screenwindow\" must be finite with x0 != x1 and y0 != y1");
    }
}

void CheckCameraPlacement(const CameraDesc &desc) {
    constexpr Float kMaxLength = 1e15;
    Point3 eye = desc.cameraFromWorld.inverse().applyPoint(Point3(0, 0, 0));
    if (!(std::abs(eye.x) <= kMaxLength && std::abs(eye.y) <= kMaxLength && std::abs(eye.z) <= kMaxLength))
        throw Error(desc.loc, "the camera lies more than 1e15 scene units from the origin, beyond the range the ray "
                              "tracer handles");
}

std::unique_ptr<Camera> CreateCamera(const CameraDesc &desc, Point2i res, const SceneDesc *scene) {
    const ParamSet &ps = desc.params;
    std::string type = desc.present ? desc.type : "perspective";
    if (type == "orthographic") return CreateOrthographicCamera(desc, res);
    if (type == "environment") return CreateEnvironmentCamera(desc, res);
    if (type == "realistic") return CreateRealisticCamera(desc, res, scene);
    if (type != "perspective")
        throw Error(desc.loc, "unknown camera type \"" + type + "\" (valid: perspective, orthographic, environment, "
                              "realistic)");
    ps.getFloat("shutteropen", 0);
    ps.getFloat("shutterclose", 1);
    Float lensRadius = ps.getFloat("lensradius", 0);
    Float focalDistance = ps.getFloat("focaldistance", 1e6);
    Float aspect = ps.getFloat("frameaspectratio", Float(res.x) / Float(res.y));
    Float sw[4];
    ReadScreenWindow(ps, desc.loc, res, sw);
    const bool hasWindow = ps.has("screenwindow");
    Float fov = ps.getFloat("fov", 90);
    Float halffov = ps.getFloat("halffov", -1);
    if (halffov > 0) fov = 2 * halffov;
    // Gradus extension (glTF cameras): "yfov" is the vertical field of view
    // whatever the image's aspect ratio.
    if (ps.has("yfov")) {
        if (ps.has("fov") || ps.has("halffov") || hasWindow)
            throw Error(ps.locOf("yfov", desc.loc), "\"yfov\" excludes \"fov\", \"halffov\" and \"screenwindow\"");
        fov = ps.getFloat("yfov", 60);
        sw[0] = -aspect, sw[1] = aspect, sw[2] = -1, sw[3] = 1;
    }
    if (!(fov > 0 && fov < 180)) throw Error(ps.locOf("fov", desc.loc), "\"fov\" must be in (0, 180) degrees");
    if (lensRadius < 0) throw Error(ps.locOf("lensradius", desc.loc), "\"lensradius\" must be >= 0");
    // Lengths beyond 1e15 scene units leave the range the ray tracer (Embree,
    // single precision, origins below ~1.8e18) can trace: refused, not aborted on.
    constexpr Float kMaxLength = 1e15;
    if (!(focalDistance > 0 && focalDistance <= kMaxLength))
        throw Error(ps.locOf("focaldistance", desc.loc), "\"focaldistance\" must be in (0, 1e15]");
    if (lensRadius > kMaxLength) throw Error(ps.locOf("lensradius", desc.loc), "\"lensradius\" must be <= 1e15");
    CheckCameraPlacement(desc);
    ps.checkUnused("Camera \"perspective\"");
    return std::make_unique<PerspectiveCamera>(desc.cameraFromWorld.inverse(), res, sw, fov, lensRadius,
                                               focalDistance);
}

}  // namespace gradus
