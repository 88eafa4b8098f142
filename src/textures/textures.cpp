// Texture parameter lookup and the Texture directive factory.
#include "textures/textures.h"

namespace gradus {

std::shared_ptr<SpectrumTexture> GetSpectrumTexture(const ParamSet &params, const std::string &name,
                                                    const Spectrum &def, const NamedTextures &textures,
                                                    const FileLoc &loc) {
    const Param *p = params.find(name);
    if (!p) return std::make_shared<ConstantTexture<Spectrum>>(def);
    if (p->type == "texture") {
        std::string tn = params.getTexture(name);
        auto it = textures.spectra.find(tn);
        if (it != textures.spectra.end()) return it->second;
        if (textures.floats.count(tn))
            throw Error(p->loc, "texture \"" + tn + "\" is a float texture; \"" + name + "\" needs a spectrum texture");
        throw Error(p->loc, "spectrum texture \"" + tn + "\" is not defined");
    }
    return std::make_shared<ConstantTexture<Spectrum>>(params.getSpectrum(name, def));
}

std::shared_ptr<FloatTexture> GetFloatTextureOrNull(const ParamSet &params, const std::string &name,
                                                    const NamedTextures &textures, const FileLoc &loc) {
    const Param *p = params.find(name);
    if (!p) return nullptr;
    if (p->type == "texture") {
        std::string tn = params.getTexture(name);
        auto it = textures.floats.find(tn);
        if (it != textures.floats.end()) return it->second;
        if (textures.spectra.count(tn))
            throw Error(p->loc, "texture \"" + tn + "\" is a spectrum texture; \"" + name + "\" needs a float texture");
        throw Error(p->loc, "float texture \"" + tn + "\" is not defined");
    }
    return std::make_shared<ConstantTexture<Float>>(params.getFloat(name, 0));
}

std::shared_ptr<FloatTexture> GetFloatTexture(const ParamSet &params, const std::string &name, Float def,
                                              const NamedTextures &textures, const FileLoc &loc) {
    auto t = GetFloatTextureOrNull(params, name, textures, loc);
    return t ? t : std::make_shared<ConstantTexture<Float>>(def);
}

void CreateTexture(const TextureDesc &desc, const SceneDesc &scene, NamedTextures *textures) {
    bool isFloat;
    if (desc.valueType == "float")
        isFloat = true;
    else if (desc.valueType == "spectrum" || desc.valueType == "color" || desc.valueType == "rgb")
        isFloat = false;
    else
        throw Error(desc.loc, "texture value type \"" + desc.valueType + "\" must be \"float\" or \"spectrum\"");
    if (isFloat)
        textures->floats[desc.name] = MakeFloatTexture(desc, scene, *textures);
    else
        textures->spectra[desc.name] = MakeSpectrumTexture(desc, scene, *textures);
}

}  // namespace gradus
