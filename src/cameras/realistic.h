// pbrt-v3's realistic camera: rays traced from the film through a system of
// spherical lens elements and an aperture stop described by a lens file.
//
// Lens file (pbrt-v3 format): one element interface per row, front (scene
// side) first: curvature radius, thickness (axial distance to the next
// interface towards the film), index of refraction of the medium behind it
// (towards the film; 0 means air) and aperture diameter, all in millimetres;
// a curvature radius of 0 is the aperture stop. '#' starts a comment. Gradus
// asks for exactly four numbers per row (pbrt-v3 only for a multiple of four in
// the whole file) so that a malformed row is reported at its line.
//
// Camera space: the film lies on z = 0 and the lens in front of it along +z,
// scene units are metres. Positive radii have their centre of curvature on the
// film side.
#pragma once
#include <string>
#include <vector>

#include "cameras/camera.h"

namespace gradus {

struct LensElement {
    Float curvatureRadius;  // m; 0: aperture stop
    Float thickness;        // m, to the next interface towards the film
    Float eta;              // of the medium behind (film side); 0 read as 1
    Float apertureRadius;   // m
};

// Rows of a lens file in millimetres as written; located errors (the lens
// file's line and column) for a row that is not four numbers, for non-finite
// or negative thicknesses/diameters, and for an empty file.
std::vector<LensElement> ReadLensFile(const std::string &path, const FileLoc &loc);

class RealisticCamera : public Camera {
  public:
    // `lensMM`: rows in millimetres (as in the file). The aperture stop's
    // diameter becomes apertureDiameterMM unless that exceeds the file's
    // (pbrt-v3 keeps the file's then); the film is moved so that the plane
    // focusDistance in front of it is in focus (thick-lens approximation).
    // Throws Error (at loc) when the lens cannot focus there. pupilSamples: the
    // exit-pupil search's points per band (pbrt-v3: 2^20; the simple weighting
    // divides by the centre band's bound, whose expansion depends on it).
    RealisticCamera(const Transform &worldFromCamera, Point2i resolution, std::vector<LensElement> lensMM,
                    Float apertureDiameterMM, Float focusDistance, Float filmDiagonalMM, bool simpleWeighting,
                    Float shutterTime, const FileLoc &loc, int pupilSamples = 1 << 20);
    Float generateRay(const CameraSample &s, Ray *ray) const override;
    // No importance function (hasImportance false): bidirectional integrators refuse it.
    Spectrum We(const Ray &ray, Point2 *pRaster) const override { return Spectrum(0); }
    void pdfWe(const Ray &ray, Float *pdfPos, Float *pdfDir) const override { *pdfPos = *pdfDir = 0; }
    bool sampleWi(const Interaction &ref, Point2 u, CameraWiSample *s) const override { return false; }
    Normal3 lensNormal() const override { return viewDir_; }
    bool rayThrough(const Point3 &lensPoint, Point2 pFilm, Ray *ray) const override { return false; }
    bool hasImportance() const override { return false; }

    // Camera-space traces through every interface; false when a ray is blocked
    // by an aperture, misses an element or is totally reflected. fromFilm
    // starts at the film side heading +z, fromScene in front heading -z.
    bool traceFromFilm(const Ray &r, Ray *out) const;
    bool traceFromScene(const Ray &r, Ray *out) const;
    // Thick-lens approximation (computed before focusing): principal planes
    // and focal points on the film side [0] and the scene side [1], as
    // camera-space z; the effective focal length.
    Float principalZ(int side) const { return pz_[side]; }
    Float focalZ(int side) const { return fz_[side]; }
    Float focalLength() const { return pz_[0] - fz_[0]; }
    Float rearZ() const { return elements_.back().thickness; }
    Float frontZ() const;
    // Film point (camera space, metres) of raster position p.
    Point2 filmPoint(Point2 pRaster) const;
    const std::vector<LensElement> &elements() const { return elements_; }

  private:
    struct Box {
        Float x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
        bool inside(Float x, Float y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
        Float area() const { return x1 > x0 && y1 > y0 ? (x1 - x0) * (y1 - y0) : 0; }
        bool empty() const { return !(x1 >= x0 && y1 >= y0); }
    };
    bool trace(Ray r, bool fromFilm, Ray *out) const;
    void cardinalPoints(const Ray &in, const Ray &out, Float *pz, Float *fz) const;
    Box searchPupil(Float r0, Float r1, int samples, const Box *window) const;
    Box boundExitPupil(Float r0, Float r1, int samples) const;

    Transform worldFromCamera_;
    std::vector<LensElement> elements_;
    std::vector<Float> z_;  // camera-space z of each interface's vertex
    Float filmX_, filmY_, filmDiagonal_;
    bool simpleWeighting_;
    Float shutterTime_;
    Float pz_[2], fz_[2];
    std::vector<Box> pupil_;  // exit-pupil bounds for film radii in 64 bands (along +x)
    Normal3 viewDir_;
};

}  // namespace gradus
