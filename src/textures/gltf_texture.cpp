// "gltfimage": a texture reading an in-memory image (SceneDesc::images) with
// glTF 2.0 sampler semantics: (u, v) = (0, 0) at the top-left texel corner,
// texel centres at ((i + 0.5) / W, (j + 0.5) / H), wrap modes REPEAT,
// CLAMP_TO_EDGE and MIRRORED_REPEAT per axis, LINEAR or NEAREST magnification
// (glTF 2.0 specification, section 3.8 "Texture Data"), an affine uv transform
// (KHR_texture_transform: uv' = M (u, v, 1)), a factor per channel and, for
// baseColor/emissive, sRGB decoding of the colour channels (alpha stays linear).
#include <array>
#include <cmath>

#include "core/error.h"
#include "image/image.h"
#include "textures/gltf_texture.h"

namespace gradus {
namespace {

enum class Wrap { Repeat, Clamp, Mirror };

Wrap ParseWrapMode(const ParamSet &p, const char *name, const FileLoc &loc) {
    std::string w = p.getString(name, "repeat");
    if (w == "repeat") return Wrap::Repeat;
    if (w == "clamp") return Wrap::Clamp;
    if (w == "mirror") return Wrap::Mirror;
    throw Error(p.locOf(name, loc), "gltfimage: unknown " + std::string(name) + " \"" + w +
                                        "\" (known: repeat, clamp, mirror)");
}

int WrapIndex(int i, int n, Wrap w) {
    switch (w) {
        case Wrap::Clamp: return std::min(std::max(i, 0), n - 1);
        case Wrap::Repeat: return ((i % n) + n) % n;
        case Wrap::Mirror: {
            int p = ((i % (2 * n)) + 2 * n) % (2 * n);
            return p < n ? p : 2 * n - 1 - p;
        }
    }
    return 0;
}

// sRGB transfer function of all 65536 texel codes, computed once.
const std::array<float, 65536> &SrgbTable() {
    static const std::array<float, 65536> table = [] {
        std::array<float, 65536> t{};
        for (int i = 0; i < 65536; ++i) t[i] = SRGBToLinear(float(i / 65535.0));
        return t;
    }();
    return table;
}

class GltfImage {
  public:
    GltfImage(const TextureDesc &d, const SceneDesc &scene) {
        const ParamSet &p = d.params;
        int idx = p.getInt("image", -1);
        if (idx < 0 || idx >= int(scene.images.size()))
            throw Error(p.locOf("image", d.loc), "gltfimage: \"integer image\" " + std::to_string(idx) +
                                                     " is not one of the scene's " +
                                                     std::to_string(scene.images.size()) + " images");
        img_ = scene.images[idx];
        if (!img_ || img_->width <= 0 || img_->height <= 0 || img_->channels <= 0 ||
            img_->texels.size() != size_t(img_->width) * img_->height * img_->channels)
            throw Error(p.locOf("image", d.loc), "gltfimage: image " + std::to_string(idx) + " is empty or inconsistent");
        wrapU_ = ParseWrapMode(p, "wrapu", d.loc);
        wrapV_ = ParseWrapMode(p, "wrapv", d.loc);
        std::string f = p.getString("filter", "linear");
        if (f != "linear" && f != "nearest")
            throw Error(p.locOf("filter", d.loc), "gltfimage: unknown filter \"" + f + "\" (known: linear, nearest)");
        nearest_ = f == "nearest";
        srgb_ = p.getBool("srgb", false);
        std::vector<Float> fac = p.getFloats("factor");
        if (!fac.empty() && fac.size() != 4)
            throw Error(p.locOf("factor", d.loc), "gltfimage: \"float factor\" needs 4 values (r g b a)");
        for (size_t i = 0; i < fac.size(); ++i) factor_[i] = fac[i];
        std::vector<Float> m = p.getFloats("uvtransform");
        if (!m.empty() && m.size() != 6)
            throw Error(p.locOf("uvtransform", d.loc), "gltfimage: \"float uvtransform\" needs 6 values (2x3, row-major)");
        for (size_t i = 0; i < m.size(); ++i) {
            if (!std::isfinite(m[i])) throw Error(p.locOf("uvtransform", d.loc), "gltfimage: uvtransform is not finite");
            uv_[i] = m[i];
        }
    }

    // Channel c (0..3) at (s, t) in image texel space, linearised and scaled by its factor.
    // Missing channels read as glTF defines them: grey images replicate, alpha 1.
    std::array<Float, 4> lookup(const SurfaceInteraction &si) const {
        Float u = uv_[0] * si.uv.x + uv_[1] * si.uv.y + uv_[2];
        Float v = uv_[3] * si.uv.x + uv_[4] * si.uv.y + uv_[5];
        const int W = img_->width, H = img_->height;
        Float x = u * W - 0.5, y = v * H - 0.5;
        std::array<Float, 4> r{0, 0, 0, 0};
        if (!std::isfinite(x) || !std::isfinite(y)) return r;  // degenerate uv: black
        // Keep the integer parts representable before wrapping.
        x = std::fmod(x, Float(2 * W) * 1024), y = std::fmod(y, Float(2 * H) * 1024);
        if (nearest_) {
            texel(WrapIndex(int(std::floor(x + 0.5)), W, wrapU_), WrapIndex(int(std::floor(y + 0.5)), H, wrapV_), 1, &r);
        } else {
            int x0 = int(std::floor(x)), y0 = int(std::floor(y));
            Float fx = x - x0, fy = y - y0;
            int xa = WrapIndex(x0, W, wrapU_), xb = WrapIndex(x0 + 1, W, wrapU_);
            int ya = WrapIndex(y0, H, wrapV_), yb = WrapIndex(y0 + 1, H, wrapV_);
            texel(xa, ya, (1 - fx) * (1 - fy), &r);
            texel(xb, ya, fx * (1 - fy), &r);
            texel(xa, yb, (1 - fx) * fy, &r);
            texel(xb, yb, fx * fy, &r);
        }
        for (int c = 0; c < 4; ++c) r[c] *= factor_[c];
        return r;
    }

  private:
    void texel(int x, int y, Float w, std::array<Float, 4> *acc) const {
        const int nc = img_->channels;
        const uint16_t *t = &img_->texels[(size_t(y) * img_->width + x) * nc];
        const auto &lut = SrgbTable();
        auto colour = [&](uint16_t code) { return srgb_ ? Float(lut[code]) : Float(code / 65535.0); };
        Float rgba[4];
        if (nc >= 3) {
            rgba[0] = colour(t[0]), rgba[1] = colour(t[1]), rgba[2] = colour(t[2]);
            rgba[3] = nc == 4 ? t[3] / 65535.0 : 1;
        } else {  // grey or grey + alpha
            rgba[0] = rgba[1] = rgba[2] = colour(t[0]);
            rgba[3] = nc == 2 ? t[1] / 65535.0 : 1;
        }
        for (int c = 0; c < 4; ++c) (*acc)[c] += w * rgba[c];
    }
    std::shared_ptr<const EmbeddedImage> img_;
    Wrap wrapU_ = Wrap::Repeat, wrapV_ = Wrap::Repeat;
    bool nearest_ = false, srgb_ = false;
    Float factor_[4] = {1, 1, 1, 1};
    Float uv_[6] = {1, 0, 0, 0, 1, 0};
};

class GltfSpectrumTexture : public SpectrumTexture {
  public:
    explicit GltfSpectrumTexture(GltfImage img) : img_(std::move(img)) {}
    Spectrum evaluate(const SurfaceInteraction &si) const override {
        auto v = img_.lookup(si);
        return {v[0], v[1], v[2]};
    }

  private:
    GltfImage img_;
};

class GltfFloatTexture : public FloatTexture {
  public:
    GltfFloatTexture(GltfImage img, int channel, Float cutoff) : img_(std::move(img)), c_(channel), cutoff_(cutoff) {}
    Float evaluate(const SurfaceInteraction &si) const override {
        Float v = img_.lookup(si)[c_];
        // alphaMode MASK: fully opaque at or above the cutoff, else fully transparent.
        if (cutoff_ >= 0) return v >= cutoff_ ? 1 : 0;
        return v;
    }

  private:
    GltfImage img_;
    int c_;
    Float cutoff_;
};

}  // namespace

std::shared_ptr<SpectrumTexture> MakeGltfSpectrumTexture(const TextureDesc &d, const SceneDesc &scene) {
    std::string ch = d.params.getString("channel", "rgb");
    if (ch != "rgb")
        throw Error(d.params.locOf("channel", d.loc), "gltfimage: a spectrum texture reads channel \"rgb\", not \"" + ch + "\"");
    return std::make_shared<GltfSpectrumTexture>(GltfImage(d, scene));
}

std::shared_ptr<FloatTexture> MakeGltfFloatTexture(const TextureDesc &d, const SceneDesc &scene) {
    std::string ch = d.params.getString("channel", "r");
    int c = ch == "r" ? 0 : ch == "g" ? 1 : ch == "b" ? 2 : ch == "a" ? 3 : -1;
    if (c < 0) throw Error(d.params.locOf("channel", d.loc), "gltfimage: unknown channel \"" + ch + "\" (known: r, g, b, a)");
    Float cutoff = d.params.getFloat("cutoff", -1);
    if (!std::isfinite(cutoff)) throw Error(d.params.locOf("cutoff", d.loc), "gltfimage: cutoff is not finite");
    return std::make_shared<GltfFloatTexture>(GltfImage(d, scene), c, cutoff);
}

}  // namespace gradus
