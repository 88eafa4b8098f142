// A float image with named channels ("R", "G", "B", "primal.R", "dx.G", ...),
// stored interleaved per pixel, plus typed metadata written to EXR headers
// and the placement of the pixels in a larger display window (crops).
#pragma once
#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace gradus {

// One metadata value: its text and the type it is written with (EXR string,
// int or double attribute). Assigning a string gives a string value.
class MetaValue {
  public:
    enum class Type { String, Int, Double };
    MetaValue() = default;
    MetaValue(std::string s) : text_(std::move(s)) {}
    MetaValue(const char *s) : text_(s) {}
    static MetaValue Int(int64_t v);
    static MetaValue Double(double v);
    Type type() const { return type_; }
    const std::string &str() const { return text_; }
    const char *c_str() const { return text_.c_str(); }
    bool empty() const { return text_.empty(); }
    operator const std::string &() const { return text_; }
    // Numeric value (0 for text that is not a number).
    double number() const;
    friend bool operator==(const MetaValue &a, const std::string &b) { return a.text_ == b; }
    friend bool operator!=(const MetaValue &a, const std::string &b) { return a.text_ != b; }
    friend std::ostream &operator<<(std::ostream &o, const MetaValue &v) { return o << v.text_; }

  private:
    Type type_ = Type::String;
    std::string text_;
};
using Metadata = std::map<std::string, MetaValue>;

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
    // Adds the channels not present yet in one reallocation (the data is
    // interleaved: adding channels one by one copies the image each time).
    void addChannels(const std::vector<std::string> &names);
    // The R, G, B channel names of a layer ("" = unprefixed).
    static std::vector<std::string> LayerRGBNames(const std::string &prefix);
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

    Metadata metadata;
    // Placement in the display window (EXR dataWindow inside displayWindow):
    // a crop of a larger image keeps its position. Display size 0 = the image's own size.
    int originX = 0, originY = 0, displayWidth = 0, displayHeight = 0;

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

// How ReadImage turns the integer pixels of 8/16-bit files (PNG, TGA, JPEG,
// BMP) into floats: sRGB-decoded to linear, or the stored value over 255 (65535)
// as pbrt-v3's ReadImage gives them to its lights (imageio.cpp, ReadImagePNG/TGA:
// no inverse gamma). Alpha is always the stored value; float formats ignore this.
enum class IntegerPixels { SRGBDecoded, Stored };

// Reads EXR (all channels, multi-layer), PNG (8/16-bit), PFM (either
// endianness); other formats stb_image knows (JPEG, TGA, BMP, HDR) too.
// Format is chosen by the file's magic bytes. Throws gradus::Error naming the file on failure.
Image ReadImage(const std::string &filename, IntegerPixels ints = IntegerPixels::SRGBDecoded);

// pbrt-v3's MIP-map base level (mipmap.h, MIPMap constructor): an image whose
// width or height is not a power of two is resampled, separably, to the next
// powers of two with a 4-tap Lanczos kernel (sinc(pi d) sinc(pi d / 2), |d| <= 2
// source texels, weights normalised per output texel), the image repeating
// beyond its edges, and negative results clamped to 0. Other images are returned as they are.
Image ResampleToPowerOfTwo(const Image &image);

// Throws Error if an EXR file's headers claim attribute sizes beyond the file
// (run by ReadImage before OpenEXR reads the headers).
void CheckEXRHeaders(const std::string &filename);

// Writes atomically (a temporary file in the same directory, renamed into
// place), by extension: .exr (float32, every channel, metadata as typed
// attributes), .png (R,G,B clamped, sRGB-encoded, 8-bit), .pfm (R,G,B float).
// PNG/PFM take the DefaultRGBLayer. Unknown extension -> gradus::Error.
void WriteImage(const std::string &filename, const Image &image);
// Throws (naming the file) unless `filename` has a writable extension and its
// directory exists and is writable: checked before a render starts.
void CheckWritableImagePath(const std::string &filename);

}  // namespace gradus
