// The conformance table's shared parts: the integrator list, the scenes, a
// scratch directory per test and a checked render through the gradus binary.
#pragma once
#include <gtest/gtest.h>

#include <iostream>
#include <string>
#include <vector>

#include "conformance_util.h"

namespace gradus::conformance {

// Read once per test process from `gradus --list-integrators`.
inline const std::vector<std::string> &Integrators() {
    static const std::vector<std::string> names = ListIntegrators();
    return names;
}

// Both scenes (tests/conformance/data): 24x24, a closed diffuse box with a
// ceiling area light, box pixel filter (every integrator estimates the same
// per-pixel image), maxdepth 5; specular-box adds a glass sphere, a glossy
// metal sphere and a mirror panel.
inline const std::vector<std::string> &Scenes() {
    static const std::vector<std::string> names = {"diffuse-box", "specular-box", "outdoor"};
    return names;
}

// Ambient occlusion inside the closed boxes is 0 everywhere: every hemisphere
// is occluded. Checks that need a lit image use another scene there.
inline bool BlackByDesign(const std::string &integrator, const std::string &scene) {
    return integrator == "ambientocclusion" && scene != "outdoor";
}

inline std::string ScenePath(const std::string &name) {
    return std::string(GRADUS_SOURCE_DIR) + "/tests/conformance/data/" + name + ".pbrt";
}

inline std::string Sanitize(std::string s) {
    for (char &c : s)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return s;
}

// A scratch directory per test, removed afterwards.
class ScratchDir {
  public:
    ScratchDir() {
        const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
        path_ = fs::temp_directory_path() / ("gradus_conformance_" + std::to_string(::getpid()) + "_" +
                                             Sanitize(std::string(info->test_suite_name()) + "_" + info->name()));
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~ScratchDir() { fs::remove_all(path_); }
    const fs::path &path() const { return path_; }

  private:
    fs::path path_;
};

struct Output {
    ProcResult proc;
    Image image;
    bool ok = false;  // exited 0 and the image was read
};

// Renders `scene` with `integrator` (the scene's Integrator parameters, i.e.
// maxdepth, apply to the override). Expects exit 0 and a readable EXR that
// passes check 5: every layer finite, nonfinite_discarded reported.
inline Output Render(const fs::path &dir, const std::string &scene, const std::string &integrator,
                     const std::vector<std::string> &extra, const std::string &outName) {
    Output o;
    std::vector<std::string> args = {ScenePath(scene), "--integrator", integrator, "--outfile", outName, "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    o.proc = RunGradus(args, dir);
    EXPECT_TRUE(o.proc.exited && o.proc.exitCode == 0) << scene << " " << outName << ": " << o.proc.describe();
    if (!o.proc.exited || o.proc.exitCode != 0) return o;
    try {
        o.image = ReadImage((dir / outName).string());
    } catch (const std::exception &e) {
        ADD_FAILURE() << scene << " " << outName << ": " << e.what();
        return o;
    }
    o.ok = true;
    long long nf = CheckFiniteAndReported(o.image, integrator + " " + scene + " " + outName);
    if (nf > 0)
        std::cout << "[ note ] " << integrator << " " << scene << " " << outName << ": nonfinite_discarded " << nf
                  << "\n";
    return o;
}

}  // namespace gradus::conformance
