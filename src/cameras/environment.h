// pbrt-v3's environment camera: a latitude-longitude image of every direction
// around the camera origin.
#pragma once
#include "cameras/camera.h"

namespace gradus {

class EnvironmentCamera : public Camera {
  public:
    EnvironmentCamera(const Transform &worldFromCamera, Point2i resolution);
    // Raster (x, y) -> theta = pi y / height, phi = 2 pi x / width, camera-space
    // direction (sin theta cos phi, cos theta, sin theta sin phi): +y is the image's top row.
    Float generateRay(const CameraSample &s, Ray *ray) const override;
    // No importance function (hasImportance false): bidirectional integrators refuse it.
    Spectrum We(const Ray &ray, Point2 *pRaster) const override { return Spectrum(0); }
    void pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const override { *pdfPos = *pdfDir = 0; }
    bool sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const override { return false; }
    Normal3 lensNormal() const override { return viewDir_; }
    bool rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const override;
    bool hasImportance() const override { return false; }
    // The camera-space direction of raster point pFilm (for tests).
    Vec3 directionOf(Point2 pFilm) const;

  private:
    Transform worldFromCamera_;
    Normal3 viewDir_;
};

}  // namespace gradus
