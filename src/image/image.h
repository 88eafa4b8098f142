// A float image with named channels ("R", "G", "B", "primal.R", "dx.G", ...),
// stored interleaved per pixel, plus string metadata written to EXR headers.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace gradus {

class Image {
  public:
    Image() = default;
    Image(int width, int height, std::vector<std::string> channels);
    // An RGB image with channels R, G, B.
    static Image RGB(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    int numChannels() const { return int(channels_.size()); }
    const std::vector<std::string> &channelNames() const { return channels_; }
    // Index of a channel, or -1.
    int channelIndex(const std::string &name) const;
    // Adds a channel (zero-filled) and returns its index; existing name -> its index.
    int addChannel(const std::string &name);
    // Layer names present: "" for unprefixed R,G,B; "primal" for primal.R etc.
    std::vector<std::string> layers() const;
    // Extracts layer `prefix` ("" = unprefixed) as an RGB image (R,G,B or Y replicated).
    Image layerRGB(const std::string &prefix) const;
    // Adds (or overwrites) layer `prefix` from an RGB image of the same size.
    void setLayerRGB(const std::string &prefix, const Image &rgb);

    float &at(int x, int y, int c) { return data_[(size_t(y) * width_ + x) * channels_.size() + c]; }
    float at(int x, int y, int c) const { return data_[(size_t(y) * width_ + x) * channels_.size() + c]; }
    std::vector<float> &data() { return data_; }
    const std::vector<float> &data() const { return data_; }

    std::map<std::string, std::string> metadata;

  private:
    int width_ = 0, height_ = 0;
    std::vector<std::string> channels_;
    std::vector<float> data_;
};

// The layer that single-layer outputs (PNG, PFM, diff) use by default: "" when
// unprefixed R,G,B (or Y) exist, else "primal" if it has R,G,B, else the first
// layer with R,G,B, else the first with Y. Throws if none.
std::string DefaultRGBLayer(const Image &image);

// sRGB transfer function (IEC 61966-2-1), on [0,1].
float SRGBToLinear(float v);
float LinearToSRGB(float v);

// Reads EXR (all channels, multi-layer), PNG (8/16-bit, sRGB decoded to linear),
// PFM (either endianness); other formats stb_image knows (JPEG, TGA, BMP, HDR) too.
// Format is chosen by the file's magic bytes. Throws gradus::Error naming the file on failure.
Image ReadImage(const std::string &filename);
// Writes by extension: .exr (float32, every channel, metadata as string
// attributes), .png (R,G,B clamped, sRGB-encoded, 8-bit), .pfm (R,G,B float).
// PNG/PFM take the DefaultRGBLayer. Unknown extension -> gradus::Error.
void WriteImage(const std::string &filename, const Image &image);

}  // namespace gradus
