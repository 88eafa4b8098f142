// Writes 8-bit codes to a PNG with libpng directly (not Gradus's writer), so
// tests can read known stored values back through ReadImage.
#pragma once
#include <png.h>

#include <cstring>
#include <string>

namespace gradus::test {

// codes: width x height pixels of `channels` (3: RGB, 4: RGBA) bytes, row-major.
inline bool WritePngCodes(const std::string &path, int width, int height, int channels, const unsigned char *codes) {
    png_image png;
    std::memset(&png, 0, sizeof(png));
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(width);
    png.height = png_uint_32(height);
    png.format = channels == 4 ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
    return png_image_write_to_file(&png, path.c_str(), 0, codes, 0, nullptr) != 0;
}

}  // namespace gradus::test
