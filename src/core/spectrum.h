// RGB radiometric quantity (Gradus renders in linear sRGB primaries, as pbrt-v3's
// default RGBSpectrum build does).
#pragma once
#include <cmath>

namespace gradus {

struct Spectrum {
    double r = 0, g = 0, b = 0;
    Spectrum() = default;
    constexpr explicit Spectrum(double v) : r(v), g(v), b(v) {}
    constexpr Spectrum(double r_, double g_, double b_) : r(r_), g(g_), b(b_) {}
    double operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    double &operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
    Spectrum operator+(const Spectrum &o) const { return {r + o.r, g + o.g, b + o.b}; }
    Spectrum operator-(const Spectrum &o) const { return {r - o.r, g - o.g, b - o.b}; }
    Spectrum operator*(const Spectrum &o) const { return {r * o.r, g * o.g, b * o.b}; }
    Spectrum operator/(const Spectrum &o) const {
        return {o.r != 0 ? r / o.r : 0, o.g != 0 ? g / o.g : 0, o.b != 0 ? b / o.b : 0};
    }
    Spectrum operator*(double s) const { return {r * s, g * s, b * s}; }
    Spectrum operator/(double s) const { double i = 1 / s; return {r * i, g * i, b * i}; }
    Spectrum &operator+=(const Spectrum &o) { r += o.r; g += o.g; b += o.b; return *this; }
    Spectrum &operator*=(const Spectrum &o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    Spectrum &operator*=(double s) { r *= s; g *= s; b *= s; return *this; }
    bool operator==(const Spectrum &o) const { return r == o.r && g == o.g && b == o.b; }
    bool isBlack() const { return r == 0 && g == 0 && b == 0; }
    bool isFinite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
    double maxComponent() const { return std::fmax(r, std::fmax(g, b)); }
    double average() const { return (r + g + b) / 3; }
    // Luminance (Rec. 709 / sRGB primaries).
    double y() const { return 0.212671 * r + 0.715160 * g + 0.072169 * b; }
};
inline Spectrum operator*(double s, const Spectrum &c) { return c * s; }
inline Spectrum Sqrt(const Spectrum &c) { return {std::sqrt(c.r), std::sqrt(c.g), std::sqrt(c.b)}; }
inline Spectrum Exp(const Spectrum &c) { return {std::exp(c.r), std::exp(c.g), std::exp(c.b)}; }

}  // namespace gradus
