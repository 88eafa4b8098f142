// libFuzzer entry: the first byte chooses the pbrt parser or the PLY reader;
// the rest is the input. Any exception other than gradus::Error, any crash or
// sanitizer report is a bug.
//   ./fuzz_parser -max_len=4096 corpus/   (seed corpus: tests/parser/data)
#include <cstdint>
#include <cstring>
#include <string>

#include "parser/ply.h"
#include "parser/scene_desc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    const char *text = reinterpret_cast<const char *>(data + 1);
    size_t n = size - 1;
    try {
        if (data[0] & 1) {
            gradus::ReadPlyFromMemory(text, n, "fuzz.ply");
        } else {
            std::string s(text, n);
            // Keep the fuzzer away from the file system (Include "/dev/zero",
            // spectrum files): those paths are not what is being tested.
            if (s.find("Include") != std::string::npos || s.find('/') != std::string::npos ||
                (s.find('.') != std::string::npos && s.find("spectrum") != std::string::npos))
                return 0;
            gradus::SceneDesc scene = gradus::ParseString(s, "fuzz.pbrt", "/nonexistent");
            // Exercise the typed lookups on whatever was parsed.
            for (const auto &sh : scene.shapes)
                for (const auto &p : sh.params.all()) {
                    try {
                        sh.params.getSpectrum(p.name, {});
                    } catch (const gradus::Error &) {
                    }
                    try {
                        sh.params.getPoint3s(p.name);
                    } catch (const gradus::Error &) {
                    }
                }
        }
    } catch (const gradus::Error &) {
    }
    return 0;
}
