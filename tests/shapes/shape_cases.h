// Analytic shape cases shared by the shape and light tests: each shape comes
// with an independent implicit description (F(p) = 0 in object space plus its
// parameter-domain test) used for brute-force answers.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/chi2_test.h"
#include "shapes/quadrics.h"
#include "shapes/sphere.h"

namespace gradus::test {

struct AnalyticCase {
    std::string name;
    std::function<std::shared_ptr<AnalyticShape>(const Transform &, bool)> make;
    std::function<Float(const Point3 &)> F;        // implicit surface, object space
    std::function<bool(const Point3 &)> inDomain;  // clipping by z/phi/radius
    std::function<Vec3(const Point3 &)> normal;    // pbrt-v3 object normal direction (unnormalised)
    Float area;                                    // closed form or independent quadrature
    // Object-space reference point from which no line of sight grazes the
    // surface (inside the shape or on its open side): pdfs there are bounded.
    Point3 inside = Point3(0.1, 0.2, 0.05);
};

inline Float TestPhi(Float x, Float y) {
    Float p = std::atan2(y, x);
    return p < 0 ? p + 2 * Pi : p;
}

// Area of the surface of revolution with squared radius q(z), z in [z0, z1],
// swept by phiMax (composite midpoint rule on phiMax * rho * sqrt(1 + rho'^2)).
template <typename Q>
Float RevolutionArea(Q q, Float z0, Float z1, Float phiMax, int n = 200000) {
    Float h = (z1 - z0) / n, sum = 0;
    for (int i = 0; i < n; ++i) {
        Float z = z0 + (i + 0.5) * h, e = 1e-6;
        Float rho = std::sqrt(q(z)), drho = (std::sqrt(q(z + e)) - std::sqrt(q(z - e))) / (2 * e);
        sum += rho * std::sqrt(1 + drho * drho);
    }
    return phiMax * sum * h;
}

inline std::vector<AnalyticCase> AnalyticCases() {
    std::vector<AnalyticCase> c;
    auto phiOk = [](Float phiMaxDeg) {
        return [phiMaxDeg](const Point3 &p) { return TestPhi(p.x, p.y) <= Radians(phiMaxDeg) + 1e-12; };
    };
    c.push_back({"sphere_full", [](const Transform &w, bool ro) { return std::make_shared<Sphere>(w, ro, 1.0, -1, 1, 360); },
                 [](const Point3 &p) { return p.lengthSquared() - 1; }, [](const Point3 &) { return true; },
                 [](const Point3 &p) { return p; }, 4 * Pi});
    c.push_back({"sphere_partial",
                 [](const Transform &w, bool ro) { return std::make_shared<Sphere>(w, ro, 1.2, -0.5, 0.9, 250); },
                 [](const Point3 &p) { return p.lengthSquared() - 1.44; },
                 [phi = phiOk(250)](const Point3 &p) { return p.z >= -0.5 && p.z <= 0.9 && phi(p); },
                 [](const Point3 &p) { return p; }, Radians(250) * 1.2 * 1.4});
    c.push_back({"disk", [](const Transform &w, bool ro) { return std::make_shared<Disk>(w, ro, 0.3, 1.0, 0.4, 300); },
                 [](const Point3 &p) { return p.z - 0.3; },
                 [phi = phiOk(300)](const Point3 &p) {
                     Float r2 = p.x * p.x + p.y * p.y;
                     return r2 <= 1 && r2 >= 0.16 && phi(p);
                 },
                 [](const Point3 &) { return Vec3(0, 0, 1); }, 0.5 * Radians(300) * (1 - 0.16)});
    c.push_back({"cylinder",
                 [](const Transform &w, bool ro) { return std::make_shared<Cylinder>(w, ro, 0.8, -0.6, 1.0, 200); },
                 [](const Point3 &p) { return p.x * p.x + p.y * p.y - 0.64; },
                 [phi = phiOk(200)](const Point3 &p) { return p.z >= -0.6 && p.z <= 1.0 && phi(p); },
                 [](const Point3 &p) { return Vec3(p.x, p.y, 0); }, 1.6 * 0.8 * Radians(200)});
    c.push_back({"cylinder_full",
                 [](const Transform &w, bool ro) { return std::make_shared<Cylinder>(w, ro, 1.0, -1, 1, 360); },
                 [](const Point3 &p) { return p.x * p.x + p.y * p.y - 1; },
                 [](const Point3 &p) { return p.z >= -1 && p.z <= 1; },
                 [](const Point3 &p) { return Vec3(p.x, p.y, 0); }, 4 * Pi});
    c.push_back({"cone", [](const Transform &w, bool ro) { return std::make_shared<Cone>(w, ro, 1.5, 0.9, 290); },
                 [](const Point3 &p) { return p.x * p.x + p.y * p.y - Sqr(0.9 / 1.5) * Sqr(1.5 - p.z); },
                 [phi = phiOk(290)](const Point3 &p) { return p.z >= 0 && p.z <= 1.5 && phi(p); },
                 [](const Point3 &p) { return Vec3(p.x, p.y, Sqr(0.9 / 1.5) * (1.5 - p.z)); },
                 0.5 * Radians(290) * 0.9 * std::sqrt(1.5 * 1.5 + 0.81)});
    {
        const Float r = 0.9, zmin = 0.2, zmax = 1.3, k = zmax / (r * r);
        c.push_back({"paraboloid",
                     [=](const Transform &w, bool ro) { return std::make_shared<Paraboloid>(w, ro, r, zmin, zmax, 320); },
                     [=](const Point3 &p) { return k * (p.x * p.x + p.y * p.y) - p.z; },
                     [=, phi = phiOk(320)](const Point3 &p) { return p.z >= zmin && p.z <= zmax && phi(p); },
                     [=](const Point3 &p) { return Vec3(2 * k * p.x, 2 * k * p.y, -1); },
                     RevolutionArea([=](Float z) { return z / k; }, zmin, zmax, Radians(320))});
    }
    {
        const Point3 p1(0.9, 0, -0.7), p2(0.1, 0.8, 0.8);
        const Vec3 d = p2 - p1;
        auto q = [=](Float z) {  // squared radius of the generating segment at height z
            Float s = (z - p1.z) / d.z;
            Point3 l = p1 + d * s;
            return l.x * l.x + l.y * l.y;
        };
        c.push_back(
            {"hyperboloid",
             [=](const Transform &w, bool ro) { return std::make_shared<Hyperboloid>(w, ro, p1, p2, 280); },
             [=](const Point3 &p) { return p.x * p.x + p.y * p.y - q(p.z); },
             [=](const Point3 &p) {
                 Float s = (p.z - p1.z) / d.z;
                 if (s < 0 || s > 1) return false;
                 Point3 l = p1 + d * s;
                 Float phi = TestPhi(l.x * p.x + l.y * p.y, l.x * p.y - l.y * p.x);
                 return phi <= Radians(280) + 1e-12;
             },
             [=](const Point3 &p) {
                 Float h = 1e-6;
                 Vec3 g(2 * p.x, 2 * p.y, -(q(p.z + h) - q(p.z - h)) / (2 * h));
                 return d.z > 0 ? g : -g;  // pbrt-v3: Cross(dpdu, dpdv) points away from the axis iff p2 is above p1
             },
             RevolutionArea(q, p1.z, p2.z, Radians(280))});
    }
    for (auto &k : c) {
        if (k.name == "disk") k.inside = Point3(0.1, 0.2, 0.8);
        if (k.name == "cone") k.inside = Point3(0.05, 0.1, 0.4);
        if (k.name == "paraboloid") k.inside = Point3(0.05, 0.1, 0.8);
        if (k.name == "hyperboloid") k.inside = Point3(0.02, 0.01, 0.14375);  // on the axis at the waist
    }
    return c;
}

// Chi-square test of sampled unit directions against a solid-angle pdf, like
// chi2::SphericalTest but robust to the edges of a shape's support:
//  - bins the pdf only partly covers are integrated on an 8x finer grid;
//  - a bin whose integral comes out 0 although samples fell in it is accepted
//    only if the pdf is positive at each of those samples (a sliver of the
//    support thinner than the grid), and then pooled;
//  - when no sample failed and the pdf integrates to 1 within the grid's
//    accuracy (1%), expectations are normalised (normalisation itself is
//    checked separately by integrating the pdf).
template <typename SampleFn, typename PdfFn>
chi2::Result DirectionalChi2(SampleFn sample, PdfFn pdf, const chi2::Options &o) {
    const int nc = o.xBins, np = o.yBins;
    auto binOf = [&](const Vec3 &w) {
        int ci = Clamp(int((w.z + 1) / 2 * nc), 0, nc - 1), pi = Clamp(int(TestPhi(w.x, w.y) * Inv2Pi * np), 0, np - 1);
        return size_t(ci) * np + pi;
    };
    std::vector<double> obs(size_t(nc) * np + 1, 0.0), exp(size_t(nc) * np + 1, 0.0);
    std::vector<Vec3> samples;
    RNG rng(o.seed);
    int64_t invalid = 0;
    for (int64_t i = 0; i < o.samples; ++i) {
        Vec3 w;
        if (!sample(rng, &w)) {
            ++invalid;
            continue;
        }
        obs[binOf(w)] += 1;
        samples.push_back(w);
    }
    obs.back() = double(invalid);
    double total = 0;
    for (int ci = 0; ci < nc; ++ci)
        for (int pi = 0; pi < np; ++pi) {
            double c0 = -1 + 2.0 * ci / nc, c1 = -1 + 2.0 * (ci + 1) / nc;
            double p0 = 2 * Pi * pi / np, p1 = 2 * Pi * (pi + 1) / np;
            bool zero = false, nonzero = false;
            auto f = [&](double c, double phi) {
                double v = pdf(SphericalDirection(SafeSqrt(1 - c * c), c, phi));
                (v > 0 ? nonzero : zero) = true;
                return v;
            };
            double e = chi2::IntegrateCell(f, c0, c1, p0, p1, o.subdivisions);
            if (zero && nonzero) e = chi2::IntegrateCell(f, c0, c1, p0, p1, 8 * o.subdivisions);  // support edge
            exp[size_t(ci) * np + pi] = e * o.samples;
            total += e;
        }
    for (const Vec3 &w : samples) {
        size_t b = binOf(w);
        if (exp[b] > 0) continue;
        if (!(pdf(w) > 0)) {
            chi2::Result r;
            std::ostringstream os;
            os << "sampled direction " << w << " has pdf 0";
            r.message = os.str();
            return r;
        }
        exp[b] = 1e-3;  // sliver of the support: pooled with the other small bins
    }
    if (invalid == 0 && std::abs(1 - total) < 0.01) {
        for (size_t i = 0; i + 1 < exp.size(); ++i) exp[i] /= total;
    } else {
        exp.back() = std::max(0.0, 1 - total) * o.samples;
    }
    chi2::Result r = chi2::TestCounts(obs, exp, o.alpha);
    r.invalid = invalid;
    r.message += ", invalid samples = " + std::to_string(invalid) + ", pdf integral = " + std::to_string(total);
    return r;
}

}  // namespace gradus::test
