// The scene as described by a pbrt-v3 file after the graphics-state layer:
// every entity with its type, parameters, location and world transform.
// The parser produces it; the scene builder (src/render) turns it into
// Embree geometry, materials, lights, camera and film.
#pragma once
#include <map>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/transform.h"
#include "parser/paramset.h"

namespace gradus {

class Image;

struct EntityDesc {
    std::string type;  // e.g. "perspective", "matte", "trianglemesh"; for MakeNamedMaterial the "string type" value
    ParamSet params;
    FileLoc loc;       // location of the directive keyword
    bool present = false;  // false for Camera/Film/... never given (defaults apply)
};

struct CameraDesc : EntityDesc {
    Transform cameraFromWorld;   // CTM at the Camera directive (pbrt-v3: world->camera)
    std::string mediumName;      // the camera's medium: the outside medium current at WorldEnd (pbrt-v3)
};

struct TextureDesc : EntityDesc {
    std::string name;
    std::string valueType;       // "float" or "spectrum" ("color" accepted as spectrum)
    Transform worldFromTexture;
};

struct MaterialDesc : EntityDesc {
    std::string name;            // "" for anonymous Material directives
};

struct LightDesc : EntityDesc {
    Transform worldFromLight;
    std::string outsideMedium;
    // An "infinite" light's map already read (gradus --envmap): R, G, B, used
    // instead of a "mapname" file.
    std::shared_ptr<const Image> map;
};

struct ShapeDesc : EntityDesc {
    Transform worldFromObject;   // for shapes inside ObjectBegin: instance-from-object
    bool reverseOrientation = false;
    int material = -1;           // index into SceneDesc::materials, -1 = default matte
    int areaLight = -1;          // index into SceneDesc::areaLights, -1 = none
    std::string insideMedium, outsideMedium;
};

struct InstanceDesc {
    std::string name;
    FileLoc loc;
    std::vector<ShapeDesc> shapes;
};

struct InstanceUseDesc {
    std::string name;
    Transform worldFromInstance;
    FileLoc loc;
};

struct MediumDesc : EntityDesc {
    std::string name;
    Transform worldFromMedium;
};

// A decoded image held in memory (glTF images): texels row by row from the
// top row, `channels` values each, as stored (not linearised), in 1/65535
// units (8-bit values are scaled by 257). "gltfimage" textures read it.
struct EmbeddedImage {
    std::string name;
    int width = 0, height = 0, channels = 0;
    std::vector<uint16_t> texels;
};

struct SceneDesc {
    CameraDesc camera;
    EntityDesc film, sampler, filter, integrator, accelerator;
    std::vector<MaterialDesc> materials;           // named and anonymous, referenced by index
    std::map<std::string, int> namedMaterials;     // name -> index into materials
    std::vector<TextureDesc> textures;             // in file order (later may reference earlier)
    std::vector<ShapeDesc> shapes;                 // world shapes
    std::vector<LightDesc> lights;
    std::vector<EntityDesc> areaLights;            // AreaLightSource entries referenced by shapes
    std::map<std::string, InstanceDesc> instances;
    std::vector<InstanceUseDesc> instanceUses;
    std::vector<MediumDesc> media;
    std::vector<std::shared_ptr<const EmbeddedImage>> images;  // "integer image" of gltfimage textures
    // Messages for the user from loading (e.g. a glTF file's defaults and ignored features).
    std::vector<std::string> notes;
    // TransformTimes and the end transforms are parsed; an entity whose start
    // and end transforms differ (motion blur) is refused by the scene builder
    // at motionLoc. Media are refused there too.
    Float transformStartTime = 0, transformEndTime = 1;
    bool motionBlur = false;
    FileLoc motionLoc;
    // Directory of the top-level scene file: pbrt-v3 resolves plymesh and
    // imagemap filenames against it.
    std::string sceneDirectory;
    // Resolves a relative filename against sceneDirectory.
    std::string resolve(const std::string &filename) const;
};

// Parses a pbrt-v3 scene file (Include resolved relative to the including file).
// Throws gradus::Error ("file:line:col: message") on any syntax or semantic error.
SceneDesc ParseFile(const std::string &filename);
// Parses text; `name` is the file name used in error messages and `directory`
// the base for relative paths.
SceneDesc ParseString(const std::string &text, const std::string &name = "<string>",
                      const std::string &directory = ".");

}  // namespace gradus
