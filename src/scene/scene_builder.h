// The scene layer's builder: turns a parsed SceneDesc into a Scene (media,
// textures, materials, shapes and instances, lights, the camera), consuming
// every parameter (unused ones are located errors).
#pragma once
#include <memory>

#include "parser/scene_desc.h"
#include "scene/scene.h"

namespace gradus {

// Builds the scene (geometry, materials, lights, camera) for the given film resolution.
std::unique_ptr<Scene> BuildScene(const SceneDesc &desc, Point2i resolution);

}  // namespace gradus
