// Scaffolding the material tests share: outgoing directions, a chi-square test of a
// sampler against its pdf over the whole sphere, a quadrature of a BxDF's albedo, a flat
// hit point, and parsing one material description.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/interaction.h"
#include "materials/bsdf.h"
#include "parser/scene_desc.h"
#include "common/chi2_test.h"
#include "samplers/rng.h"

namespace gradus::mattest {

// Unpolarised Fresnel reflectance from index n1 into n2 at incidence cosine cosI,
// written out for tests that must not use the code under test (fresnel.h).
inline double FresnelFromIndices(double cosI, double n1, double n2) {
    const double sinT = n1 / n2 * std::sqrt(std::max(0.0, 1 - cosI * cosI));
    if (sinT >= 1) return 1;
    const double cosT = std::sqrt(1 - sinT * sinT);
    const double rs = (n1 * cosI - n2 * cosT) / (n1 * cosI + n2 * cosT);
    const double rp = (n2 * cosI - n1 * cosT) / (n2 * cosI + n1 * cosT);
    return (rs * rs + rp * rp) / 2;
}

// Outgoing directions: three elevations above, and one below the surface. (At more
// grazing angles the refracted lobes get peaks that the midpoint-rule integration of
// the expected counts cannot resolve at test-suite cost.)
inline std::vector<Vec3> Wos() {
    std::vector<Vec3> w;
    for (Float c : {0.95, 0.5, 0.2}) w.push_back(SphericalDirection(std::sqrt(1 - c * c), c, 0.7));
    w.push_back(SphericalDirection(std::sqrt(1 - 0.6 * 0.6), -0.6, 2.1));
    return w;
}

// The direction with cos(theta) = cosTheta and azimuth phi.
inline Vec3 Dir(double cosTheta, double phi) {
    return SphericalDirection(SafeSqrt(1 - cosTheta * cosTheta), cosTheta, phi);
}

// Chi-square test over directions binned per hemisphere in (s, phi) with
// |cos theta| = 1 - s^2: bins shrink towards the poles, where specular-like lobes
// concentrate, and the midpoint rule in (s, phi) resolves those peaks. Invalid samples
// form one more bin expecting N (1 - integral of the pdf). sample(rng, &w) draws a
// direction (false: no sample); pdf(w) is its density. The expected count of a bin
// starts from a subStart^2 midpoint grid, doubled until the count changes by less than a
// small fraction of its Poisson deviation or the grid reaches subMax.
template <typename SampleFn, typename PdfFn>
chi2::Result SphereChi2(SampleFn sample, PdfFn pdf, int64_t n, uint64_t seed, double alpha, int subStart = 16,
                        int subMax = 384) {
    const int ns = 12, np = 24;
    auto bin = [&](const Vec3 &w) {
        int h = w.z < 0;
        double sv = std::sqrt(std::max(0.0, 1 - std::abs(w.z)));
        int i = Clamp(int(sv * ns), 0, ns - 1), j = Clamp(int(SphericalPhi(w) * Inv2Pi * np), 0, np - 1);
        return (h * ns + i) * np + j;
    };
    std::vector<double> obs(2 * ns * np + 1, 0.0), exp(2 * ns * np + 1, 0.0);
    RNG rng(seed);
    for (int64_t k = 0; k < n; ++k) {
        Vec3 w;
        if (!sample(rng, &w)) obs.back() += 1;
        else obs[bin(w)] += 1;
    }
    auto integrate = [&](int h, int i, int j, int sub) {
        double sum = 0;
        for (int a = 0; a < sub; ++a)
            for (int b = 0; b < sub; ++b) {
                double sv = (i + (a + 0.5) / sub) / ns, phi = 2 * Pi * (j + (b + 0.5) / sub) / np;
                double ct = (1 - sv * sv) * (h ? -1 : 1);
                sum += 2 * sv * pdf(Dir(ct, phi));
            }
        return sum * (1.0 / (ns * sub)) * (2 * Pi / (np * sub));
    };
    double total = 0;
    for (int h = 0; h < 2; ++h)
        for (int i = 0; i < ns; ++i)
            for (int j = 0; j < np; ++j) {
                int sub = subStart;
                double prev = integrate(h, i, j, sub), e = prev;
                while (sub < subMax) {
                    sub *= 2;
                    e = integrate(h, i, j, sub);
                    double dCount = std::abs(e - prev) * n;
                    if (dCount < std::max(0.1, 0.01 * std::sqrt(e * n))) break;
                    prev = e;
                }
                exp[(h * ns + i) * np + j] = e * n;
                total += e;
            }
    // The integral is accurate to ~1e-5; a lost mass below that is not resolvable.
    exp.back() = std::max(1e-5, 1 - total) * n;
    auto r = chi2::TestCounts(obs, exp, alpha);
    r.message += ", invalid = " + std::to_string(int64_t(obs.back())) + ", pdf integral = " + std::to_string(total);
    return r;
}

// SphereChi2 of a BxDF's sample() against its pdf() for one wo (radiance mode).
inline chi2::Result BxDFChi2(const BxDF &b, const Vec3 &wo, int64_t n, uint64_t seed, double alpha,
                             int subStart = 16, int subMax = 384) {
    return SphereChi2(
        [&](RNG &rng, Vec3 *w) {
            BSDFSample s;
            Float uc = rng.uniform();
            Point2 u(rng.uniform(), rng.uniform());
            if (!b.sample(wo, uc, u, TransportMode::Radiance, &s)) return false;
            *w = s.wi;
            return true;
        },
        [&](const Vec3 &wi) { return b.pdf(wo, wi, TransportMode::Radiance); }, n, seed, alpha, subStart, subMax);
}

// Midpoint-rule integral of f |cos| (importance mode) over the sphere, on an ns x np
// grid in (s, phi) per hemisphere with |cos theta| = 1 - s^2.
inline Spectrum QuadratureAlbedo(const BxDF &b, const Vec3 &wo, int ns, int np) {
    Spectrum sum(0);
    for (int h = 0; h < 2; ++h)
        for (int i = 0; i < ns; ++i)
            for (int j = 0; j < np; ++j) {
                double sv = (i + 0.5) / ns, ct = (1 - sv * sv) * (h ? -1 : 1);
                sum += b.f(wo, Dir(ct, 2 * Pi * (j + 0.5) / np), TransportMode::Importance) * (2 * sv * std::abs(ct));
            }
    return sum * ((1.0 / ns) * (2 * Pi / np));
}

// A hit on the plane z = 0 at the origin, normal +z, uv = (0.5, 0.5), dpdu = x, dpdv = y.
inline SurfaceInteraction FlatHit() {
    SurfaceInteraction si;
    si.p = Point3(0, 0, 0);
    si.n = Normal3(0, 0, 1);
    si.uv = Point2(0.5, 0.5);
    si.dpdu = Vec3(1, 0, 0);
    si.dpdv = Vec3(0, 1, 0);
    si.shading.n = si.n;
    si.shading.dpdu = si.dpdu;
    si.shading.dpdv = si.dpdv;
    return si;
}

// Parses "WorldBegin <text> WorldEnd" and returns its first material description.
inline MaterialDesc ParseMaterial(const std::string &text) {
    SceneDesc s = ParseString("WorldBegin\n" + text + "\nWorldEnd\n", "test.pbrt");
    EXPECT_FALSE(s.materials.empty());
    return s.materials.at(0);
}

}  // namespace gradus::mattest
