#include "parser/spectrum_convert.h"

#include "core/provenance.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace gradus {

namespace {

// Piecewise Gaussian g(x; mu, s1, s2) of Wyman et al. 2013 (Eq. 1): s1 left of
// the mean, s2 right of it.
inline double PiecewiseGaussian(double x, double mu, double s1, double s2) {
    double t = (x - mu) / (x < mu ? s1 : s2);
    return std::exp(-0.5 * t * t);
}

constexpr double kLambdaMin = 360, kLambdaMax = 830;  // CIE tabulation range (nm)
constexpr int kSamples = 471;                        // 1 nm steps, as the CIE table

// Trapezoid-free Riemann sum at 1 nm spacing (matches pbrt-v3's sum over the
// 1 nm CIE table, and the normalisation divides it out anyway).
double YIntegral() {
    static const double v = [] {
        double s = 0;
        for (int i = 0; i < kSamples; ++i) s += CieY(kLambdaMin + i);
        return s;
    }();
    return v;
}

Spectrum IntegrateToRGB(const std::vector<std::pair<double, double>> &samples) {
    double X = 0, Y = 0, Z = 0;
    size_t j = 0;  // segment cursor, samples sorted by wavelength
    for (int i = 0; i < kSamples; ++i) {
        double l = kLambdaMin + i;
        double v;
        if (l <= samples.front().first) v = samples.front().second;
        else if (l >= samples.back().first) v = samples.back().second;
        else {
            while (j + 1 < samples.size() && samples[j + 1].first < l) ++j;
            const auto &a = samples[j], &b = samples[j + 1];
            double t = (b.first > a.first) ? (l - a.first) / (b.first - a.first) : 0;
            v = (1 - t) * a.second + t * b.second;
        }
        X += v * CieX(l);
        Y += v * CieY(l);
        Z += v * CieZ(l);
    }
    double norm = 1 / YIntegral();
    return XYZToLinearSRGB(X * norm, Y * norm, Z * norm);
}

Spectrum EqualEnergyRGB() {
    static const Spectrum e = IntegrateToRGB({{kLambdaMin, 1.0}, {kLambdaMax, 1.0}});
    return e;
}

}  // namespace

// Wyman, Sloan & Shirley 2013, multi-lobe fit (their Eq. 2).
double CieX(double l) {
    return 1.056 * PiecewiseGaussian(l, 599.8, 37.9, 31.0) + 0.362 * PiecewiseGaussian(l, 442.0, 16.0, 26.7) -
           0.065 * PiecewiseGaussian(l, 501.1, 20.4, 26.2);
}
double CieY(double l) {
    return 0.821 * PiecewiseGaussian(l, 568.8, 46.9, 40.5) + 0.286 * PiecewiseGaussian(l, 530.9, 16.3, 31.1);
}
double CieZ(double l) {
    return 1.217 * PiecewiseGaussian(l, 437.0, 11.8, 36.0) + 0.681 * PiecewiseGaussian(l, 459.0, 26.0, 13.8);
}

// IEC 61966-2-1 (sRGB) XYZ -> linear RGB matrix.
Spectrum XYZToLinearSRGB(double x, double y, double z) {
    return {3.240479 * x - 1.537150 * y - 0.498535 * z, -0.969256 * x + 1.875991 * y + 0.041556 * z,
            0.055648 * x - 0.204043 * y + 1.057311 * z};
}

Spectrum SampledToRGB(const std::vector<double> &lambda, const std::vector<double> &values,
                      SpectrumKind kind) {
    if (lambda.empty() || lambda.size() != values.size())
        throw Error("sampled spectrum needs matching, non-empty wavelength and value arrays");
    std::vector<std::pair<double, double>> s(lambda.size());
    for (size_t i = 0; i < lambda.size(); ++i) s[i] = {lambda[i], values[i]};
    std::stable_sort(s.begin(), s.end(), [](const auto &a, const auto &b) { return a.first < b.first; });
    Spectrum rgb = IntegrateToRGB(s);
    if (kind == SpectrumKind::Reflectance) rgb = rgb / EqualEnergyRGB();
    return rgb;
}

double Blackbody(double lambdaNm, double T) {
    if (T <= 0) return 0;
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double l = lambdaNm * 1e-9;
    return (2 * h * c * c) / (std::pow(l, 5) * (std::exp((h * c) / (l * kb * T)) - 1));
}

Spectrum BlackbodyToRGB(double T, double scale) {
    if (!(T > 0)) return Spectrum(0.0);
    double lambdaMaxNm = 2.8977721e-3 / T * 1e9;  // Wien's displacement law
    double peak = Blackbody(lambdaMaxNm, T);
    std::vector<std::pair<double, double>> s(kSamples);
    for (int i = 0; i < kSamples; ++i) {
        double l = kLambdaMin + i;
        s[i] = {l, Blackbody(l, T) / peak};
    }
    return IntegrateToRGB(s) * scale;
}

std::vector<double> ReadSpdFile(const std::string &filename) {
    std::string text;
    if (ReadFileBytes(filename, &text) == FileRead::CannotOpen) throw Error(filename + ": cannot open spectrum file");
    RecordInputFile(filename, text.data(), text.size());  // provenance: spectra are scene inputs
    std::vector<double> out;
    size_t i = 0, n = text.size();
    int line = 1;
    while (i < n) {
        char ch = text[i];
        if (ch == '\n') { ++line; ++i; continue; }
        if (std::isspace(static_cast<unsigned char>(ch))) { ++i; continue; }
        if (ch == '#') {
            while (i < n && text[i] != '\n') ++i;
            continue;
        }
        size_t j = i;
        while (j < n && !std::isspace(static_cast<unsigned char>(text[j])) && text[j] != '#') ++j;
        const char *b = text.data() + i, *e = text.data() + j;
        if (*b == '+') ++b;
        double v;
        auto r = std::from_chars(b, e, v);
        if (r.ec != std::errc() || r.ptr != e)
            throw Error(filename + ":" + std::to_string(line) + ": malformed number '" + text.substr(i, j - i) +
                        "' in spectrum file");
        out.push_back(v);
        i = j;
    }
    if (out.empty() || out.size() % 2 != 0)
        throw Error(filename + ": spectrum file must hold (wavelength value) pairs, found " +
                    std::to_string(out.size()) + " numbers");
    return out;
}

}  // namespace gradus
