// glTF 2.0 scenes (.gltf, .glb) read through tinygltf into the SceneDesc the
// scene builder consumes: the node hierarchy flattened to world transforms,
// triangle meshes (meshes used by several nodes as object instances), the
// metallic-roughness materials as "gltfpbr" with "gltfimage" textures,
// emissive primitives as diffuse area lights, KHR_lights_punctual lights and
// a perspective camera. Errors name the file and the line and column of the
// offending JSON value (for .glb: of its JSON chunk) and its JSON pointer.
#pragma once
#include <string>

#include "core/transform.h"
#include "parser/scene_desc.h"

namespace gradus {

struct GltfOptions {
    // Camera to render: a camera's or a camera node's name; "" = the first
    // camera in the scene's node order.
    std::string camera;
    // A uniform white environment for a file without punctual lights (off:
    // gradus --envmap none, or --envmap FILE, which brings its own).
    bool defaultEnvironment = true;
};

// True for names ending in .gltf or .glb (any case).
bool IsGltfFile(const std::string &filename);

// A whole scene from a glTF file: everything above, plus a default film
// (640x480, or 480 rows at the camera's aspect ratio) writing <stem>.exr; a
// default camera when the file has none and a uniform white environment when
// it has no punctual light (opts.defaultEnvironment), each said in SceneDesc::notes.
SceneDesc LoadGltfScene(const std::string &filename, const GltfOptions &opts);

// Adds a glTF asset to `desc` under worldFromAsset (the GltfAsset directive of
// pbrt scenes). With useCamera, the asset's camera (opts.camera) becomes the
// scene's camera; otherwise the asset's cameras are ignored. `loc` locates
// errors about the file itself (missing, unreadable).
void AddGltfAsset(const std::string &filename, const Transform &worldFromAsset, const GltfOptions &opts,
                  bool useCamera, const FileLoc &loc, SceneDesc *desc);

}  // namespace gradus
