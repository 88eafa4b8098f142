// Cameras. The perspective camera follows pbrt-v3 (fov on the shorter image
// axis, screen window, thin lens) and exposes the importance function We and
// its pdfs, which light tracing and bidirectional connections need.
#pragma once
#include <memory>

#include "core/transform.h"
#include "parser/scene_desc.h"
#include "core/interaction.h"

namespace gradus {

struct CameraSample {
    Point2 pFilm;  // continuous raster position
    Point2 pLens;  // [0,1)^2
};

struct CameraWiSample {
    Spectrum We;          // importance arriving along -wi at the lens point
    Vec3 wi;              // from ref towards the lens point
    Float pdf = 0;        // solid angle at ref
    Point2 pRaster;       // raster position of the connection
    Interaction pLens;
};

// pbrt-v3's screen -> raster map: the screen window sw (x0 x1 y0 y1) onto the
// full resolution, y flipped (shared by the projective cameras).
Transform RasterFromScreen(Point2i res, const Float sw[4]);

class Camera {
  public:
    virtual ~Camera() = default;
    // Ray with unit direction in world space; returns the weight (0 if none: the
    // sample still counts in its pixel, with radiance 0, as in pbrt-v3).
    virtual Float generateRay(const CameraSample &s, Ray *ray) const = 0;
    // Importance along ray (from the lens); *pRaster receives the raster point.
    virtual Spectrum We(const Ray &ray, Point2 *pRaster) const = 0;
    virtual void pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const = 0;
    // Samples a lens point as seen from ref (for t = 1 connections).
    virtual bool sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const = 0;
    virtual Normal3 lensNormal() const = 0;  // world-space view direction (the lens plane normal)
    // The ray from a given world-space lens point through film position pFilm
    // (the lens point held, as G-MLT's shift holds x_0); false if none.
    virtual bool rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const = 0;
    // False when We, pdfWe's direction density and sampleWi are not defined
    // (orthographic: a Dirac direction; environment, realistic): no light-to-
    // camera (t = 1) connections; only integrators that do without them render it.
    virtual bool hasImportance() const { return true; }
    Point2i fullResolution;
};

class PerspectiveCamera : public Camera {
  public:
    PerspectiveCamera(const Transform &worldFromCamera, Point2i resolution, const Float screenWindow[4],
                      Float fovDeg, Float lensRadius, Float focalDistance);
    Float generateRay(const CameraSample &s, Ray *ray) const override;
    Spectrum We(const Ray &ray, Point2 *pRaster) const override;
    void pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const override;
    bool sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const override;
    Normal3 lensNormal() const override { return viewDir_; }
    bool rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const override;
    Float lensRadius() const { return lensRadius_; }
    // Raster position of a camera-space direction from the lens centre (for tests).
    const Transform &rasterFromCamera() const { return rasterFromCamera_; }

  private:
    Transform worldFromCamera_, cameraFromWorld_;
    Transform cameraFromRaster_, rasterFromCamera_;
    Float lensRadius_, focalDistance_;
    Float imagePlaneArea_;  // at z = 1
    Vec3 viewDir_;
};

// Creates the camera from the Camera directive (perspective, orthographic,
// environment, realistic). `resolution` is the film's full resolution.
// `scene` (optional) resolves the realistic camera's lens file and gives the
// Film's "diagonal".
std::unique_ptr<Camera> CreateCamera(const CameraDesc &desc, Point2i resolution, const SceneDesc *scene = nullptr);

// pbrt-v3's screen window: from "frameaspectratio" (default the film's) or
// "screenwindow" [x0 x1 y0 y1]; a located error when malformed.
void ReadScreenWindow(const ParamSet &ps, const FileLoc &loc, Point2i resolution, Float sw[4]);
// Refuses a camera placed beyond the range the ray tracer handles.
void CheckCameraPlacement(const CameraDesc &desc);
std::unique_ptr<Camera> CreateOrthographicCamera(const CameraDesc &desc, Point2i resolution);
std::unique_ptr<Camera> CreateEnvironmentCamera(const CameraDesc &desc, Point2i resolution);
std::unique_ptr<Camera> CreateRealisticCamera(const CameraDesc &desc, Point2i resolution, const SceneDesc *scene);

}  // namespace gradus
