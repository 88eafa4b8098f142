// "gltfimage" textures: in-memory glTF images with glTF sampler semantics.
// Parameters: "integer image" (index into SceneDesc::images), "string channel"
// (spectrum: "rgb"; float: "r", "g", "b" or "a"), "float factor" [r g b a],
// "bool srgb", "string wrapu"/"wrapv" (repeat, clamp, mirror), "string filter"
// (linear, nearest), "float uvtransform" [2x3 row-major], "float cutoff"
// (float textures: 1 at or above it, else 0; alphaMode MASK).
#pragma once
#include <memory>

#include "parser/scene_desc.h"
#include "textures/texture.h"

namespace gradus {

std::shared_ptr<SpectrumTexture> MakeGltfSpectrumTexture(const TextureDesc &d, const SceneDesc &scene);
std::shared_ptr<FloatTexture> MakeGltfFloatTexture(const TextureDesc &d, const SceneDesc &scene);

}  // namespace gradus
