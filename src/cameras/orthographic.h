// pbrt-v3's orthographic camera: rays parallel to the view axis from the
// screen window (camera-space units) on the z = 0 plane, optional thin lens.
#pragma once
#include "cameras/camera.h"

namespace gradus {

class OrthographicCamera : public Camera {
  public:
    OrthographicCamera(const Transform &worldFromCamera, Point2i resolution, const Float screenWindow[4],
                       Float lensRadius, Float focalDistance);
    Float generateRay(const CameraSample &s, Ray *ray) const override;
    // Importance is a Dirac in direction (pinhole) or a convolution with the
    // lens (thin lens): no density to connect to. We and pdfDir are 0, pdfPos
    // 1 / (film area) inside the image; sampleWi fails (hasImportance false).
    Spectrum We(const Ray &ray, Point2 *pRaster) const override;
    void pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const override;
    bool sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const override { return false; }
    Normal3 lensNormal() const override { return viewDir_; }
    // Thin lens only: the ray from a lens point (within lensradius of the
    // film point's camera-space position) through the film point's focus.
    bool rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const override;
    bool hasImportance() const override { return false; }
    const Transform &cameraFromRaster() const { return cameraFromRaster_; }
    Float filmArea() const { return filmArea_; }

  private:
    Transform worldFromCamera_, cameraFromWorld_;
    Transform cameraFromRaster_, rasterFromCamera_;
    Float lensRadius_, focalDistance_;
    Float filmArea_;  // of the screen window, camera-space units
    Normal3 viewDir_;
};

}  // namespace gradus
