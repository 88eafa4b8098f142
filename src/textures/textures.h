// The texture classes of Gradus (pbrt-v3 names and parameters) and their factories.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/transform.h"
#include "image/image.h"
#include "parser/scene_desc.h"
#include "textures/texture.h"

namespace gradus {

// Texture-space (s, t) of a hit: pbrt-v3 "uv", "spherical", "cylindrical", "planar".
class TextureMapping2D {
  public:
    enum Kind { UV, Spherical, Cylindrical, Planar };
    TextureMapping2D() = default;
    static TextureMapping2D MakeUV(Float su, Float sv, Float du, Float dv);
    // Reads "string mapping" and its parameters (uscale, vscale, udelta, vdelta, v1, v2).
    static TextureMapping2D FromParams(const ParamSet &p, const Transform &worldFromTexture, const FileLoc &loc);
    Point2 map(const SurfaceInteraction &si) const;

  private:
    Kind kind_ = UV;
    Float su_ = 1, sv_ = 1, du_ = 0, dv_ = 0;
    Vec3 vs_{1, 0, 0}, vt_{0, 1, 0};
    Transform textureFromWorld_;
};

// 3D texture space: the hit point transformed by the inverse of the texture's CTM.
class TextureMapping3D {
  public:
    explicit TextureMapping3D(const Transform &worldFromTexture = Transform())
        : textureFromWorld_(worldFromTexture.inverse()) {}
    Point3 map(const SurfaceInteraction &si) const { return textureFromWorld_.applyPoint(si.p); }

  private:
    Transform textureFromWorld_;
};

// Gradient noise (Perlin 2002, "Improving noise", with a permutation of our own),
// values in about [-1, 1], zero at integer lattice points.
Float Noise(Float x, Float y = 0.5, Float z = 0.5);
inline Float Noise(const Point3 &p) { return Noise(p.x, p.y, p.z); }
// Fractional Brownian motion: sum over octaves i of omega^i Noise(2^i p).
Float FBm(const Point3 &p, Float omega, int octaves);
// Turbulence: sum over octaves of omega^i |Noise(2^i p)|.
Float Turbulence(const Point3 &p, Float omega, int octaves);

// Wrap modes of image textures.
enum class WrapMode { Repeat, Black, Clamp };

// An RGB texel grid with bilinear lookup. Row 0 is the top of the file; t = 0
// is the bottom of the image (pbrt-v3 flips images on load).
class TexelGrid {
  public:
    TexelGrid() = default;
    TexelGrid(int w, int h, std::vector<Spectrum> texels) : w_(w), h_(h), texels_(std::move(texels)) {}
    int width() const { return w_; }
    int height() const { return h_; }
    Spectrum texel(int x, int y, WrapMode wrap) const;
    // Bilinear interpolation at (s, t) in [0,1]^2 (texel centres at half-integers).
    Spectrum bilerp(Point2 st, WrapMode wrap) const;

  private:
    int w_ = 0, h_ = 0;
    std::vector<Spectrum> texels_;
};

// Loads an image texture file (EXR, PFM, PNG, TGA, JPEG, ...). 8-bit files are
// sRGB-decoded to linear when `gamma` is true and taken as stored (value / 255)
// when false; float formats are always linear. Results are cached per (file, gamma).
std::shared_ptr<const TexelGrid> LoadTexelGrid(const std::string &filename, bool gamma, const FileLoc &loc);
// The texels of a loaded image's default RGB layer, as LoadTexelGrid makes them;
// `storedValues` re-encodes sRGB-decoded 8-bit values to what the file stores.
std::shared_ptr<const TexelGrid> MakeTexelGrid(const Image &img, bool storedValues);

// Factories for the Texture directive ("constant", "scale", "mix", "bilerp",
// "imagemap", "uv", "checkerboard", "dots", "fbm", "wrinkled", "windy", "marble").
std::shared_ptr<FloatTexture> MakeFloatTexture(const TextureDesc &desc, const SceneDesc &scene,
                                               const NamedTextures &textures);
std::shared_ptr<SpectrumTexture> MakeSpectrumTexture(const TextureDesc &desc, const SceneDesc &scene,
                                                     const NamedTextures &textures);

// Creates a texture of class desc.type ("constant", "imagemap", "checkerboard", ...).
// Adds it to `textures` under desc.name (float or spectrum by desc.valueType).
void CreateTexture(const TextureDesc &desc, const SceneDesc &scene, NamedTextures *textures);

// Texture-or-constant parameter lookup ("texture Kd" "name" or "rgb Kd" [...]).
std::shared_ptr<SpectrumTexture> GetSpectrumTexture(const ParamSet &params, const std::string &name,
                                                    const Spectrum &def, const NamedTextures &textures,
                                                    const FileLoc &loc);
std::shared_ptr<FloatTexture> GetFloatTexture(const ParamSet &params, const std::string &name, Float def,
                                              const NamedTextures &textures, const FileLoc &loc);
// Like GetFloatTexture but returns nullptr when the parameter is absent (e.g. "bumpmap").
std::shared_ptr<FloatTexture> GetFloatTextureOrNull(const ParamSet &params, const std::string &name,
                                                    const NamedTextures &textures, const FileLoc &loc);

}  // namespace gradus
