// libFuzzer entry for the image loaders behind image textures and environment
// maps: the first byte picks the file name's extension (which decides the 8-bit
// "gamma" handling of textures; ReadImage itself goes by the magic bytes) and
// the rest is the file, written to a temp file because ReadImage takes a path.
// The image is turned into texels as "imagemap" does and into an "infinite"
// light, both queried. Any exception other than gradus::Error, any crash or
// sanitizer report is a bug, and so is a non-finite light pdf or sample from a
// map whose texels are all finite and non-negative.
//   ./fuzz_image -max_len=8192 corpus/   (seeds: tests/fuzz/corpus/fuzz_image)
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <stb_image.h>

#include "core/error.h"
#include "image/image.h"
#include "lights/light.h"
#include "textures/textures.h"

namespace {

const char *kExtensions[8] = {".exr", ".png", ".tga", ".pfm", ".hdr", ".jpg", ".bmp", ".gif"};

bool Finite(const gradus::Spectrum &s) { return std::isfinite(s.r) && std::isfinite(s.g) && std::isfinite(s.b); }

// Pixels the file's header claims (the sum over EXR parts), 0 if unknown.
size_t ClaimedPixels(const std::string &path, const uint8_t *bytes, size_t n) {
    if (n >= 4 && bytes[0] == 0x76 && bytes[1] == 0x2f && bytes[2] == 0x31 && bytes[3] == 0x01) {
        try {
            gradus::CheckEXRHeaders(path);
            Imf::MultiPartInputFile file(path.c_str());
            size_t sum = 0;
            for (int p = 0; p < file.parts(); ++p) {
                Imath::Box2i dw = file.header(p).dataWindow();
                sum += size_t(int64_t(dw.max.x) - dw.min.x + 1) * size_t(int64_t(dw.max.y) - dw.min.y + 1);
            }
            return sum;
        } catch (const std::exception &) {
            return 0;  // ReadImage reports it
        }
    }
    int w = 0, h = 0, c = 0;
    if (!stbi_info_from_memory(bytes, int(std::min<size_t>(n, INT32_MAX)), &w, &h, &c)) return 0;
    return size_t(w) * size_t(h);
}

void Require(bool ok, const char *what) {
    if (ok) return;
    std::fprintf(stderr, "fuzz_image: %s\n", what);
    std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    using namespace gradus;
    if (size < 1) return 0;
    const int ext = data[0] & 7;
    const bool gamma = data[0] & 8;
    static const std::string base =
        (std::filesystem::temp_directory_path() / ("gradus-fuzz-image-" + std::to_string(::getpid()))).string();
    const std::string path = base + kExtensions[ext];
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char *>(data + 1), std::streamsize(size - 1));
    }
    try {
        // Known finding, skipped so that fuzzing gets past it: ReadImage allocates the size a
        // header claims before any pixel data is read or found missing (stb_image even
        // decodes truncated files as if complete): a 23-byte RLE TGA claiming 5124x12062
        // decodes 62 Mpx, a 1.3 KB EXR with a mutated data window asks for 58 GB.
        // Remove once ReadImage bounds it.
        if (ClaimedPixels(path, data + 1, size - 1) > (size_t(1) << 18)) {
            std::remove(path.c_str());
            return 0;
        }
        Image img = ReadImage(path);
        std::remove(path.c_str());
        bool eightBit = ext == 1 || ext == 2 || ext >= 5;
        auto grid = MakeTexelGrid(img, eightBit && !gamma);
        bool valid = img.width() > 0 && img.height() > 0;
        for (float v : img.data()) valid = valid && std::isfinite(v) && v >= 0;
        for (WrapMode wrap : {WrapMode::Repeat, WrapMode::Black, WrapMode::Clamp})
            for (Point2 st : {Point2(0.5, 0.5), Point2(0, 0), Point2(1, 1), Point2(-3.7, 12.2), Point2(1e300, -1e300)}) {
                Spectrum s = grid->bilerp(st, wrap);
                if (valid) Require(Finite(s), "non-finite texel lookup");
            }
        auto light = CreateInfiniteLight(Transform(), Spectrum(1), &img);
        light->preprocess(Bounds3{Point3(-1, -1, -1), Point3(1, 1, 1)});
        Spectrum power = light->power();
        if (valid) Require(Finite(power), "non-finite environment power");
        Interaction ref(Point3(0, 0, 0), Normal3(0, 0, 1), Vec3(0, 0, 1));
        for (Point2 u : {Point2(0.5, 0.5), Point2(0, 0), Point2(0.999999, 0.999999), Point2(0.25, 0.75)}) {
            LightLiSample s;
            if (light->sampleLi(ref, u, &s) && valid) {
                Require(std::isfinite(s.pdf) && s.pdf > 0 && Finite(s.L), "non-finite environment sample");
                Require(std::isfinite(light->pdfLi(ref, s.wi)), "non-finite environment pdf");
            }
            LightLeSample le;
            if (light->sampleLe(u, Point2(0.3, 0.6), &le) && valid)
                Require(std::isfinite(le.pdfDir) && std::isfinite(le.pdfPos) && Finite(le.L),
                        "non-finite environment emission sample");
            Spectrum L = light->Le(Ray(Point3(0, 0, 0), Normalize(Vec3(u.x - 0.5, u.y - 0.5, 0.3))));
            if (valid) Require(Finite(L), "non-finite environment radiance");
        }
    } catch (const Error &) {
        std::remove(path.c_str());
    }
    return 0;
}
