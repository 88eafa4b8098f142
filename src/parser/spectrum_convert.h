// Conversion of sampled and blackbody spectra to linear sRGB for the RGB
// renderer. The CIE 1931 colour matching functions are evaluated with the
// multi-lobe Gaussian fit of Wyman, Sloan & Shirley, "Simple Analytic
// Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2), 2013.
#pragma once
#include <string>
#include <vector>

#include "core/spectrum.h"

namespace gradus {

// CIE 1931 2-degree matching functions (analytic fit, Wyman et al. 2013, Eq. 2
// with the multi-lobe parameters of their Table 1). lambda in nm.
double CieX(double lambda);
double CieY(double lambda);
double CieZ(double lambda);

// How a sampled spectrum is turned into RGB.
enum class SpectrumKind {
    // Emission: XYZ = integral(S * cmf) / integral(ybar) (pbrt-v3's
    // RGBSpectrum::FromSampled normalisation), then XYZ -> linear sRGB.
    // An equal-energy spectrum of 1 has Y = 1 but is slightly pink in sRGB.
    Illuminant,
    // Reflectance: as Illuminant, then divided channel-wise by the RGB of the
    // equal-energy spectrum, so a constant reflectance c maps to grey (c, c, c).
    Reflectance
};

// Linear sRGB from XYZ (sRGB primaries, D65 white).
Spectrum XYZToLinearSRGB(double x, double y, double z);
// Piecewise-linear spectrum through (lambda[i], value[i]) (sorted internally,
// clamped outside the sampled range), integrated against the CMFs over
// 360..830 nm. Throws gradus::Error if the arrays are empty or differ in size.
Spectrum SampledToRGB(const std::vector<double> &lambda, const std::vector<double> &values,
                      SpectrumKind kind);
// Planck's law spectral radiance at lambda (nm) and temperature T (K).
double Blackbody(double lambdaNm, double T);
// pbrt-v3 "blackbody" [T scale]: Planck spectrum normalised to a peak of 1
// (at Wien's wavelength), converted as an illuminant, times scale.
Spectrum BlackbodyToRGB(double T, double scale);

// Reads a pbrt .spd file: whitespace-separated (lambda value) pairs, '#' comments.
// Throws gradus::Error naming the file if unreadable or malformed.
std::vector<double> ReadSpdFile(const std::string &filename);

}  // namespace gradus
