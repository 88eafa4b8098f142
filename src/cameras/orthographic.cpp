#include "cameras/orthographic.h"

#include "core/error.h"
#include "samplers/sampling.h"

namespace gradus {

OrthographicCamera::OrthographicCamera(const Transform &worldFromCamera, Point2i res, const Float sw[4],
                                       Float lensRadius, Float focalDistance)
    : worldFromCamera_(worldFromCamera),
      cameraFromWorld_(worldFromCamera.inverse()),
      lensRadius_(lensRadius),
      focalDistance_(focalDistance) {
    fullResolution = res;
    // pbrt-v3: screen = camera space (Orthographic(0, 1) is the identity on
    // z = 0); screen -> raster maps the window onto the full resolution, y flipped.
    rasterFromCamera_ = RasterFromScreen(res, sw) * Orthographic(0, 1);
    cameraFromRaster_ = rasterFromCamera_.inverse();
    filmArea_ = std::abs((sw[1] - sw[0]) * (sw[3] - sw[2]));
    viewDir_ = Normal3(Normalize(worldFromCamera_.applyVector(Vec3(0, 0, 1))));
}

Float OrthographicCamera::generateRay(const CameraSample &s, Ray *ray) const {
    const Point3 pCam = cameraFromRaster_.applyPoint(Point3(s.pFilm.x, s.pFilm.y, 0));
    Point3 o = pCam;
    Vec3 d(0, 0, 1);
    if (lensRadius_ > 0) {
        // Thin lens centred on the film point's ray, focused at z = focaldistance
        // (pbrt-v4's form; pbrt-v3 put every lens sample around the camera-space
        // origin, which bends all rays towards the window's centre).
        const Point2 pl = SampleUniformDiskConcentric(s.pLens) * lensRadius_;
        const Point3 pFocus(pCam.x, pCam.y, focalDistance_);
        o = Point3(pCam.x + pl.x, pCam.y + pl.y, 0);
        d = Normalize(pFocus - o);
    }
    *ray = Ray(worldFromCamera_.applyPoint(o), Normalize(worldFromCamera_.applyVector(d)));
    return 1;
}

bool OrthographicCamera::rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const {
    if (lensRadius_ <= 0) return false;  // the film point fixes the whole ray
    const Point3 pCam = cameraFromRaster_.applyPoint(Point3(pFilm.x, pFilm.y, 0));
    const Point3 l = cameraFromWorld_.applyPoint(lensPoint);
    const Float dx = l.x - pCam.x, dy = l.y - pCam.y;
    if (dx * dx + dy * dy > lensRadius_ * lensRadius_) return false;
    const Point3 pFocus(pCam.x, pCam.y, focalDistance_);
    *ray = Ray(lensPoint, Normalize(worldFromCamera_.applyVector(pFocus - Point3(l.x, l.y, 0))));
    return true;
}

Spectrum OrthographicCamera::We(const Ray &ray, Point2 *pRaster) const {
    if (pRaster) {
        const Point3 pr = rasterFromCamera_.applyPoint(cameraFromWorld_.applyPoint(ray.o));
        *pRaster = Point2(pr.x, pr.y);
    }
    return Spectrum(0);
}

void OrthographicCamera::pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const {
    *pdfPos = *pdfDir = 0;
    const Point3 pr = rasterFromCamera_.applyPoint(cameraFromWorld_.applyPoint(ray.o));
    if (lensRadius_ > 0 || pr.x < 0 || pr.x >= fullResolution.x || pr.y < 0 || pr.y >= fullResolution.y) return;
    *pdfPos = 1 / filmArea_;
}

std::unique_ptr<Camera> CreateOrthographicCamera(const CameraDesc &desc, Point2i res) {
    const ParamSet &ps = desc.params;
    ps.getFloat("shutteropen", 0);
    ps.getFloat("shutterclose", 1);
    const Float lensRadius = ps.getFloat("lensradius", 0);
    const Float focalDistance = ps.getFloat("focaldistance", 1e6);
    Float sw[4];
    ReadScreenWindow(ps, desc.loc, res, sw);
    constexpr Float kMaxLength = 1e15;  // Embree's single-precision range (as for perspective)
    if (!(lensRadius >= 0 && lensRadius <= kMaxLength))
        throw Error(ps.locOf("lensradius", desc.loc), "\"lensradius\" must be in [0, 1e15]");
    if (!(focalDistance > 0 && focalDistance <= kMaxLength))
        throw Error(ps.locOf("focaldistance", desc.loc), "\"focaldistance\" must be in (0, 1e15]");
    for (int i = 0; i < 4; ++i)
        if (!(std::abs(sw[i]) <= kMaxLength))
            throw Error(ps.locOf("screenwindow", desc.loc), "\"screenwindow\" must lie within 1e15 of the axis");
    CheckCameraPlacement(desc);
    ps.checkUnused("Camera \"orthographic\"");
    return std::make_unique<OrthographicCamera>(desc.cameraFromWorld.inverse(), res, sw, lensRadius, focalDistance);
}

}  // namespace gradus
