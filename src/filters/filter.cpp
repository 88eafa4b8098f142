#include "filters/filter.h"

#include <cmath>

#include "core/error.h"

namespace gradus {
namespace {

class BoxFilter : public Filter {
  public:
    using Filter::Filter;
    Float evaluate(Point2) const override { return 1; }
};

class TriangleFilter : public Filter {
  public:
    using Filter::Filter;
    Float evaluate(Point2 p) const override {
        return std::max<Float>(0, radius.x - std::abs(p.x)) * std::max<Float>(0, radius.y - std::abs(p.y));
    }
};

class GaussianFilter : public Filter {
  public:
    GaussianFilter(Vec2 r, Float alpha)
        : Filter(r), alpha_(alpha), expX_(std::exp(-alpha * r.x * r.x)), expY_(std::exp(-alpha * r.y * r.y)) {}
    Float evaluate(Point2 p) const override {
        return std::max<Float>(0, std::exp(-alpha_ * p.x * p.x) - expX_) *
               std::max<Float>(0, std::exp(-alpha_ * p.y * p.y) - expY_);
    }

  private:
    Float alpha_, expX_, expY_;
};

// Mitchell-Netravali cubic (B, C) over [-2, 2] scaled to the radius.
class MitchellFilter : public Filter {
  public:
    MitchellFilter(Vec2 r, Float b, Float c) : Filter(r), B_(b), C_(c) {}
    Float m1(Float x) const {
        x = std::abs(2 * x);
        if (x > 1)
            return ((-B_ - 6 * C_) * x * x * x + (6 * B_ + 30 * C_) * x * x + (-12 * B_ - 48 * C_) * x +
                    (8 * B_ + 24 * C_)) / 6;
        return ((12 - 9 * B_ - 6 * C_) * x * x * x + (-18 + 12 * B_ + 6 * C_) * x * x + (6 - 2 * B_)) / 6;
    }
    Float evaluate(Point2 p) const override { return m1(p.x / radius.x) * m1(p.y / radius.y); }

  private:
    Float B_, C_;
};

// Windowed sinc (Lanczos window with tau cycles).
class LanczosSincFilter : public Filter {
  public:
    LanczosSincFilter(Vec2 r, Float tau) : Filter(r), tau_(tau) {}
    static Float sinc(Float x) {
        x = std::abs(x);
        if (x < 1e-5) return 1 - Pi * Pi * x * x / 6;
        return std::sin(Pi * x) / (Pi * x);
    }
    Float windowed(Float x, Float r) const {
        x = std::abs(x);
        if (x > r) return 0;
        return sinc(x) * sinc(x / tau_);
    }
    Float evaluate(Point2 p) const override { return windowed(p.x, radius.x) * windowed(p.y, radius.y); }

  private:
    Float tau_;
};

}  // namespace

std::unique_ptr<Filter> CreateFilter(const EntityDesc &desc) {
    std::string type = desc.present ? desc.type : "box";
    const ParamSet &ps = desc.params;
    auto radius = [&](Float def) {
        Vec2 r(ps.getFloat("xwidth", def), ps.getFloat("ywidth", def));
        // Upper bound: the film samples every pixel within the radius of the image (a
        // width of 1e6 would allocate the whole plane; pbrt-v3's filters use <= 4).
        constexpr Float kMaxWidth = 64;
        for (const char *n : {"xwidth", "ywidth"}) {
            Float v = n[0] == 'x' ? r.x : r.y;
            if (!(v > 0 && v <= kMaxWidth))
                throw Error(ps.locOf(n, desc.loc), "PixelFilter \"" + type + "\": \"" + n + "\" must be in (0, 64] pixels");
        }
        return r;
    };
    std::unique_ptr<Filter> f;
    if (type == "box") {
        f = std::make_unique<BoxFilter>(radius(0.5));
    } else if (type == "triangle") {
        f = std::make_unique<TriangleFilter>(radius(2));
    } else if (type == "gaussian") {
        Vec2 r = radius(2);
        f = std::make_unique<GaussianFilter>(r, ps.getFloat("alpha", 2));
    } else if (type == "mitchell") {
        Vec2 r = radius(2);
        f = std::make_unique<MitchellFilter>(r, ps.getFloat("B", 1.0 / 3), ps.getFloat("C", 1.0 / 3));
    } else if (type == "sinc") {
        Vec2 r = radius(4);
        f = std::make_unique<LanczosSincFilter>(r, ps.getFloat("tau", 3));
    } else {
        throw Error(desc.loc, "unknown pixel filter \"" + type + "\" (valid: box, triangle, gaussian, mitchell, sinc)");
    }
    ps.checkUnused("PixelFilter \"" + type + "\"");
    return f;
}

}  // namespace gradus
