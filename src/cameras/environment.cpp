#include "cameras/environment.h"

#include "core/error.h"

namespace gradus {

EnvironmentCamera::EnvironmentCamera(const Transform &worldFromCamera, Point2i res)
    : worldFromCamera_(worldFromCamera) {
    fullResolution = res;
    viewDir_ = Normal3(Normalize(worldFromCamera_.applyVector(Vec3(0, 0, 1))));
}

Vec3 EnvironmentCamera::directionOf(Point2 pFilm) const {
    const Float theta = Pi * pFilm.y / fullResolution.y, phi = 2 * Pi * pFilm.x / fullResolution.x;
    return Vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
}

Float EnvironmentCamera::generateRay(const CameraSample &s, Ray *ray) const {
    *ray = Ray(worldFromCamera_.applyPoint(Point3(0, 0, 0)),
               Normalize(worldFromCamera_.applyVector(directionOf(s.pFilm))));
    return 1;
}

bool EnvironmentCamera::rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const {
    *ray = Ray(worldFromCamera_.applyPoint(Point3(0, 0, 0)),
               Normalize(worldFromCamera_.applyVector(directionOf(pFilm))));
    return true;  // one origin: the lens point is always the camera's
}

std::unique_ptr<Camera> CreateEnvironmentCamera(const CameraDesc &desc, Point2i res) {
    const ParamSet &ps = desc.params;
    // pbrt-v3 reads the common camera parameters and ignores all but the
    // shutter (which Gradus ignores too: no motion blur).
    ps.getFloat("shutteropen", 0);
    ps.getFloat("shutterclose", 1);
    ps.getFloat("lensradius", 0);
    ps.getFloat("focaldistance", 1e30);
    Float sw[4];
    ReadScreenWindow(ps, desc.loc, res, sw);
    CheckCameraPlacement(desc);
    ps.checkUnused("Camera \"environment\"");
    return std::make_unique<EnvironmentCamera>(desc.cameraFromWorld.inverse(), res);
}

}  // namespace gradus
