// Textures evaluated at a surface point.
#pragma once
#include <map>
#include <memory>
#include <string>

#include "core/spectrum.h"
#include "core/interaction.h"

namespace gradus {

template <typename T>
class Texture {
  public:
    virtual ~Texture() = default;
    virtual T evaluate(const SurfaceInteraction &si) const = 0;
    // True when evaluate() returns the same value everywhere (lets materials skip work).
    virtual bool isConstant() const { return false; }
};
using FloatTexture = Texture<Float>;
using SpectrumTexture = Texture<Spectrum>;

template <typename T>
class ConstantTexture : public Texture<T> {
  public:
    explicit ConstantTexture(const T &v) : value_(v) {}
    T evaluate(const SurfaceInteraction &) const override { return value_; }
    bool isConstant() const override { return true; }
    const T &value() const { return value_; }

  private:
    T value_;
};

// Named textures declared so far by Texture directives.
struct NamedTextures {
    std::map<std::string, std::shared_ptr<FloatTexture>> floats;
    std::map<std::string, std::shared_ptr<SpectrumTexture>> spectra;
};

}  // namespace gradus
