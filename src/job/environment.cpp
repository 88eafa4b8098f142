#include "job/environment.h"

#include <cctype>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "core/provenance.h"
#include "core/transform.h"

namespace gradus {

namespace {

FileLoc CommandLineLoc() {
    FileLoc loc;
    loc.file = std::make_shared<const std::string>("<command line --envmap>");
    return loc;
}

std::string Number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string LowerExtension(const std::string &file) {
    const size_t dot = file.rfind('.'), slash = file.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    std::string e = file.substr(dot + 1);
    for (char &c : e) c = char(std::tolower((unsigned char)c));
    return e;
}

}  // namespace

std::string EnvironmentOptions::describe() const {
    if (!given()) return "";
    if (!addsLight()) return "none";
    return "\"" + map + "\" scale " + Number(scale) + " rotate " + Number(rotateDegrees);
}

std::string EnvironmentOptions::identity() const {
    if (!addsLight()) return given() ? "none" : "";
    return "map scale " + Number(scale) + " rotate " + Number(rotateDegrees);
}

void LoadEnvironmentMap(EnvironmentOptions *env) {
    const FileLoc at = CommandLineLoc();
    if (!(std::isfinite(env->scale) && env->scale >= 0))
        throw Error(at, "--envmap-scale must be a finite number >= 0, got " + Number(env->scale));
    if (!std::isfinite(env->rotateDegrees))
        throw Error(at, "--envmap-rotate must be a finite number of degrees, got " + Number(env->rotateDegrees));
    if (!env->addsLight()) {
        if (env->scale != 1 || env->rotateDegrees != 0)
            throw Error(at, "--envmap-scale and --envmap-rotate need --envmap FILE");
        return;
    }
    const std::string ext = LowerExtension(env->map);
    if (ext != "exr" && ext != "hdr" && ext != "pfm")
        throw Error(at, env->map + ": expected a lat-long HDR image (.exr, .hdr or .pfm), or \"none\"");
    Image rgb;
    try {
        const Image img = ReadImage(env->map);  // .hdr: stb_image's Radiance reader (stbi_loadf)
        rgb = img.layerRGB(DefaultRGBLayer(img));
    } catch (const Error &e) {
        throw Error(at, e.what());  // the reader's message starts with the file's name
    }
    // An infinite light's radiance must be finite and non-negative (no NaN/Inf reaches a film).
    for (int y = 0; y < rgb.height(); ++y)
        for (int x = 0; x < rgb.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                const float v = rgb.at(x, y, c);
                if (!(std::isfinite(v) && v >= 0))
                    throw Error(at, env->map + ": texel (" + std::to_string(x) + ", " + std::to_string(y) +
                                        ") has the value " + Number(v) + " (radiance must be finite and >= 0)");
            }
    env->image = std::make_shared<const Image>(std::move(rgb));
}

void AddEnvironmentLight(const EnvironmentOptions &env, bool gltfScene, SceneDesc *desc) {
    if (!env.addsLight()) return;
    GRADUS_CHECK(env.image != nullptr);  // LoadEnvironmentMap first
    RecordInputFile(env.map);            // the map is an input of the render (scene_hash)
    LightDesc l;
    l.type = "infinite";
    l.present = true;
    l.loc = CommandLineLoc();
    l.map = env.image;
    Param L;
    L.type = "rgb";
    L.name = "L";
    L.loc = l.loc;
    L.numbers = {env.scale, env.scale, env.scale};
    l.params.add(L);
    // pbrt-v3's map: the top row at light-space +z, u = phi / 2 pi from +x towards +y.
    const Float deg = Float(env.rotateDegrees);
    l.worldFromLight = gltfScene ? RotateY(deg) * RotateX(-90) : RotateZ(deg);
    desc->lights.push_back(std::move(l));
}

}  // namespace gradus
