// Environment lighting from the command line (gradus --envmap, the Python
// module's envmap=): a lat-long map added to any scene as an infinite light
// with pbrt-v3's mapping, or the glTF default environment turned off.
#pragma once
#include <memory>
#include <string>

#include "image/image.h"
#include "parser/scene_desc.h"

namespace gradus {

struct EnvironmentOptions {
    // --envmap FILE (.exr, .hdr, .pfm), "none" (no default environment: glTF
    // scenes without punctual lights get none), or "" (not given).
    std::string map;
    double scale = 1;          // --envmap-scale: radiance multiplier (>= 0)
    double rotateDegrees = 0;  // --envmap-rotate: about the up axis (right-handed)
    std::shared_ptr<const Image> image;  // the map's R, G, B (LoadEnvironmentMap)

    bool given() const { return !map.empty(); }
    bool addsLight() const { return given() && map != "none"; }
    // "" when not given; else what the outputs record (metadata "environment",
    // the checkpoint identity): "none" or "\"FILE\" scale S rotate DEG".
    std::string describe() const;
    // As describe() without the file's name (its contents are in the scene hash).
    std::string identity() const;
};

// Checks the options and reads the map (R, G, B; finite, non-negative), so
// that a missing or bad map fails before the scene is loaded. Errors are
// located at "<command line --envmap>" and name the file.
void LoadEnvironmentMap(EnvironmentOptions *env);

// Adds the map's infinite light to a loaded scene and records the map among
// the input files (provenance). The map's pole (top row) is the scene's up
// axis: +z for pbrt scenes (pbrt-v3's "infinite" light under the identity),
// +y for glTF scenes (glTF's up; as pbrt's Rotate -90 1 0 0 gives); u runs
// with the angle phi about that axis, rotateDegrees added.
void AddEnvironmentLight(const EnvironmentOptions &env, bool gltfScene, SceneDesc *desc);

}  // namespace gradus
