// Scenes of the G-PT media tests: scenes/media/fog-box.pbrt (homogeneous fog
// and a material-less smoke sphere: a medium interface inside the fog) and a
// variant whose fog is a density grid (delta tracking, ratio tracking, empty
// majorant cells), as the bidirectional media tests use them
// (tests/integrators/media_test.cpp).
#pragma once
#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace gradus::gptmedia {

inline std::string ReadText(const std::string &path) {
    std::ifstream f(path);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

inline std::string FogBoxText() { return ReadText(std::string(GRADUS_SOURCE_DIR) + "/scenes/media/fog-box.pbrt"); }

inline std::string ReplaceOnce(std::string text, const std::string &from, const std::string &to) {
    const size_t at = text.find(from);
    if (at == std::string::npos) return "";
    text.replace(at, from.size(), to);
    return text;
}

// The fog as a 6 x 4 x 8 density grid over the room (values 0 .. 2.25,
// sigma_t = 0.5 x density, coloured albedo).
inline std::string GridFogBoxText() {
    constexpr int nx = 6, ny = 4, nz = 8;
    std::ostringstream g;
    g << "MakeNamedMedium \"fog\" \"string type\" \"heterogeneous\"\n"
      << "    \"rgb sigma_a\" [0.0625 0.125 0.1875] \"rgb sigma_s\" [0.4375 0.375 0.3125] \"float g\" [0.3]\n"
      << "    \"point p0\" [-1.5 0 -3.3] \"point p1\" [1.5 2 1.5] \"integer nx\" [" << nx << "] \"integer ny\" [" << ny
      << "] \"integer nz\" [" << nz << "]\n    \"float density\" [";
    for (int z = 0; z < nz; ++z)
        for (int y = 0; y < ny; ++y)
            for (int x = 0; x < nx; ++x) g << " " << double((7 * x + 3 * y + 5 * z) % 10) / 4;
    g << "]\n";
    return ReplaceOnce(FogBoxText(),
                       "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                       "    \"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.35 0.3 0.25] \"float g\" [0.3]\n",
                       g.str());
}

// fog-box with its fog 4 times denser on a 12 x 9 film: one pixel is ~5
// degrees, so offsets' segments differ from the base's by tenths of a unit at
// optical depths ~1.6 per unit: transmittance ratios far from 1.
inline std::string DenseFogBoxText() {
    std::string t = ReplaceOnce(FogBoxText(),
                                "\"rgb sigma_a\" [0.05 0.05 0.05] \"rgb sigma_s\" [0.35 0.3 0.25] \"float g\" [0.3]",
                                "\"rgb sigma_a\" [0.2 0.2 0.2] \"rgb sigma_s\" [1.4 1.2 1.0] \"float g\" [0.3]");
    t = ReplaceOnce(t, "\"integer xresolution\" [24] \"integer yresolution\" [18]",
                    "\"integer xresolution\" [12] \"integer yresolution\" [9]");
    return t;
}

// A material-less wedge of dense smoke (sigma_t 2, albedo 0.8, g 0.2) whose
// thickness grows from 0.05 to 1.05 across the image, before a diffuse wall
// lit by an area light above; the camera is outside the wedge (vacuum). Base
// and offset camera segments cross its faces in lockstep, and their pieces
// inside it differ in length by a lot and in one direction: the transmittance
// ratios of changed segments (pass-through, scattering, reconnection across
// the back face) set the gradients.
// `extra`: more shapes in the world block.
inline std::string WedgeText(const std::string &integratorLine = "Integrator \"path\" \"integer maxdepth\" [4]",
                             const std::string &extra = "") {
    // Faces of the prism with x in [-1.5, 1.5], y in [0, 2], z from 0 to
    // 0.05 + (x + 1.5) / 3, each oriented outwards (pbrt's triangle normal is
    // cross(p0 - p2, p1 - p2); the interface's inside is against it).
    struct P {
        double x, y, z;
    };
    const P c{0.0, 1.0, 0.3};
    auto face = [&](std::vector<P> q) {
        auto sub = [](P a, P b) { return P{a.x - b.x, a.y - b.y, a.z - b.z}; };
        const P u = sub(q[0], q[2]), v = sub(q[1], q[2]);
        const P n{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
        const P d = sub(q[0], c);
        if (n.x * d.x + n.y * d.y + n.z * d.z < 0) std::reverse(q.begin(), q.end());
        std::ostringstream o;
        o << "  Shape \"trianglemesh\" \"integer indices\" [" << (q.size() == 4 ? "0 1 2 0 2 3" : "0 1 2")
          << "] \"point P\" [";
        for (const P &p : q) o << p.x << " " << p.y << " " << p.z << " ";
        o << "]\n";
        return o.str();
    };
    const double z0 = 0.05, z1 = 1.05;
    std::ostringstream s;
    s << "LookAt 0 1 -3  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\n"
      << "Film \"image\" \"integer xresolution\" [12] \"integer yresolution\" [9] \"string filename\" \"w.exr\"\n"
      << "Sampler \"sobol\" \"integer pixelsamples\" [16]\nPixelFilter \"box\"\n"
      << integratorLine << "\n"
      << "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.4 0.4 0.4] "
         "\"rgb sigma_s\" [1.6 1.6 1.6] \"float g\" [0.2]\n"
      << "WorldBegin\n"
      << "AttributeBegin\n  AreaLightSource \"diffuse\" \"rgb L\" [4 4 4] \"bool twosided\" true\n"
      << "  Material \"matte\" \"rgb Kd\" [0 0 0]\n"
      << "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
         "[-1 2.6 -1  1 2.6 -1  1 2.6 1.5  -1 2.6 1.5]\nAttributeEnd\n"
      << "AttributeBegin\n  Material \"matte\" \"rgb Kd\" [0.7 0.6 0.5]\n"
      << "  Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" "
         "[-4 -2 2.2  4 -2 2.2  4 4 2.2  -4 4 2.2]\nAttributeEnd\n"
      << "AttributeBegin\n  MediumInterface \"smoke\" \"\"\n  Material \"\"\n"
      << face({{-1.5, 0, 0}, {1.5, 0, 0}, {1.5, 2, 0}, {-1.5, 2, 0}})
      << face({{-1.5, 0, z0}, {1.5, 0, z1}, {1.5, 2, z1}, {-1.5, 2, z0}})
      << face({{-1.5, 0, 0}, {-1.5, 2, 0}, {-1.5, 2, z0}, {-1.5, 0, z0}})
      << face({{1.5, 0, 0}, {1.5, 2, 0}, {1.5, 2, z1}, {1.5, 0, z1}})
      << face({{-1.5, 0, 0}, {1.5, 0, 0}, {1.5, 0, z1}, {-1.5, 0, z0}})
      << face({{-1.5, 2, 0}, {1.5, 2, 0}, {1.5, 2, z1}, {-1.5, 2, z0}}) << "AttributeEnd\n"
      << extra << "WorldEnd\n";
    return s.str();
}

// Specular and near-specular surfaces in and behind the smoke: a smooth glass
// sphere inside the wedge (random replay of its Dirac lobes; the smoke fills it:
// its surface is no medium transition) and a near-specular metal sphere behind
// it (roughness 5e-4, below the shift threshold: half-vector copy), so that
// offsets copy free-flight distances after specular bounces; and an
// environment light (environment shifts: reconnections towards infinity out of
// the smoke).
inline std::string WedgeSpecularText(const std::string &integratorLine) {
    return WedgeText(integratorLine,
                     "LightSource \"infinite\" \"rgb L\" [0.4 0.5 0.6]\n"
                     "AttributeBegin\n  Material \"glass\"\n  Translate 0.6 1.2 0.45\n"
                     "  Shape \"sphere\" \"float radius\" [0.3]\nAttributeEnd\n"
                     "AttributeBegin\n  Material \"metal\" \"float roughness\" [0.0005] \"bool remaproughness\" \"false\"\n"
                     "  Translate -0.6 0.7 1.6\n  Shape \"sphere\" \"float radius\" [0.5]\nAttributeEnd\n");
}

}  // namespace gradus::gptmedia
