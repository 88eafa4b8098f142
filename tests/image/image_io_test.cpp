// Image container and file I/O: EXR/PNG/PFM round trips, format details, and
// readers rejecting damaged files with gradus::Error.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfOutputFile.h>
#include <gtest/gtest.h>
#include <png.h>

#include <Imath/half.h>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "common/png_test_util.h"
#include "core/error.h"
#include "image/image.h"
#include "test_util.h"

using namespace gradus;
using gradus_test::ReadBytes;
using gradus_test::TempDir;
using gradus_test::WriteBytes;

namespace {

// Expects `f` to throw gradus::Error whose message names `file`.
template <typename F>
void ExpectErrorNaming(F f, const std::string &file) {
    try {
        f();
        ADD_FAILURE() << "no gradus::Error thrown for " << file;
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    }
}

std::string FloatBytes(float v, bool bigEndian) {
    unsigned char b[4];
    std::memcpy(b, &v, 4);
    uint32_t one = 1;
    unsigned char first;
    std::memcpy(&first, &one, 1);
    bool hostLittle = first == 1;
    if (hostLittle == bigEndian) {
        std::swap(b[0], b[3]);
        std::swap(b[1], b[2]);
    }
    return std::string(reinterpret_cast<char *>(b), 4);
}

}  // namespace

// addChannels: one reallocation for many channels; names present already and
// repeated names are skipped, order is kept, data survives.
TEST(Image, AddChannelsAtOnce) {
    Image img(2, 2, {"R", "G", "B"});
    img.at(1, 1, 2) = 3.f;
    img.addChannels({"dx.R", "G", "dx.G", "dx.R", "dy.Y"});
    ASSERT_EQ(img.channelNames(), (std::vector<std::string>{"R", "G", "B", "dx.R", "dx.G", "dy.Y"}));
    EXPECT_EQ(img.at(1, 1, 2), 3.f);
    for (int c = 3; c < 6; ++c) EXPECT_EQ(img.at(1, 1, c), 0.f);
    EXPECT_EQ(Image::LayerRGBNames("dx"), (std::vector<std::string>{"dx.R", "dx.G", "dx.B"}));
    EXPECT_EQ(Image::LayerRGBNames(""), (std::vector<std::string>{"R", "G", "B"}));
    img.addChannels({});
    EXPECT_EQ(img.numChannels(), 6);
}

TEST(Image, ChannelsAndLayers) {
    Image img(3, 2, {"R", "G", "B"});
    img.at(2, 1, 1) = 5.f;
    int a = img.addChannel("primal.Y");
    EXPECT_EQ(a, 3);
    EXPECT_EQ(img.addChannel("G"), 1);
    EXPECT_EQ(img.at(2, 1, 1), 5.f);  // data survives re-interleaving
    EXPECT_EQ(img.at(2, 1, 3), 0.f);
    img.at(1, 0, 3) = 7.f;
    std::vector<std::string> layers = img.layers();
    ASSERT_EQ(layers.size(), 2u);
    EXPECT_EQ(layers[0], "");
    EXPECT_EQ(layers[1], "primal");
    Image y = img.layerRGB("primal");  // Y replicated
    for (int c = 0; c < 3; ++c) EXPECT_EQ(y.at(1, 0, c), 7.f);
    EXPECT_THROW(img.layerRGB("dx"), Error);

    Image rgb = Image::RGB(3, 2);
    rgb.at(0, 1, 2) = 9.f;
    img.setLayerRGB("dx", rgb);
    EXPECT_GE(img.channelIndex("dx.B"), 0);
    EXPECT_EQ(img.at(0, 1, img.channelIndex("dx.B")), 9.f);
    EXPECT_EQ(img.layerRGB("dx").at(0, 1, 2), 9.f);
    EXPECT_THROW(img.setLayerRGB("dy", Image::RGB(2, 2)), Error);
    EXPECT_THROW(Image(2, 2, {"R", "R"}), Error);
    EXPECT_EQ(DefaultRGBLayer(img), "");
    EXPECT_EQ(DefaultRGBLayer(Image(1, 1, {"primal.R", "primal.G", "primal.B"})), "primal");
    EXPECT_EQ(DefaultRGBLayer(Image(1, 1, {"dx.R", "dx.G", "dx.B", "primal.R", "primal.G",
                                           "primal.B"})),
              "primal");
    EXPECT_EQ(DefaultRGBLayer(Image(1, 1, {"a.Y", "b.R", "b.G", "b.B"})), "b");
    EXPECT_THROW(DefaultRGBLayer(Image(1, 1, {"depth"})), Error);
}

TEST(ImageIO, ExrRoundTripMultiLayerWithMetadata) {
    TempDir dir;
    std::vector<std::string> names = {"R", "G", "B", "primal.R", "primal.G", "primal.B",
                                      "dx.R", "dx.G", "dx.B", "sampleCount"};
    Image img(7, 5, names);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-100.f, 100.f);
    for (float &v : img.data()) v = u(rng);
    img.at(3, 4, 9) = 1e-30f;  // float32 must survive, half could not
    img.metadata["integrator"] = "gbdpt";
    img.metadata["spp"] = "64";
    std::string f = dir.file("multi.exr");
    WriteImage(f, img);
    Image back = ReadImage(f);
    ASSERT_EQ(back.width(), 7);
    ASSERT_EQ(back.height(), 5);
    ASSERT_EQ(back.numChannels(), int(names.size()));
    // R, G, B keep their order within a layer; unprefixed layer first.
    EXPECT_EQ(back.channelNames()[0], "R");
    EXPECT_EQ(back.channelNames()[1], "G");
    EXPECT_EQ(back.channelNames()[2], "B");
    for (size_t c = 0; c < names.size(); ++c) {
        int bc = back.channelIndex(names[c]);
        ASSERT_GE(bc, 0) << names[c];
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 7; ++x)
                ASSERT_EQ(back.at(x, y, bc), img.at(x, y, int(c))) << names[c] << x << "," << y;
    }
    EXPECT_EQ(back.metadata.at("integrator"), "gbdpt");
    EXPECT_EQ(back.metadata.at("spp"), "64");
}

TEST(ImageIO, ExrReadsHalfAndUintChannels) {
    TempDir dir;
    std::string f = dir.file("mixed.exr");
    const int w = 4, h = 3;
    std::vector<half> hv(w * h);
    std::vector<unsigned int> uv(w * h);
    for (int i = 0; i < w * h; ++i) {
        hv[i] = half(0.25f * i);
        uv[i] = 1000u + unsigned(i);
    }
    {
        Imf::Header header(w, h);
        header.channels().insert("Y", Imf::Channel(Imf::HALF));
        header.channels().insert("id", Imf::Channel(Imf::UINT));
        Imf::FrameBuffer fb;
        fb.insert("Y", Imf::Slice(Imf::HALF, (char *)hv.data(), sizeof(half), sizeof(half) * w));
        fb.insert("id", Imf::Slice(Imf::UINT, (char *)uv.data(), sizeof(unsigned), sizeof(unsigned) * w));
        Imf::OutputFile out(f.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(h);
    }
    Image img = ReadImage(f);
    ASSERT_EQ(img.numChannels(), 2);
    int y = img.channelIndex("Y"), id = img.channelIndex("id");
    ASSERT_GE(y, 0);
    ASSERT_GE(id, 0);
    EXPECT_EQ(img.at(3, 2, y), 0.25f * 11);
    EXPECT_EQ(img.at(1, 1, id), 1005.f);
    EXPECT_EQ(img.layerRGB("").at(3, 2, 1), 0.25f * 11);
}

// Multi-part files: channels of a named part get the part name as layer prefix
// (unless they already carry it); metadata of every part is kept.
TEST(ImageIO, ExrReadsMultiPartFiles) {
    TempDir dir;
    std::string f = dir.file("parts.exr");
    const int w = 3, h = 2;
    std::vector<float> a(w * h * 3), b(w * h);
    for (size_t i = 0; i < a.size(); ++i) a[i] = float(i);
    for (size_t i = 0; i < b.size(); ++i) b[i] = 100.f + float(i);
    {
        std::vector<Imf::Header> headers(2, Imf::Header(w, h));
        headers[0].setName("primal");
        headers[0].setType(Imf::SCANLINEIMAGE);
        for (const char *c : {"R", "G", "B"}) headers[0].channels().insert(c, Imf::Channel(Imf::FLOAT));
        headers[1].setName("dx");
        headers[1].setType(Imf::SCANLINEIMAGE);
        headers[1].channels().insert("dx.Y", Imf::Channel(Imf::FLOAT));
        Imf::MultiPartOutputFile out(f.c_str(), headers.data(), 2);
        Imf::OutputPart p0(out, 0), p1(out, 1);
        Imf::FrameBuffer fb0, fb1;
        const char *names[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c)
            fb0.insert(names[c], Imf::Slice(Imf::FLOAT, (char *)(a.data() + c), 3 * sizeof(float),
                                            3 * sizeof(float) * w));
        fb1.insert("dx.Y", Imf::Slice(Imf::FLOAT, (char *)b.data(), sizeof(float), sizeof(float) * w));
        p0.setFrameBuffer(fb0);
        p0.writePixels(h);
        p1.setFrameBuffer(fb1);
        p1.writePixels(h);
    }
    Image img = ReadImage(f);
    ASSERT_EQ(img.numChannels(), 4);
    int g = img.channelIndex("primal.G"), y = img.channelIndex("dx.Y");
    ASSERT_GE(g, 0);
    ASSERT_GE(y, 0);
    EXPECT_EQ(img.at(2, 1, g), float((1 * w + 2) * 3 + 1));
    EXPECT_EQ(img.at(2, 1, y), 100.f + float(1 * w + 2));
    EXPECT_EQ(DefaultRGBLayer(img), "primal");  // full RGB preferred over Y
}

TEST(ImageIO, PngRoundTripWithin8BitQuantisation) {
    TempDir dir;
    Image img = Image::RGB(16, 9);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (float &v : img.data()) v = u(rng);
    img.at(0, 0, 0) = 3.f;     // clamps to 1
    img.at(0, 0, 1) = -0.5f;   // clamps to 0
    img.at(0, 0, 2) = NAN;     // written as 0
    std::string f = dir.file("rt.png");
    WriteImage(f, img);
    Image back = ReadImage(f);
    ASSERT_EQ(back.width(), 16);
    ASSERT_EQ(back.height(), 9);
    ASSERT_EQ(back.numChannels(), 3);
    EXPECT_FLOAT_EQ(back.at(0, 0, 0), 1.f);
    EXPECT_EQ(back.at(0, 0, 1), 0.f);
    EXPECT_EQ(back.at(0, 0, 2), 0.f);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                if (x == 0 && y == 0) continue;
                // Within half a code value in the encoded domain.
                EXPECT_NEAR(LinearToSRGB(back.at(x, y, c)), LinearToSRGB(img.at(x, y, c)),
                            0.5f / 255 + 1e-5f);
            }
}

TEST(ImageIO, PngIsSRGBEncoded) {
    TempDir dir;
    // Write known 8-bit codes with libpng directly, read through ReadImage.
    std::string f = dir.file("codes.png");
    unsigned char px[3] = {0, 128, 255};
    ASSERT_TRUE(test::WritePngCodes(f, 1, 1, 3, px));
    Image img = ReadImage(f);
    EXPECT_EQ(img.at(0, 0, 0), 0.f);
    EXPECT_NEAR(img.at(0, 0, 1), 0.2158605f, 1e-6f);  // sRGB code 128
    EXPECT_FLOAT_EQ(img.at(0, 0, 2), 1.f);

    // And the writer encodes linear 0.2158605 as code 128 (read back raw by libpng).
    Image lin = Image::RGB(1, 1);
    lin.at(0, 0, 0) = 0.2158605f;
    lin.at(0, 0, 1) = 0.0031308f * 0.5f;  // linear segment: 12.92 * v * 255 = 5.16 -> 5
    lin.at(0, 0, 2) = 0.5f;               // 0.7353569 * 255 = 187.5 -> 188
    std::string g = dir.file("lin.png");
    WriteImage(g, lin);
    png_image rd;
    std::memset(&rd, 0, sizeof(rd));
    rd.version = PNG_IMAGE_VERSION;
    ASSERT_TRUE(png_image_begin_read_from_file(&rd, g.c_str()));
    rd.format = PNG_FORMAT_RGB;
    unsigned char raw[3];
    ASSERT_TRUE(png_image_finish_read(&rd, nullptr, raw, 0, nullptr));
    EXPECT_EQ(raw[0], 128);
    EXPECT_EQ(raw[1], 5);
    EXPECT_EQ(raw[2], 188);
}

// IntegerPixels::Stored: the file's codes over 255, as pbrt-v3's ReadImage hands
// PNG maps to its lights; alpha is the stored value in both modes.
TEST(ImageIO, PngStoredValuesWithoutSRGBDecoding) {
    TempDir dir;
    std::string f = dir.file("codes.png");
    const unsigned char px[8] = {0, 1, 60, 90, 128, 200, 254, 255};  // two RGBA pixels
    ASSERT_TRUE(test::WritePngCodes(f, 2, 1, 4, px));
    const Image stored = ReadImage(f, IntegerPixels::Stored), decoded = ReadImage(f);
    for (int x = 0; x < 2; ++x)
        for (int c = 0; c < 4; ++c) {
            const float code = px[4 * x + c] / 255.f;
            EXPECT_EQ(stored.at(x, 0, c), code) << x << " " << c;
            // sRGB (IEC 61966-2-1) decoding of the colour channels by default.
            const float srgb = code <= 0.04045f ? code / 12.92f : std::pow((code + 0.055f) / 1.055f, 2.4f);
            EXPECT_NEAR(decoded.at(x, 0, c), c == 3 ? code : srgb, 1e-6f) << x << " " << c;
        }
    EXPECT_NEAR(decoded.at(1, 0, 0), 0.2158605f, 1e-6f);  // code 128
}

// ResampleToPowerOfTwo against the convolution it stands for, summed here over
// every source texel (the image repeating): output texel (X, Y) of W x H has its
// centre at ((X + 1/2) w / W, (Y + 1/2) h / H) in source texels, the kernel is
// k(d) = sinc(pi d) sinc(pi d / 2) for |d| < 2, normalised per axis, and the
// result is clamped at 0 (pbrt-v3, mipmap.h, MIPMap::MIPMap and resampleWeights).
TEST(Image, ResampleToPowerOfTwoIsTheLanczosConvolution) {
    auto sinc = [](double x) { return x == 0 ? 1.0 : std::sin(x) / x; };
    auto k = [&](double d) { return std::abs(d) < 2 ? sinc(M_PI * d) * sinc(M_PI * d / 2) : 0.0; };
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0, 1);
    for (auto [w, h] : {std::pair{6, 3}, std::pair{5, 8}, std::pair{3, 5}}) {
        Image img(w, h, {"R", "G", "B", "A"});
        for (float &v : img.data()) v = u(rng) < 0.3f ? 0.f : u(rng);  // edges: negative lobes get clamped
        img.metadata["note"] = "kept";
        const Image out = ResampleToPowerOfTwo(img);
        int W = 1, H = 1;
        while (W < w) W *= 2;
        while (H < h) H *= 2;
        ASSERT_EQ(out.width(), W);
        ASSERT_EQ(out.height(), H);
        ASSERT_EQ(out.channelNames(), img.channelNames());
        EXPECT_EQ(out.metadata.at("note"), std::string("kept"));
        int clamped = 0;
        for (int Y = 0; Y < H; ++Y)
            for (int X = 0; X < W; ++X)
                for (int c = 0; c < 4; ++c) {
                    const double cx = (X + 0.5) * w / W, cy = (Y + 0.5) * h / H;
                    double sum = 0, kx = 0, ky = 0;
                    for (int a = -3 * w; a < 4 * w; ++a) kx += k(a + 0.5 - cx);
                    for (int b = -3 * h; b < 4 * h; ++b) ky += k(b + 0.5 - cy);
                    for (int b = -3 * h; b < 4 * h; ++b)
                        for (int a = -3 * w; a < 4 * w; ++a) {
                            const double wt = k(a + 0.5 - cx) * k(b + 0.5 - cy);
                            if (wt != 0) sum += wt * img.at(((a % w) + w) % w, ((b % h) + h) % h, c);
                        }
                    const double expect = std::max(0.0, sum / (kx * ky));
                    clamped += sum < 0;
                    EXPECT_NEAR(out.at(X, Y, c), expect, 1e-6) << w << "x" << h << " at " << X << " " << Y << " " << c;
                }
        if (W != w) {
            EXPECT_GT(clamped, 0) << w << "x" << h << ": no clamped texel exercised";
        }
    }
    // Powers of two are left as they are.
    Image p2(4, 2, {"R", "G", "B"});
    for (float &v : p2.data()) v = u(rng) - 0.5f;
    EXPECT_EQ(ResampleToPowerOfTwo(p2).data(), p2.data());
}

TEST(ImageIO, PfmRoundTripExact) {
    TempDir dir;
    Image img = Image::RGB(5, 3);
    for (size_t i = 0; i < img.data().size(); ++i) img.data()[i] = float(i) * 0.37f - 2.f;
    img.at(4, 2, 0) = 18602.5f;
    std::string f = dir.file("rt.pfm");
    WriteImage(f, img);
    Image back = ReadImage(f);
    ASSERT_EQ(back.width(), 5);
    ASSERT_EQ(back.height(), 3);
    EXPECT_EQ(back.data(), img.data());
    // The file stores the bottom row first.
    std::string bytes = ReadBytes(f);
    size_t header = bytes.find('\n', bytes.find('\n', 3) + 1) + 1;
    float first;
    std::memcpy(&first, bytes.data() + header, 4);  // written in host order
    EXPECT_EQ(first, img.at(0, 2, 0));
}

TEST(ImageIO, PfmReadsBothEndiannessesAndGrey) {
    TempDir dir;
    // 2x2 colour, big-endian (positive scale); rows bottom to top.
    std::string be = "PF\n2 2\n1.0\n";
    for (int i = 0; i < 12; ++i) be += FloatBytes(float(i), true);
    WriteBytes(dir.file("be.pfm"), be);
    Image a = ReadImage(dir.file("be.pfm"));
    ASSERT_EQ(a.numChannels(), 3);
    EXPECT_EQ(a.at(0, 1, 0), 0.f);   // first stored pixel is bottom-left
    EXPECT_EQ(a.at(1, 1, 2), 5.f);
    EXPECT_EQ(a.at(0, 0, 0), 6.f);   // second stored row is the top one
    EXPECT_EQ(a.at(1, 0, 2), 11.f);

    // Same data little-endian with |scale| 2: values are scaled.
    std::string le = "PF\n2 2\n-2.0\n";
    for (int i = 0; i < 12; ++i) le += FloatBytes(float(i), false);
    WriteBytes(dir.file("le.pfm"), le);
    Image b = ReadImage(dir.file("le.pfm"));
    EXPECT_EQ(b.at(1, 0, 2), 22.f);
    EXPECT_EQ(b.at(0, 1, 1), 2.f);

    // Greyscale "Pf" gives one Y channel.
    std::string grey = "Pf\n3 1\n-1\n";
    for (int i = 0; i < 3; ++i) grey += FloatBytes(0.5f * i, false);
    WriteBytes(dir.file("g.pfm"), grey);
    Image g = ReadImage(dir.file("g.pfm"));
    ASSERT_EQ(g.numChannels(), 1);
    EXPECT_EQ(g.channelNames()[0], "Y");
    EXPECT_EQ(g.at(2, 0, 0), 1.f);
    EXPECT_EQ(g.layerRGB("").at(2, 0, 1), 1.f);
}

TEST(ImageIO, ReadersRejectDamagedFiles) {
    TempDir dir;
    Image img = Image::RGB(64, 64);
    for (size_t i = 0; i < img.data().size(); ++i) img.data()[i] = float(i % 97) / 97.f;
    WriteImage(dir.file("ok.exr"), img);
    WriteImage(dir.file("ok.png"), img);
    WriteImage(dir.file("ok.pfm"), img);
    for (std::string ext : {"exr", "png", "pfm"}) {
        std::string bytes = ReadBytes(dir.file("ok." + ext));
        ASSERT_GT(bytes.size(), 100u);
        for (size_t keep : {size_t(2), size_t(20), bytes.size() / 2, bytes.size() - 10}) {
            std::string f = dir.file("cut" + std::to_string(keep) + "." + ext);
            WriteBytes(f, bytes.substr(0, keep));
            ExpectErrorNaming([&] { ReadImage(f); }, f);
        }
    }
    std::string garbage = dir.file("garbage.exr");
    WriteBytes(garbage, std::string("this is not an image at all, just text\n"));
    ExpectErrorNaming([&] { ReadImage(garbage); }, garbage);
    std::string badExr = dir.file("bad-magic.exr");
    WriteBytes(badExr, std::string("\x76\x2f\x31\x01", 4) + std::string(200, '\xff'));
    ExpectErrorNaming([&] { ReadImage(badExr); }, badExr);
    std::string badPfm = dir.file("bad.pfm");
    WriteBytes(badPfm, "PF\n-3 2\n-1\n");
    ExpectErrorNaming([&] { ReadImage(badPfm); }, badPfm);
    std::string empty = dir.file("empty.png");
    WriteBytes(empty, "");
    ExpectErrorNaming([&] { ReadImage(empty); }, empty);
    std::string missing = dir.file("does-not-exist.exr");
    ExpectErrorNaming([&] { ReadImage(missing); }, missing);
}

// OpenEXR allocates what an attribute size claims before reading it: a string
// attribute claiming 2 GB in a file of a few hundred bytes must be refused by
// the header walk (message "claims"), not allocated (fuzz_image finding).
TEST(ImageIO, ExrAttributeSizeBeyondFileIsRefused) {
    TempDir dir;
    Image img = Image::RGB(4, 4);
    img.metadata["note"] = std::string("hello");
    WriteImage(dir.file("ok.exr"), img);
    std::string bytes = ReadBytes(dir.file("ok.exr"));
    const std::string key = std::string("note\0string\0", 12);
    size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    ASSERT_EQ(bytes.substr(at + key.size() + 4, 5), "hello");
    std::string bomb = bytes;
    bomb.replace(at + key.size(), 4, std::string("\xff\xff\xff\x7f", 4));
    std::string f = dir.file("bomb.exr");
    WriteBytes(f, bomb);
    try {
        ReadImage(f);
        ADD_FAILURE() << "no error for an attribute claiming 2 GB";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("\"note\" claims 2147483647 bytes"), std::string::npos) << e.what();
    }
    // The unmodified file passes the same walk.
    EXPECT_NO_THROW(CheckEXRHeaders(dir.file("ok.exr")));
    EXPECT_EQ(ReadImage(dir.file("ok.exr")).metadata.at("note").str(), "hello");
}

TEST(ImageIO, WriterErrors) {
    TempDir dir;
    Image img = Image::RGB(2, 2);
    std::string f = dir.file("x.tiff");
    ExpectErrorNaming([&] { WriteImage(f, img); }, f);
    std::string g = dir.file("no-such-dir/x.exr");
    ExpectErrorNaming([&] { WriteImage(g, img); }, g);
    Image bad = img;
    bad.metadata["channels"] = "oops";
    std::string h = dir.file("meta.exr");
    ExpectErrorNaming([&] { WriteImage(h, bad); }, h);
    Image noRGB(2, 2, {"depth", "id"});
    std::string p = dir.file("norgb.png");
    ExpectErrorNaming([&] { WriteImage(p, noRGB); }, p);
    EXPECT_NO_THROW(WriteImage(dir.file("norgb.exr"), noRGB));
}

TEST(ImageIO, TypedMetadataAndCropPlacementRoundTrip) {
    TempDir dir;
    Image img = Image::RGB(3, 2);
    img.at(2, 1, 0) = 5;
    img.metadata["scene"] = "a scene";
    img.metadata["spp"] = MetaValue::Int(64);
    img.metadata["seconds"] = MetaValue::Double(1.25);
    img.metadata["big"] = MetaValue::Int(int64_t(1) << 40);  // beyond an EXR int: written as double
    img.originX = 5, img.originY = 7, img.displayWidth = 16, img.displayHeight = 12;
    std::string f = dir.file("typed.exr");
    WriteImage(f, img);
    Image back = ReadImage(f);
    EXPECT_EQ(back.metadata.at("scene").type(), MetaValue::Type::String);
    EXPECT_EQ(back.metadata.at("spp").type(), MetaValue::Type::Int);
    EXPECT_EQ(back.metadata.at("spp"), "64");
    EXPECT_EQ(back.metadata.at("seconds").type(), MetaValue::Type::Double);
    EXPECT_EQ(back.metadata.at("seconds").number(), 1.25);
    EXPECT_EQ(back.metadata.at("big").number(), double(int64_t(1) << 40));
    EXPECT_EQ(back.width(), 3);
    EXPECT_EQ(back.originX, 5);
    EXPECT_EQ(back.originY, 7);
    EXPECT_EQ(back.displayWidth, 16);
    EXPECT_EQ(back.displayHeight, 12);
    EXPECT_EQ(back.at(2, 1, 0), 5.0f);
    // The EXR windows themselves: data window inside the display window.
    Imf::InputFile in(f.c_str());
    EXPECT_EQ(in.header().dataWindow().min.x, 5);
    EXPECT_EQ(in.header().dataWindow().max.y, 8);
    EXPECT_EQ(in.header().displayWindow().max.x, 15);
}

TEST(ImageIO, WritesAreAtomic) {
    TempDir dir;
    std::string f = dir.file("out.exr");
    Image a = Image::RGB(2, 2);
    a.at(0, 0, 0) = 1;
    WriteImage(f, a);
    // A failing write (a metadata key that collides with a standard attribute)
    // leaves the previous file intact and no temporary file behind.
    Image bad = a;
    bad.at(0, 0, 0) = 2;
    bad.metadata["channels"] = "oops";
    EXPECT_THROW(WriteImage(f, bad), Error);
    EXPECT_EQ(ReadImage(f).at(0, 0, 0), 1.0f);
    int files = 0;
    for (const auto &e : std::filesystem::directory_iterator(std::filesystem::path(f).parent_path())) {
        (void)e;
        ++files;
    }
    EXPECT_EQ(files, 1);
}

TEST(ImageIO, OutputPathIsCheckedBeforeWriting) {
    TempDir dir;
    EXPECT_NO_THROW(CheckWritableImagePath(dir.file("x.exr")));
    EXPECT_NO_THROW(CheckWritableImagePath(dir.file("x.png")));
    ExpectErrorNaming([&] { CheckWritableImagePath(dir.file("x.tiff")); }, dir.file("x.tiff"));
    ExpectErrorNaming([&] { CheckWritableImagePath(dir.file("nope/x.exr")); }, dir.file("nope/x.exr"));
    EXPECT_THROW(CheckWritableImagePath("/nonexistent/x.exr"), Error);
}

// The pbrt-v3 Cornell box reference: mean RGB matches ref.info.txt.
TEST(ImageIO, CornellReferenceMean) {
    const std::string f = std::string(GRADUS_SOURCE_DIR) + "/../shared/references/cornell-box/ref.exr";
    if (!std::filesystem::exists(f)) GTEST_SKIP() << f << " not present";
    Image img = ReadImage(f);
    ASSERT_EQ(img.width(), 256);
    ASSERT_EQ(img.height(), 256);
    Image rgb = img.layerRGB("");
    double sum[3] = {0, 0, 0};
    for (int y = 0; y < rgb.height(); ++y)
        for (int x = 0; x < rgb.width(); ++x)
            for (int c = 0; c < 3; ++c) sum[c] += rgb.at(x, y, c);
    double n = double(rgb.width()) * rgb.height();
    EXPECT_NEAR(sum[0] / n, 0.196299, 1e-4);
    EXPECT_NEAR(sum[1] / n, 0.127568, 1e-4);
    EXPECT_NEAR(sum[2] / n, 0.036110, 1e-4);
}

// PNM is not a format gradus reads (stb_image detects formats by content; its
// PNM header parser overflowed int on a long digit run: UBSan in the
// fuzz_image campaign). A PNM file under an image extension is refused.
TEST(ImageIO, PnmContentIsRefused) {
    TempDir dir;
    std::string f = dir.file("fake.png");
    {
        std::ofstream out(f, std::ios::binary);
        out << "P6\n2222222222222 1\n255\n" << std::string(16, 'x');
    }
    try {
        ReadImage(f);
        FAIL() << "a PNM file was read";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("fake.png"), std::string::npos) << e.what();
    }
}
