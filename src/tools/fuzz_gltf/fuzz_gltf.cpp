// libFuzzer entry: the input is a glTF file (.gltf JSON or .glb; the loader
// tells them apart by the magic). It is written to a temporary file, loaded
// with LoadGltfScene and built with BuildScene for an 8x8 film. gradus::Error
// is an expected outcome; any other exception, a crash, a sanitizer report or
// a hang (-timeout) is a finding.
//   ./fuzz_gltf corpus/   (seeds: the files of tests/gltf/make_gltf.py; scripts/fuzz writes them)
// FUZZ_GLTF_PRINT=1 prints each input's error, if any (to replay an input).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "parser/gltf.h"
#include "job/job.h"

namespace {

// A directory of our own, so that relative URIs in the input resolve to nothing.
const std::string &InputPath() {
    static const std::string path = [] {
        char tmpl[] = "/tmp/fuzz_gltf.XXXXXX";
        const char *dir = ::mkdtemp(tmpl);
        if (!dir) std::abort();
        return std::string(dir) + "/input.gltf";
    }();
    return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    using namespace gradus;
    static const bool print = std::getenv("FUZZ_GLTF_PRINT") != nullptr;
    const std::string &path = InputPath();
    FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    try {
        SceneDesc desc = LoadGltfScene(path, GltfOptions());
        std::unique_ptr<Scene> scene = BuildScene(desc, Point2i{8, 8});
        if (print) std::fprintf(stderr, "---- built: %zu lights\n", scene->lights.size());
    } catch (const Error &e) {
        if (print) std::fprintf(stderr, "---- error: %s\n", e.what());
    }
    return 0;
}
