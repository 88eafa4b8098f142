// Materials turn a surface hit into a BSDF (allocated in the per-thread arena).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/arena.h"
#include "materials/bsdf.h"
#include "parser/scene_desc.h"
#include "textures/texture.h"

namespace gradus {

class BSSRDF;  // materials/bssrdf.h

class Material {
  public:
    virtual ~Material() = default;
    // May perturb si.shading (bump mapping) before building the BSDF.
    virtual BSDF getBSDF(SurfaceInteraction &si, Arena &arena, TransportMode mode) const = 0;
    // Lowest roughness this material can produce anywhere (for scene features:
    // "has specular or near-specular surfaces"). 0 = perfectly specular.
    virtual Float minRoughness() const = 0;
    virtual bool hasTextures() const { return false; }
    // Subsurface scattering below the surface (pbrt-v3's "subsurface", "kdsubsurface"):
    // the BSSRDF at si (called with the si getBSDF returned with), allocated in the arena;
    // nullptr for materials without one.
    virtual const BSSRDF *getBSSRDF(const SurfaceInteraction &si, Arena &arena) const { return nullptr; }
    virtual bool hasSubsurface() const { return false; }
};

// Creates a material of pbrt-v3 type `desc.type` ("matte", ...). Reads its
// parameters (textures resolved through `textures`); unknown types and known
// but unsupported pbrt-v3 materials throw located errors. The caller runs
// desc.params.checkUnused() afterwards. `named` resolves "mix" components; `scene`
// (when given) resolves relative file names such as "fourier"'s bsdffile; `notes`
// (when given) receives located notes on parameters read but ignored (pbrt-v3's warnings).
std::shared_ptr<Material> CreateMaterial(const MaterialDesc &desc, const NamedTextures &textures,
                                         const std::map<std::string, std::shared_ptr<Material>> &named,
                                         const SceneDesc *scene = nullptr, std::vector<std::string> *notes = nullptr);

}  // namespace gradus
