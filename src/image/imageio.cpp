// Image file I/O: OpenEXR (multi-part, multi-layer), PNG (write: libpng; read:
// stb_image, which also covers JPEG/TGA/BMP/HDR) and PFM.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfDoubleAttribute.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/provenance.h"
#include "image/image.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-but-set-variable"
#define STB_IMAGE_IMPLEMENTATION
#define STBI_NO_STDIO
#define STBI_FAILURE_USERMSG
// Formats gradus does not read (stb detects formats by content, whatever the
// file's extension): PNM's header parser overflows int on long digit runs
// (UBSan, fuzz_image campaign), and PSD/PIC are no texture formats of pbrt-v3.
#define STBI_NO_PNM
#define STBI_NO_PSD
#define STBI_NO_PIC
#include <stb_image.h>
#pragma GCC diagnostic pop

namespace gradus {

namespace {

std::string Lower(std::string s) {
    for (char &c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

std::string Extension(const std::string &filename) {
    size_t dot = filename.rfind('.');
    size_t slash = filename.find_last_of("/\\");
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return Lower(filename.substr(dot + 1));
}

std::vector<unsigned char> ReadWholeFile(const std::string &filename) {
    std::vector<unsigned char> bytes;
    switch (ReadFileBytes(filename, &bytes)) {
    case FileRead::CannotOpen: throw Error(filename + ": cannot open file for reading");
    case FileRead::ReadError: throw Error(filename + ": read error");
    case FileRead::Ok: break;
    }
    return bytes;
}

// A header that claims more pixels than this machine could hold fails with a
// message before anything is allocated (a 22-byte TGA may claim 62 Mpx, a
// damaged EXR 58 GB).
void CheckImageSize(const std::string &filename, double width, double height, double channels) {
    static const double physical = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
    const double bytes = width * height * channels * sizeof(float);
    if (!(width > 0 && height > 0) || width > (1 << 20) || height > (1 << 20) || (physical > 0 && bytes > physical / 2)) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ": image of %.0fx%.0f pixels x %.0f channels (%.3g GiB) is larger than this "
                      "reader accepts", width, height, channels, bytes / (1 << 30));
        throw Error(filename + buf);
    }
}

bool LittleEndianHost() {
    uint32_t one = 1;
    unsigned char b;
    std::memcpy(&b, &one, 1);
    return b == 1;
}

// Channel order inside a layer: R, G, B, A, then the others alphabetically.
int ChannelRank(const std::string &name) {
    size_t dot = name.rfind('.');
    std::string base = dot == std::string::npos ? name : name.substr(dot + 1);
    if (base == "R") return 0;
    if (base == "G") return 1;
    if (base == "B") return 2;
    if (base == "A") return 3;
    return 4;
}

std::string LayerOf(const std::string &name) {
    size_t dot = name.rfind('.');
    return dot == std::string::npos ? "" : name.substr(0, dot);
}

// Standard EXR attributes that are not user metadata.
bool IsStandardAttribute(const std::string &n) {
    static const char *names[] = {"channels", "compression", "dataWindow", "displayWindow",
                                  "lineOrder", "pixelAspectRatio", "screenWindowCenter",
                                  "screenWindowWidth", "tiles", "type", "name", "version",
                                  "chunkCount", "view"};
    for (const char *s : names)
        if (n == s) return true;
    return false;
}

// ---------------------------------------------------------------- EXR

// Size in bytes of the EXR attribute types OpenEXR reads with a fixed layout, -1 otherwise.
int FixedEXRAttributeSize(const std::string &type) {
    static const std::pair<const char *, int> sizes[] = {
        {"box2i", 16}, {"box2f", 16}, {"chromaticities", 32}, {"compression", 1}, {"double", 8}, {"envmap", 1},
        {"float", 4}, {"int", 4}, {"keycode", 28}, {"lineOrder", 1}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64},
        {"m44d", 128}, {"rational", 8}, {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16},
        {"v3i", 12}, {"v3f", 12}, {"v3d", 24}, {"deepImageState", 1}};
    for (const auto &[name, size] : sizes)
        if (type == name) return size;
    return -1;
}

}  // namespace

// OpenEXR allocates the size an attribute claims before reading it (a 1.3 KB file
// whose string attribute claims 1.9 GB allocates 1.9 GB). The attribute list of
// every header is walked here first: each size must fit in what is left of the
// file and agree with the layout OpenEXR will read for the type (fixed sizes,
// channel lists, string vectors, a preview's pixel count).
void CheckEXRHeaders(const std::string &filename) {
    std::ifstream in(filename, std::ios::binary | std::ios::ate);
    if (!in) throw Error(filename + ": cannot open file for reading");
    const int64_t fileSize = int64_t(in.tellg());
    in.seekg(0);
    auto fail = [&](const std::string &what) { throw Error(filename + ": corrupt EXR header: " + what); };
    unsigned char head[8];
    if (!in.read(reinterpret_cast<char *>(head), 8)) fail("file ends inside the magic number and version");
    const bool longNames = head[5] & 0x04, multipart = head[5] & 0x10;
    const size_t maxName = longNames ? 255 : 31;
    auto readString = [&](const char *what) {
        std::string s;
        for (char c; in.get(c) && c != '\0';) {
            if (s.size() >= maxName) fail(std::string(what) + " longer than " + std::to_string(maxName) + " characters");
            s.push_back(c);
        }
        if (!in) fail(std::string("file ends inside an attribute ") + what);
        return s;
    };
    auto readInt = [&](const char *what) {
        unsigned char b[4];
        if (!in.read(reinterpret_cast<char *>(b), 4)) fail(std::string("file ends inside ") + what);
        return int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
    };
    for (int part = 0;; ++part) {
        int attributes = 0;
        for (;; ++attributes) {
            std::string name = readString("name");
            if (name.empty()) break;
            std::string type = readString("type");
            const int32_t size = readInt("an attribute size");
            const int64_t left = fileSize - int64_t(in.tellg());
            if (size < 0 || size > left)
                fail("attribute \"" + name + "\" claims " + std::to_string(size) + " bytes, " +
                     std::to_string(left) + " are left in the file");
            // OpenEXR reads known types by their structure, not by the size field: a
            // fixed-size type must have its size, a channel list and a string vector must
            // end exactly where the size says, or its reading drifts into other bytes.
            const int64_t end = int64_t(in.tellg()) + size;
            auto mismatch = [&] { fail("attribute \"" + name + "\" of type " + type + " has " + std::to_string(size) + " bytes"); };
            const int fixed = FixedEXRAttributeSize(type);
            if (fixed >= 0 && size != fixed) mismatch();
            if (type == "preview") {
                if (size < 8) mismatch();
                const int64_t w = uint32_t(readInt("a preview size")), h = uint32_t(readInt("a preview size"));
                if (w * h * 4 != int64_t(size) - 8)
                    fail("preview of " + std::to_string(w) + "x" + std::to_string(h) + " pixels in " +
                         std::to_string(size) + " bytes");
            } else if (type == "chlist") {
                // Entries: name, then 16 bytes (type, pLinear + reserved, x and y sampling); an empty name ends it.
                while (!readString("channel name").empty()) {
                    in.seekg(16, std::ios::cur);
                    if (int64_t(in.tellg()) > end - 1) mismatch();
                }
                if (int64_t(in.tellg()) != end) mismatch();
            } else if (type == "stringvector") {
                while (int64_t(in.tellg()) < end) {
                    const int32_t len = readInt("a string vector");
                    if (len < 0 || len > end - int64_t(in.tellg())) mismatch();
                    in.seekg(len, std::ios::cur);
                }
            }
            in.seekg(end);
        }
        // A single-part file has one header; a multi-part file ends its list with an empty one.
        if (!multipart || (attributes == 0 && part > 0)) break;
        if (attributes == 0) fail("multi-part file without a header");
    }
}

namespace {

Image ReadEXR(const std::string &filename) {
    CheckEXRHeaders(filename);
    Imf::MultiPartInputFile file(filename.c_str());
    int nparts = file.parts();
    struct Src {
        int part;
        std::string exrName, name;
    };
    std::vector<Src> sources;
    Imath::Box2i window;
    bool haveWindow = false;
    Metadata metadata;
    Imath::Box2i display = file.header(0).displayWindow();
    for (int p = 0; p < nparts; ++p) {
        const Imf::Header &h = file.header(p);
        if (h.hasType() && (h.type() == Imf::DEEPSCANLINE || h.type() == Imf::DEEPTILE))
            throw Error(filename + ": deep EXR images are not supported");
        Imath::Box2i dw = h.dataWindow();
        if (!haveWindow) {
            window = dw;
            haveWindow = true;
        } else if (dw.size() != window.size()) {
            throw Error(filename + ": EXR parts have different data window sizes");
        }
        std::string partName = (nparts > 1 && h.hasName()) ? h.name() : "";
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                throw Error(filename + ": subsampled channel \"" + it.name() +
                            "\" is not supported");
            std::string name = it.name();
            if (!partName.empty() && name.compare(0, partName.size() + 1, partName + ".") != 0)
                name = partName + "." + name;
            sources.push_back({p, it.name(), name});
        }
        for (auto it = h.begin(); it != h.end(); ++it) {
            std::string key = it.name();
            if (IsStandardAttribute(key)) continue;
            const Imf::Attribute &a = it.attribute();
            if (auto *s = dynamic_cast<const Imf::StringAttribute *>(&a))
                metadata[key] = s->value();
            else if (auto *i = dynamic_cast<const Imf::IntAttribute *>(&a))
                metadata[key] = MetaValue::Int(i->value());
            else if (auto *f = dynamic_cast<const Imf::FloatAttribute *>(&a))
                metadata[key] = MetaValue::Double(f->value());
            else if (auto *d = dynamic_cast<const Imf::DoubleAttribute *>(&a))
                metadata[key] = MetaValue::Double(d->value());
        }
    }
    if (sources.empty()) throw Error(filename + ": EXR file has no channels");
    std::stable_sort(sources.begin(), sources.end(), [](const Src &a, const Src &b) {
        std::string la = LayerOf(a.name), lb = LayerOf(b.name);
        if (la != lb) return la < lb;
        int ra = ChannelRank(a.name), rb = ChannelRank(b.name);
        if (ra != rb) return ra < rb;
        return a.name < b.name;
    });
    std::vector<std::string> names;
    for (const Src &s : sources) {
        if (std::find(names.begin(), names.end(), s.name) != names.end())
            throw Error(filename + ": duplicate channel \"" + s.name + "\" across EXR parts");
        names.push_back(s.name);
    }
    int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    CheckImageSize(filename, double(window.max.x) - window.min.x + 1, double(window.max.y) - window.min.y + 1,
                   double(names.size()));
    Image image(width, height, names);
    image.metadata = std::move(metadata);
    // A data window inside a larger display window (a crop) keeps its placement.
    if (!(display == window)) {
        image.originX = window.min.x - display.min.x;
        image.originY = window.min.y - display.min.y;
        image.displayWidth = display.max.x - display.min.x + 1;
        image.displayHeight = display.max.y - display.min.y + 1;
    }
    size_t nc = names.size();
    size_t xStride = nc * sizeof(float), yStride = size_t(width) * xStride;
    for (int p = 0; p < nparts; ++p) {
        Imf::FrameBuffer fb;
        bool any = false;
        const Imath::Box2i dw = file.header(p).dataWindow();
        for (size_t c = 0; c < nc; ++c) {
            if (sources[c].part != p) continue;
            char *base = reinterpret_cast<char *>(image.data().data() + c);
            fb.insert(sources[c].exrName,
                      Imf::Slice::Make(Imf::FLOAT, base, dw, xStride, yStride));
            any = true;
        }
        if (!any) continue;
        Imf::InputPart part(file, p);
        part.setFrameBuffer(fb);
        part.readPixels(dw.min.y, dw.max.y);
    }
    return image;
}

void WriteEXR(const std::string &filename, const Image &image) {
    const int dispW = image.displayWidth > 0 ? image.displayWidth : image.width();
    const int dispH = image.displayHeight > 0 ? image.displayHeight : image.height();
    const Imath::Box2i display({0, 0}, {dispW - 1, dispH - 1});
    const Imath::Box2i data({image.originX, image.originY},
                            {image.originX + image.width() - 1, image.originY + image.height() - 1});
    Imf::Header header(display, data);
    // PIZ: lossless, and on noisy float renders both faster and smaller than ZIP.
    header.compression() = Imf::PIZ_COMPRESSION;
    for (const auto &kv : image.metadata) {
        if (kv.first.empty()) throw Error(filename + ": empty metadata key");
        if (header.find(kv.first) != header.end() || IsStandardAttribute(kv.first))
            throw Error(filename + ": metadata key \"" + kv.first +
                        "\" collides with a standard EXR attribute");
        const MetaValue &v = kv.second;
        const double x = v.number();
        if (v.type() == MetaValue::Type::Int && x >= INT32_MIN && x <= INT32_MAX)
            header.insert(kv.first, Imf::IntAttribute(int(x)));
        else if (v.type() != MetaValue::Type::String)
            header.insert(kv.first, Imf::DoubleAttribute(x));
        else
            header.insert(kv.first, Imf::StringAttribute(v.str()));
    }
    Imf::FrameBuffer fb;
    size_t nc = size_t(image.numChannels());
    size_t xStride = nc * sizeof(float), yStride = size_t(image.width()) * xStride;
    for (size_t c = 0; c < nc; ++c) {
        const std::string &name = image.channelNames()[c];
        if (name.empty()) throw Error(filename + ": empty channel name");
        header.channels().insert(name, Imf::Channel(Imf::FLOAT));
        char *base = const_cast<char *>(reinterpret_cast<const char *>(image.data().data() + c));
        fb.insert(name, Imf::Slice::Make(Imf::FLOAT, base, data, xStride, yStride));
    }
    Imf::OutputFile out(filename.c_str(), header);
    out.setFrameBuffer(fb);
    out.writePixels(image.height());
}

// ---------------------------------------------------------------- PFM

Image ReadPFM(const std::string &filename, const std::vector<unsigned char> &bytes) {
    size_t pos = 0;
    auto skipSpace = [&] {
        while (pos < bytes.size() && std::isspace(bytes[pos])) ++pos;
    };
    auto token = [&] {
        skipSpace();
        std::string t;
        while (pos < bytes.size() && !std::isspace(bytes[pos])) t += char(bytes[pos++]);
        if (t.empty()) throw Error(filename + ": truncated PFM header");
        return t;
    };
    std::string magic = token();
    int nc = magic == "PF" ? 3 : magic == "Pf" ? 1 : 0;
    if (nc == 0) throw Error(filename + ": not a PFM file (bad magic)");
    long w = 0, h = 0;
    double scale = 0;
    try {
        size_t used;
        std::string tw = token(), th = token(), ts = token();
        w = std::stol(tw, &used);
        if (used != tw.size()) throw std::invalid_argument("w");
        h = std::stol(th, &used);
        if (used != th.size()) throw std::invalid_argument("h");
        scale = std::stod(ts, &used);
        if (used != ts.size()) throw std::invalid_argument("scale");
    } catch (const Error &) {
        throw;
    } catch (const std::exception &) {
        throw Error(filename + ": malformed PFM header");
    }
    if (w <= 0 || h <= 0 || w > (1 << 20) || h > (1 << 20) || scale == 0 || !std::isfinite(scale))
        throw Error(filename + ": invalid PFM size or scale");
    if (pos >= bytes.size() || !std::isspace(bytes[pos]))
        throw Error(filename + ": truncated PFM header");
    ++pos;  // the single whitespace after the scale
    size_t count = size_t(w) * size_t(h) * size_t(nc);
    if (bytes.size() - pos < count * 4)
        throw Error(filename + ": truncated PFM data (expected " + std::to_string(count * 4) +
                    " bytes, found " + std::to_string(bytes.size() - pos) + ")");
    bool swap = (scale < 0) != LittleEndianHost();
    float mult = float(std::fabs(scale));
    Image image(int(w), int(h),
                nc == 3 ? std::vector<std::string>{"R", "G", "B"} : std::vector<std::string>{"Y"});
    const unsigned char *src = bytes.data() + pos;
    for (long y = 0; y < h; ++y) {
        long row = h - 1 - y;  // PFM rows run bottom to top
        for (long i = 0; i < w * nc; ++i) {
            unsigned char b[4];
            std::memcpy(b, src + (size_t(y) * w * nc + i) * 4, 4);
            if (swap) {
                std::swap(b[0], b[3]);
                std::swap(b[1], b[2]);
            }
            float v;
            std::memcpy(&v, b, 4);
            if (mult != 1.f) v *= mult;
            image.data()[size_t(row) * w * nc + i] = v;
        }
    }
    return image;
}

void WritePFM(const std::string &filename, const Image &image) {
    Image rgb = image.layerRGB(DefaultRGBLayer(image));
    std::ofstream out(filename, std::ios::binary);
    if (!out) throw Error(filename + ": cannot open file for writing");
    out << "PF\n" << rgb.width() << " " << rgb.height() << "\n"
        << (LittleEndianHost() ? "-1" : "1") << "\n";
    size_t rowLen = size_t(rgb.width()) * 3;
    for (int y = rgb.height() - 1; y >= 0; --y)
        out.write(reinterpret_cast<const char *>(rgb.data().data() + size_t(y) * rowLen),
                  std::streamsize(rowLen * sizeof(float)));
    if (!out) throw Error(filename + ": write error");
}

// ---------------------------------------------------------------- PNG & co.

Image ReadSTB(const std::string &filename, const std::vector<unsigned char> &bytes, IntegerPixels ints) {
    if (bytes.size() > size_t(INT32_MAX)) throw Error(filename + ": file too large");
    const stbi_uc *buf = bytes.data();
    int len = int(bytes.size());
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(buf, len, &w, &h, &n))
        throw Error(filename + ": unrecognised or corrupt image file (" +
                    std::string(stbi_failure_reason()) + ")");
    std::vector<std::string> names = {"R", "G", "B"};  // grey is replicated
    if (n == 2 || n == 4) names.push_back("A");
    CheckImageSize(filename, w, h, double(names.size()));
    Image image;
    auto fill = [&](auto *pix, auto decodeColor, auto decodeAlpha) {
        image = Image(w, h, names);
        size_t npix = size_t(w) * size_t(h), nc = names.size();
        for (size_t p = 0; p < npix; ++p) {
            const auto *s = pix + p * n;
            float *d = image.data().data() + p * nc;
            if (n <= 2) {
                d[0] = d[1] = d[2] = decodeColor(s[0]);
                if (n == 2) d[3] = decodeAlpha(s[1]);
            } else {
                for (int c = 0; c < 3; ++c) d[c] = decodeColor(s[c]);
                if (n == 4) d[3] = decodeAlpha(s[3]);
            }
        }
    };
    auto fail = [&]() {
        throw Error(filename + ": cannot decode image (" + std::string(stbi_failure_reason()) +
                    ")");
    };
    if (stbi_is_hdr_from_memory(buf, len)) {
        int ww, hh, nn;
        float *pix = stbi_loadf_from_memory(buf, len, &ww, &hh, &nn, 0);
        if (!pix) fail();
        fill(pix, [](float v) { return v; }, [](float v) { return v; });
        stbi_image_free(pix);
    } else if (stbi_is_16_bit_from_memory(buf, len)) {
        int ww, hh, nn;
        stbi_us *pix = stbi_load_16_from_memory(buf, len, &ww, &hh, &nn, 0);
        if (!pix) fail();
        const bool decode = ints == IntegerPixels::SRGBDecoded;
        fill(pix, [decode](stbi_us v) { return decode ? SRGBToLinear(v / 65535.f) : v / 65535.f; },
             [](stbi_us v) { return v / 65535.f; });
        stbi_image_free(pix);
    } else {
        float lut[256];
        for (int i = 0; i < 256; ++i) lut[i] = ints == IntegerPixels::SRGBDecoded ? SRGBToLinear(i / 255.f) : i / 255.f;
        int ww, hh, nn;
        stbi_uc *pix = stbi_load_from_memory(buf, len, &ww, &hh, &nn, 0);
        if (!pix) fail();
        fill(pix, [&](stbi_uc v) { return lut[v]; }, [](stbi_uc v) { return v / 255.f; });
        stbi_image_free(pix);
    }
    return image;
}

unsigned char EncodeSRGB8(float v) {
    if (!(v > 0.f)) return 0;  // also maps NaN to 0
    if (v >= 1.f) return 255;
    return (unsigned char)std::lround(LinearToSRGB(v) * 255.f);
}

void WritePNG(const std::string &filename, const Image &image) {
    Image rgb = image.layerRGB(DefaultRGBLayer(image));
    std::vector<unsigned char> buf(rgb.data().size());
    for (size_t i = 0; i < buf.size(); ++i) buf[i] = EncodeSRGB8(rgb.data()[i]);
    png_image png;
    std::memset(&png, 0, sizeof(png));
    png.version = PNG_IMAGE_VERSION;
    png.width = png_uint_32(rgb.width());
    png.height = png_uint_32(rgb.height());
    png.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&png, filename.c_str(), 0, buf.data(), 0, nullptr)) {
        std::string msg = png.message;
        png_image_free(&png);
        throw Error(filename + ": cannot write PNG (" + msg + ")");
    }
}

}  // namespace

Image ReadImage(const std::string &filename, IntegerPixels ints) {
    try {
        unsigned char magic[4] = {0, 0, 0, 0};
        {
            std::ifstream in(filename, std::ios::binary);
            if (!in) throw Error(filename + ": cannot open file for reading");
            in.read(reinterpret_cast<char *>(magic), 4);
            if (in.gcount() == 0) throw Error(filename + ": empty file");
        }
        // Images read by a render (textures) are part of its provenance.
        if (magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01) {
            Image img = ReadEXR(filename);
            RecordInputFile(filename);
            return img;
        }
        std::vector<unsigned char> bytes = ReadWholeFile(filename);
        RecordInputFile(filename, bytes.data(), bytes.size());
        if (magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f'))
            return ReadPFM(filename, bytes);
        return ReadSTB(filename, bytes, ints);
    } catch (const Error &) {
        throw;
    } catch (const std::exception &e) {
        throw Error(filename + ": " + e.what());
    }
}

void CheckWritableImagePath(const std::string &filename) {
    std::string ext = Extension(filename);
    if (ext != "exr" && ext != "png" && ext != "pfm")
        throw Error(filename + ": unknown image extension \"" + ext + "\" (supported for writing: .exr, .png, .pfm)");
    size_t slash = filename.find_last_of('/');
    std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : filename.substr(0, slash));
    struct stat st;
    if (stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        throw Error(filename + ": output directory \"" + dir + "\" does not exist");
    if (access(dir.c_str(), W_OK) != 0) throw Error(filename + ": output directory \"" + dir + "\" is not writable");
}

void WriteImage(const std::string &filename, const Image &image) {
    if (image.width() <= 0 || image.height() <= 0 || image.numChannels() == 0)
        throw Error(filename + ": cannot write an empty image");
    std::string ext = Extension(filename);
    // Written to a temporary file beside the target, then renamed: a reader or
    // an interrupted write never sees a partial file.
    const std::string tmp = filename + ".tmp-" + std::to_string(getpid());
    try {
        if (ext == "exr")
            WriteEXR(tmp, image);
        else if (ext == "png")
            WritePNG(tmp, image);
        else if (ext == "pfm")
            WritePFM(tmp, image);
        else
            throw Error(filename + ": unknown image extension \"" + ext +
                        "\" (supported for writing: .exr, .png, .pfm)");
        if (std::rename(tmp.c_str(), filename.c_str()) != 0)
            throw Error(filename + ": cannot rename " + tmp + " into place: " + std::strerror(errno));
    } catch (const Error &e) {
        std::remove(tmp.c_str());
        std::string msg = e.what();
        if (msg.compare(0, tmp.size(), tmp) == 0) msg = filename + msg.substr(tmp.size());
        if (msg.compare(0, filename.size(), filename) == 0) throw Error(msg);
        throw Error(filename + ": " + msg);
    } catch (const std::exception &e) {
        std::remove(tmp.c_str());
        throw Error(filename + ": " + e.what());
    }
}

}  // namespace gradus
