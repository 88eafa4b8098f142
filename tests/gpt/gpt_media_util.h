// Scenes of the G-PT media tests: scenes/media/fog-box.pbrt (homogeneous fog
// and a material-less smoke sphere: a medium interface inside the fog) and a
// variant whose fog is a density grid (delta tracking, ratio tracking, empty
// majorant cells), as the bidirectional media tests use them
// (tests/integrators/media_test.cpp).
#pragma once
#include <fstream>
#include <sstream>
#include <string>

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

}  // namespace gradus::gptmedia
