// Fresnel reflectance for dielectrics and conductors (unpolarized light).
#pragma once
#include <cmath>

#include "core/geometry.h"
#include "core/spectrum.h"

namespace gradus {

// Dielectric Fresnel reflectance. cosI is measured against the normal on the
// "outside" (+z) side; eta = eta_inside / eta_outside. cosI < 0 means the light
// arrives from inside. Total internal reflection returns 1.
inline Float FrDielectric(Float cosI, Float eta) {
    cosI = Clamp<Float>(cosI, -1, 1);
    if (cosI < 0) {
        eta = 1 / eta;
        cosI = -cosI;
    }
    Float sin2T = (1 - cosI * cosI) / (eta * eta);
    if (sin2T >= 1) return 1;
    Float cosT = std::sqrt(1 - sin2T);
    Float rPar = (eta * cosI - cosT) / (eta * cosI + cosT);
    Float rPerp = (cosI - eta * cosT) / (cosI + eta * cosT);
    return (rPar * rPar + rPerp * rPerp) / 2;
}

// Conductor Fresnel reflectance for complex relative index eta + i k (exact
// unpolarized form; see e.g. Born & Wolf, Principles of Optics, Sec. 14.2).
inline Float FrConductor1(Float cosI, Float eta, Float k) {
    cosI = Clamp<Float>(std::abs(cosI), 0, 1);
    Float cos2 = cosI * cosI, sin2 = 1 - cos2;
    Float t0 = eta * eta - k * k - sin2;
    Float a2b2 = std::sqrt(t0 * t0 + 4 * eta * eta * k * k);
    Float a = std::sqrt(std::max<Float>(0, (a2b2 + t0) / 2));
    Float rs = (a2b2 + cos2 - 2 * a * cosI) / (a2b2 + cos2 + 2 * a * cosI);
    Float t1 = cos2 * a2b2 + sin2 * sin2, t2 = 2 * a * cosI * sin2;
    Float rp = rs * (t1 - t2) / (t1 + t2);
    return (rs + rp) / 2;
}

// Fresnel term of a reflection lobe: none (always 1), dielectric or conductor.
struct Fresnel {
    enum Kind { None, Dielectric, Conductor } kind = None;
    Float eta = 1;            // dielectric: eta_inside / eta_outside
    Spectrum etaC{1}, kC{0};  // conductor: relative complex index per channel

    static Fresnel One() { return Fresnel(); }
    static Fresnel MakeDielectric(Float eta) {
        Fresnel f;
        f.kind = Dielectric;
        f.eta = eta;
        return f;
    }
    static Fresnel MakeConductor(const Spectrum &eta, const Spectrum &k) {
        Fresnel f;
        f.kind = Conductor;
        f.etaC = eta;
        f.kC = k;
        return f;
    }
    // cosI: cosine between the incident direction and the (micro)normal, signed as for FrDielectric.
    Spectrum evaluate(Float cosI) const {
        switch (kind) {
        case Dielectric: return Spectrum(FrDielectric(cosI, eta));
        case Conductor:
            return {FrConductor1(cosI, etaC.r, kC.r), FrConductor1(cosI, etaC.g, kC.g),
                    FrConductor1(cosI, etaC.b, kC.b)};
        default: return Spectrum(1);
        }
    }
};

}  // namespace gradus
