#include "cameras/realistic.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include <tbb/parallel_for.h>

#include "core/error.h"

namespace gradus {

namespace {
// Van der Corput radical inverses in base B of i = 0, 1, 2, ... in turn (the
// points of the pupil search): the digits of i are counted up with carries and
// their reversal kept as an integer over B^D (i < B^D), so each step costs O(1)
// on average and every value is the exact digit reversal, rounded once.
template <int B, int D>
class RadicalInverseCounter {
  public:
    RadicalInverseCounter() {
        uint64_t p = 1;
        for (int k = D - 1; k >= 0; --k) place_[k] = p, p *= B;
        scale_ = double(p);
    }
    Float value() const { return Float(double(rev_) / scale_); }
    void next() {
        for (int k = 0; k < D; ++k) {
            if (digit_[k] < B - 1) {
                ++digit_[k], rev_ += place_[k];
                return;
            }
            digit_[k] = 0, rev_ -= uint64_t(B - 1) * place_[k];
        }
    }

  private:
    int digit_[D] = {};
    uint64_t place_[D];
    uint64_t rev_ = 0;
    double scale_;
};
}  // namespace

std::vector<LensElement> ReadLensFile(const std::string &path, const FileLoc &paramLoc) {
    std::ifstream in(path);
    if (!in) throw Error(paramLoc, "realistic camera: cannot open lens file \"" + path + "\"");
    auto file = std::make_shared<const std::string>(path);
    std::vector<LensElement> rows;
    std::string line;
    for (int lineNo = 1; std::getline(in, line); ++lineNo) {
        const size_t hash = line.find('#');
        if (hash != std::string::npos) line.erase(hash);
        std::vector<Float> v;
        FileLoc at{file, lineNo, 1};
        size_t pos = 0;
        while (true) {
            while (pos < line.size() && std::isspace((unsigned char)line[pos])) ++pos;
            if (pos >= line.size()) break;
            size_t end = pos;
            while (end < line.size() && !std::isspace((unsigned char)line[end])) ++end;
            const std::string tok = line.substr(pos, end - pos);
            char *stop = nullptr;
            const double x = std::strtod(tok.c_str(), &stop);
            if (v.empty()) at.column = int(pos) + 1;
            if (stop != tok.c_str() + tok.size() || !std::isfinite(x))
                throw Error(FileLoc{file, lineNo, int(pos) + 1}, "lens file: \"" + tok + "\" is not a finite number");
            v.push_back(x);
            pos = end;
        }
        if (v.empty()) continue;
        if (v.size() != 4)
            throw Error(at, "lens file: a row needs 4 numbers (curvature radius, thickness, eta, aperture diameter "
                            "in mm), this one has " + std::to_string(v.size()));
        if (v[1] < 0) throw Error(at, "lens file: negative thickness");
        if (v[2] < 0) throw Error(at, "lens file: negative index of refraction");
        if (!(v[3] > 0)) throw Error(at, "lens file: the aperture diameter must be > 0");
        rows.push_back(LensElement{v[0], v[1], v[2], v[3]});
    }
    if (rows.empty()) throw Error(paramLoc, "realistic camera: lens file \"" + path + "\" holds no element");
    return rows;
}

RealisticCamera::RealisticCamera(const Transform &worldFromCamera, Point2i res, std::vector<LensElement> lens,
                                 Float apertureDiameterMM, Float focusDistance, Float filmDiagonalMM,
                                 bool simpleWeighting, Float shutterTime, const FileLoc &loc, int pupilSamples)
    : worldFromCamera_(worldFromCamera), simpleWeighting_(simpleWeighting), shutterTime_(shutterTime) {
    fullResolution = res;
    viewDir_ = Normal3(Normalize(worldFromCamera_.applyVector(Vec3(0, 0, 1))));
    // Millimetres to metres; the stop takes the requested diameter unless it exceeds the file's.
    for (LensElement e : lens) {
        if (e.curvatureRadius == 0 && apertureDiameterMM <= e.apertureRadius) e.apertureRadius = apertureDiameterMM;
        elements_.push_back(LensElement{e.curvatureRadius * Float(1e-3), e.thickness * Float(1e-3), e.eta,
                                        e.apertureRadius * Float(0.5e-3)});
    }
    auto place = [&]() {
        z_.assign(elements_.size(), 0);
        Float z = 0;
        for (int i = int(elements_.size()) - 1; i >= 0; --i) z_[i] = (z += elements_[i].thickness);
    };
    place();
    filmDiagonal_ = filmDiagonalMM * Float(1e-3);
    // Physical film: the diagonal split by the image's aspect ratio (pbrt-v3 Film).
    const Float aspect = Float(res.y) / Float(res.x);
    filmX_ = std::sqrt(filmDiagonal_ * filmDiagonal_ / (1 + aspect * aspect));
    filmY_ = aspect * filmX_;

    // Thick-lens approximation from two paraxial rays parallel to the axis.
    const Float h = Float(1e-3) * filmDiagonal_;
    Ray out;
    const Ray fromScene(Point3(h, 0, frontZ() + 1), Vec3(0, 0, -1));
    if (!traceFromScene(fromScene, &out))
        throw Error(loc, "realistic camera: a paraxial ray from the scene does not pass the lens system");
    cardinalPoints(fromScene, out, &pz_[0], &fz_[0]);
    const Ray fromFilm(Point3(h, 0, -1), Vec3(0, 0, 1));
    if (!traceFromFilm(fromFilm, &out))
        throw Error(loc, "realistic camera: a paraxial ray from the film does not pass the lens system");
    cardinalPoints(fromFilm, out, &pz_[1], &fz_[1]);
    const Float f = focalLength();
    if (!(f > 0) || !std::isfinite(f))
        throw Error(loc, "realistic camera: the lens system does not converge light (focal length " +
                             std::to_string(f) + " m)");
    // Focus: move the film back by delta so that the plane focusDistance in
    // front of the moved film is imaged on it. With a, b the film- and
    // scene-side principal planes, 1/s_o + 1/s_i = 1/f for s_i = a + delta and
    // s_o = D - delta - b gives delta^2 - (B - A) delta - AB + f (A + B) = 0
    // with A = a, B = D - b (Hecht, Optics, Sec. 6.1); the smaller root is the
    // film near the focal plane.
    const Float A = pz_[0], B = focusDistance - pz_[1];
    const Float disc = (A + B) * (A + B - 4 * f);
    if (!(disc > 0) || !(A + B > 0))
        throw Error(loc, "realistic camera: \"focusdistance\" " + std::to_string(focusDistance) +
                             " m is too short for this lens (focal length " + std::to_string(f) +
                             " m; object and image need at least 4 f between them)");
    const Float delta = 0.5 * ((B - A) - std::sqrt(disc));
    elements_.back().thickness += delta;
    if (!(elements_.back().thickness > 0))
        throw Error(loc, "realistic camera: focusing at \"focusdistance\" puts the film inside the lens");
    place();

    // Exit-pupil bounds for 64 bands of film radius (as pbrt-v3), searched along +x;
    // each band is independent (the bounds do not depend on the thread count).
    const int nBands = 64;
    pupil_.resize(nBands);
    tbb::parallel_for(0, nBands, [&](int i) {
        pupil_[i] = boundExitPupil(Float(i) / nBands * filmDiagonal_ / 2, Float(i + 1) / nBands * filmDiagonal_ / 2,
                                   pupilSamples);
    });
}

Float RealisticCamera::frontZ() const { return z_.empty() ? 0 : z_.front(); }

void RealisticCamera::cardinalPoints(const Ray &in, const Ray &out, Float *pz, Float *fz) const {
    // Focal point: where the exiting ray crosses the axis; principal plane:
    // where it reaches the entering ray's height.
    const Float tf = -out.o.x / out.d.x, tp = (in.o.x - out.o.x) / out.d.x;
    *fz = out.o.z + tf * out.d.z;
    *pz = out.o.z + tp * out.d.z;
}

bool RealisticCamera::traceFromFilm(const Ray &r, Ray *out) const { return trace(r, true, out); }
bool RealisticCamera::traceFromScene(const Ray &r, Ray *out) const { return trace(r, false, out); }

bool RealisticCamera::trace(Ray ray, bool fromFilm, Ray *out) const {
    const int n = int(elements_.size());
    ray.d = Normalize(ray.d);
    auto etaOf = [&](int i) { return i < 0 || elements_[i].eta == 0 ? Float(1) : elements_[i].eta; };
    for (int k = 0; k < n; ++k) {
        const int i = fromFilm ? n - 1 - k : k;
        const LensElement &e = elements_[i];
        Float t;
        Vec3 nrm;
        if (e.curvatureRadius == 0) {
            if (ray.d.z == 0) return false;
            t = (z_[i] - ray.o.z) / ray.d.z;
            if (!(t > 0)) return false;
        } else {
            // Sphere of radius |R| centred on the axis at z_i - R; the interface is
            // the cap on the vertex's side of the centre ((p.z - c.z) R > 0).
            const Float R = e.curvatureRadius, cz = z_[i] - R;
            const Vec3 oc(ray.o.x, ray.o.y, ray.o.z - cz);
            const Float b = Dot(oc, ray.d), c = Dot(oc, oc) - R * R;
            const Float disc = b * b - c;
            if (disc < 0) return false;
            const Float sq = std::sqrt(disc);
            t = Infinity;
            for (Float tc : {-b - sq, -b + sq})
                if (tc > 0 && tc < t && (ray.o.z + tc * ray.d.z - cz) * R > 0) t = tc;
            if (!std::isfinite(t)) return false;
        }
        const Point3 p = ray(t);
        if (p.x * p.x + p.y * p.y > e.apertureRadius * e.apertureRadius) return false;
        ray.o = p;
        if (e.curvatureRadius == 0) continue;
        nrm = Normalize(Vec3(p.x, p.y, p.z - (z_[i] - e.curvatureRadius)));
        if (Dot(nrm, ray.d) > 0) nrm = -nrm;
        // Snell's law in vector form; nrm faces the incoming ray.
        const Float n1 = fromFilm ? etaOf(i) : etaOf(i - 1), n2 = fromFilm ? etaOf(i - 1) : etaOf(i);
        const Float eta = n1 / n2, cosI = -Dot(nrm, ray.d);
        const Float sin2T = eta * eta * std::max(Float(0), 1 - cosI * cosI);
        if (sin2T >= 1) return false;  // total internal reflection
        ray.d = Normalize(ray.d * eta + nrm * (eta * cosI - std::sqrt(1 - sin2T)));
        if (fromFilm ? !(ray.d.z > 0) : !(ray.d.z < 0)) return false;
    }
    *out = ray;
    return true;
}

RealisticCamera::Box RealisticCamera::searchPupil(Float r0, Float r1, int samples, const Box *window) const {
    // Sample i: the film point (i + 1/2) / samples along [r0, r1] on +x and the
    // rear-plane point of the 2D radical inverse (bases 2, 3) in the square
    // [-s, s]^2, s = 1.5 rear radius (pbrt-v3's BoundExitPupil). The result is
    // the bounding box of the points whose rays leave the front (a point inside
    // the box so far cannot change it and is not traced).
    const Float s = 1.5 * elements_.back().apertureRadius;
    Box b;
    Ray tmp;
    RadicalInverseCounter<2, 31> u0;  // samples < 2^31 <= 3^20
    RadicalInverseCounter<3, 20> u1;
    for (int i = 0; i < samples; ++i, u0.next(), u1.next()) {
        const Point3 pr(Lerp(u0.value(), -s, s), Lerp(u1.value(), -s, s), rearZ());
        if (b.inside(pr.x, pr.y)) continue;
        if (window && !window->inside(pr.x, pr.y)) continue;
        const Point3 pf(Lerp((i + 0.5) / samples, r0, r1), 0, 0);
        if (!traceFromFilm(Ray(pf, pr - pf), &tmp)) continue;
        b.x0 = std::min(b.x0, pr.x), b.y0 = std::min(b.y0, pr.y);
        b.x1 = std::max(b.x1, pr.x), b.y1 = std::max(b.y1, pr.y);
    }
    return b;
}

RealisticCamera::Box RealisticCamera::boundExitPupil(Float r0, Float r1, int samples) const {
    // pbrt-v3's bound: the box of the exiting sample points, expanded by twice the
    // square's diagonal over sqrt(samples); the whole square when none exits. Its
    // area normalises the simple weighting, so the samples and the expansion are
    // pbrt-v3's. Only the sample points within a window are traced: the box of a
    // coarse search (2^16 samples) expanded by 16 of its sample spacings on
    // every side (a pupil does not reach that far beyond the coarse samples).
    const Float s = 1.5 * elements_.back().apertureRadius;
    const int coarse = 1 << 16;
    Box window = samples > coarse ? searchPupil(r0, r1, coarse, nullptr) : Box{};
    const bool windowed = !window.empty();
    const Float m = 16 * 2 * s / std::sqrt(Float(coarse));
    window.x0 -= m, window.y0 -= m, window.x1 += m, window.y1 += m;
    Box b = searchPupil(r0, r1, samples, windowed ? &window : nullptr);
    if (b.empty()) return Box{-s, -s, s, s};
    const Float grow = 2 * std::sqrt(2 * (2 * s) * (2 * s)) / std::sqrt(Float(samples));
    b.x0 -= grow, b.y0 -= grow, b.x1 += grow, b.y1 += grow;
    return b;
}

Point2 RealisticCamera::filmPoint(Point2 p) const {
    const Float x = Lerp(p.x / fullResolution.x, -filmX_ / 2, filmX_ / 2);
    const Float y = Lerp(p.y / fullResolution.y, -filmY_ / 2, filmY_ / 2);
    return Point2(-x, y);  // the lens inverts the image: x mirrored, raster y already points down
}

Float RealisticCamera::generateRay(const CameraSample &s, Ray *ray) const {
    // A valid ray even when the sample is blocked (weight 0).
    *ray = Ray(worldFromCamera_.applyPoint(Point3(0, 0, 0)), Vec3(viewDir_));
    const Point2 pf = filmPoint(s.pFilm);
    const Float radius = std::sqrt(pf.x * pf.x + pf.y * pf.y);
    const int band = std::min(int(pupil_.size()) - 1, int(radius / (filmDiagonal_ / 2) * pupil_.size()));
    const Box &b = pupil_[band];
    // The band's bounds (found along +x) rotated to the film point's azimuth.
    const Float lx = Lerp(s.pLens.x, b.x0, b.x1), ly = Lerp(s.pLens.y, b.y0, b.y1);
    const Float sinP = radius > 0 ? pf.y / radius : 0, cosP = radius > 0 ? pf.x / radius : 1;
    const Point3 pRear(cosP * lx - sinP * ly, sinP * lx + cosP * ly, rearZ());
    const Point3 pFilm(pf.x, pf.y, 0);
    const Ray rFilm(pFilm, pRear - pFilm);
    Ray out;
    if (!traceFromFilm(rFilm, &out)) return 0;
    *ray = Ray(worldFromCamera_.applyPoint(out.o), Normalize(worldFromCamera_.applyVector(out.d)));
    // Irradiance at the film point: cos^4 theta times the sampled pupil area over
    // the squared distance (PBR3 Sec. 6.4.7); simple weighting divides by the
    // on-axis value instead, so the centre of the image reads radiance.
    const Float cosT = Normalize(rFilm.d).z, cos4 = cosT * cosT * cosT * cosT;
    if (simpleWeighting_) return cos4 * b.area() / pupil_[0].area();
    return shutterTime_ * cos4 * b.area() / (rearZ() * rearZ());
}

std::unique_ptr<Camera> CreateRealisticCamera(const CameraDesc &desc, Point2i res, const SceneDesc *scene) {
    const ParamSet &ps = desc.params;
    const Float shutterOpen = ps.getFloat("shutteropen", 0), shutterClose = ps.getFloat("shutterclose", 1);
    const std::string lensFile = ps.getString("lensfile", "");
    const Float apertureDiameter = ps.getFloat("aperturediameter", 1);
    const Float focusDistance = ps.getFloat("focusdistance", 10);
    const bool simple = ps.getBool("simpleweighting", true);
    if (lensFile.empty()) throw Error(desc.loc, "Camera \"realistic\": missing \"string lensfile\"");
    if (!(apertureDiameter > 0) || !std::isfinite(apertureDiameter))
        throw Error(ps.locOf("aperturediameter", desc.loc), "\"aperturediameter\" must be > 0 and finite (mm)");
    if (!(focusDistance > 0 && focusDistance <= 1e15))
        throw Error(ps.locOf("focusdistance", desc.loc), "\"focusdistance\" must be in (0, 1e15]");
    if (!(shutterClose >= shutterOpen))
        throw Error(ps.locOf("shutterclose", desc.loc), "\"shutterclose\" must not precede \"shutteropen\"");
    Float diagonal = 35;
    FileLoc diagLoc = desc.loc;
    if (scene) {
        diagonal = scene->film.params.getFloat("diagonal", 35);
        diagLoc = scene->film.params.locOf("diagonal", scene->film.loc);
    }
    if (!(diagonal > 0) || !std::isfinite(diagonal))
        throw Error(diagLoc, "Film \"diagonal\" must be > 0 and finite (mm)");
    const std::string path = scene ? scene->resolve(lensFile) : lensFile;
    std::vector<LensElement> lens = ReadLensFile(path, ps.locOf("lensfile", desc.loc));
    CheckCameraPlacement(desc);
    ps.checkUnused("Camera \"realistic\"");
    return std::make_unique<RealisticCamera>(desc.cameraFromWorld.inverse(), res, std::move(lens), apertureDiameter,
                                             focusDistance, diagonal, simple, shutterClose - shutterOpen,
                                             ps.locOf("focusdistance", desc.loc));
}

}  // namespace gradus
