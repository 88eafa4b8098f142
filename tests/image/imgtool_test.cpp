// End-to-end runs of the imgtool binary: exit codes, text and JSON output, files.
#include <gtest/gtest.h>

#include <Imath/half.h>
#include <cstring>
#include <sys/wait.h>
#include <zlib.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "job/checkpoint.h"
#include "render/film.h"
#include "image/image.h"
#include "test_util.h"

using namespace gradus;
using gradus_test::ReadBytes;
using gradus_test::TempDir;

namespace {

struct RunResult {
    int code;
    std::string out, err;
};

std::string Quote(const std::string &s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

RunResult RunTool(const TempDir &dir, const std::vector<std::string> &args) {
    std::string cmd = Quote(IMGTOOL_PATH);
    for (const std::string &a : args) cmd += " " + Quote(a);
    std::string o = dir.file("stdout.txt"), e = dir.file("stderr.txt");
    cmd += " >" + Quote(o) + " 2>" + Quote(e);
    int status = std::system(cmd.c_str());
    RunResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = ReadBytes(o);
    r.err = ReadBytes(e);
    return r;
}

Image Make(int w, int h, std::vector<float> v) {
    Image img = Image::RGB(w, h);
    img.data() = std::move(v);
    return img;
}

// The hand-worked pair of metrics_test: MSE 5.5/6, relMSE (5/1.001+250+0.25/1.001)/6.
struct Pair {
    std::string img, ref;
};
Pair WritePair(const TempDir &dir) {
    Pair p{dir.file("img.exr"), dir.file("ref.exr")};
    WriteImage(p.img, Make(2, 1, {1, 2, 3, 0.5f, 0.5f, 0.5f}));
    WriteImage(p.ref, Make(2, 1, {1, 1, 1, 0, 1, 0.5f}));
    return p;
}

}  // namespace

TEST(Imgtool, HelpAndBadUsage) {
    TempDir dir;
    RunResult h = RunTool(dir, {"--help"});
    EXPECT_EQ(h.code, 0);
    EXPECT_NE(h.out.find("relMSE"), std::string::npos);
    EXPECT_EQ(RunTool(dir, {}).code, 2);
    RunResult u = RunTool(dir, {"frobnicate"});
    EXPECT_EQ(u.code, 2);
    EXPECT_NE(u.err.find("unknown command"), std::string::npos);
    Pair p = WritePair(dir);
    RunResult o = RunTool(dir, {"diff", p.img, p.ref, "--no-such-option"});
    EXPECT_EQ(o.code, 2);
    EXPECT_NE(o.err.find("--no-such-option"), std::string::npos);
    EXPECT_EQ(RunTool(dir, {"diff", p.img}).code, 2);
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--metric", "ssim"}).code, 2);
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--tolerance", "abc"}).code, 2);
    RunResult missing = RunTool(dir, {"info", dir.file("missing.exr")});
    EXPECT_EQ(missing.code, 2);
    EXPECT_NE(missing.err.find("missing.exr"), std::string::npos);
    // Per-command help: that command's options only.
    RunResult dh = RunTool(dir, {"diff", "--help"});
    EXPECT_EQ(dh.code, 0);
    EXPECT_NE(dh.out.find("--ref-layer"), std::string::npos);
    EXPECT_EQ(dh.out.find("falsecolor"), std::string::npos);
    EXPECT_EQ(dh.out.find("--weights"), std::string::npos);
}

TEST(Imgtool, DiffJsonAndTolerance) {
    TempDir dir;
    Pair p = WritePair(dir);
    RunResult r = RunTool(dir, {"diff", p.img, p.ref, "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j["mse"].get<double>(), 5.5 / 6, 1e-7);
    EXPECT_NEAR(j["relmse"].get<double>(), (5.0 / 1.001 + 250.0 + 0.25 / 1.001) / 6, 1e-5);
    EXPECT_NEAR(j["mean_rel_diff"].get<double>(), 2.0 / 3.0, 1e-7);
    EXPECT_EQ(j["used_pixels"].get<int>(), 2);

    // relMSE is 42.54: a tolerance of 43 passes, 42 fails.
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--tolerance", "43"}).code, 0);
    RunResult f = RunTool(dir, {"diff", p.img, p.ref, "--tolerance", "42"});
    EXPECT_EQ(f.code, 1);
    EXPECT_NE(f.out.find("FAIL"), std::string::npos);
    // MSE 0.9167.
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--metric", "mse", "--tolerance", "0.92"}).code, 0);
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--metric=mse", "--tolerance=0.91"}).code, 1);
    // PSNR 0.378 dB: the tolerance is a lower bound.
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--metric", "psnr", "--tolerance", "0.3"}).code, 0);
    EXPECT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--metric", "psnr", "--tolerance", "0.4"}).code, 1);
    // Discarding the worst pixel leaves relMSE 5/1.001/3.
    RunResult d = RunTool(dir, {"diff", p.img, p.ref, "--discard-count", "1", "--json"});
    ASSERT_EQ(d.code, 0) << d.err;
    nlohmann::json jd = nlohmann::json::parse(d.out);
    EXPECT_EQ(jd["discarded_pixels"].get<int>(), 1);
    EXPECT_NEAR(jd["relmse"].get<double>(), 5.0 / 1.001 / 3, 1e-6);
    RunResult df = RunTool(dir, {"diff", p.img, p.ref, "--discard-fraction", "0.5", "--json"});
    ASSERT_EQ(df.code, 0) << df.err;
    EXPECT_EQ(nlohmann::json::parse(df.out)["discarded_pixels"].get<int>(), 1);
}

TEST(Imgtool, DiffSizeMismatchNaNAndOutfile) {
    TempDir dir;
    Pair p = WritePair(dir);
    std::string big = dir.file("big.exr");
    WriteImage(big, Image::RGB(3, 1));
    RunResult m = RunTool(dir, {"diff", p.img, big});
    EXPECT_EQ(m.code, 2);
    EXPECT_NE(m.err.find("size mismatch"), std::string::npos);

    std::string nan = dir.file("nan.exr");
    WriteImage(nan, Make(2, 1, {NAN, 2, 3, 0.5f, 0.5f, 0.5f}));
    RunResult t = RunTool(dir, {"diff", nan, p.ref});
    EXPECT_EQ(t.code, 0);
    EXPECT_NE(t.out.find("1 NaN"), std::string::npos) << t.out;
    EXPECT_NE(t.out.find("excluded"), std::string::npos) << t.out;
    RunResult js = RunTool(dir, {"diff", nan, p.ref, "--json"});
    nlohmann::json j = nlohmann::json::parse(js.out);
    EXPECT_EQ(j["nonfinite_pixels"].get<int>(), 1);
    EXPECT_EQ(j["nan_values"]["image"].get<int>(), 1);
    EXPECT_NEAR(j["mse"].get<double>(), 0.5 / 3, 1e-7);

    std::string err = dir.file("err.exr");
    ASSERT_EQ(RunTool(dir, {"diff", p.img, p.ref, "--outfile", err}).code, 0);
    Image e = ReadImage(err);
    int rel = e.channelIndex("relmse");
    ASSERT_GE(rel, 0);
    EXPECT_NEAR(e.at(1, 0, rel), (250.0 + 0.25 / 1.001) / 3, 1e-3);
}

TEST(Imgtool, InfoJson) {
    TempDir dir;
    Image img(2, 2, {"R", "G", "B", "dx.R", "dx.G", "dx.B"});
    for (size_t i = 0; i < img.data().size(); ++i) img.data()[i] = float(i);
    img.at(1, 1, 4) = INFINITY;
    img.metadata["spp"] = "32";
    std::string f = dir.file("info.exr");
    WriteImage(f, img);
    RunResult r = RunTool(dir, {"info", f, "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["width"].get<int>(), 2);
    EXPECT_EQ(j["channels"].size(), 6u);
    EXPECT_EQ(j["metadata"]["spp"].get<std::string>(), "32");
    bool sawDx = false;
    for (const auto &l : j["layers"])
        if (l["name"] == "dx") {
            sawDx = true;
            EXPECT_EQ(l["inf"].get<int>(), 1);
            EXPECT_EQ(l["nan"].get<int>(), 0);
        }
    EXPECT_TRUE(sawDx);
    for (const auto &c : j["channel_stats"])
        if (c["name"] == "R") {
            // R values are 0, 6, 12, 18.
            EXPECT_DOUBLE_EQ(c["min"].get<double>(), 0);
            EXPECT_DOUBLE_EQ(c["max"].get<double>(), 18);
            EXPECT_DOUBLE_EQ(c["mean"].get<double>(), 9);
        }
    RunResult t = RunTool(dir, {"info", f});
    EXPECT_EQ(t.code, 0);
    EXPECT_NE(t.out.find("spp = 32"), std::string::npos);
}

TEST(Imgtool, ConvertMergeFalsecolor) {
    TempDir dir;
    Image img(2, 1, {"R", "G", "B", "primal.R", "primal.G", "primal.B"});
    img.data() = {0.25f, 0.5f, 1, 3, 4, 5, 0, 0.125f, 2, 6, 7, 8};
    std::string in = dir.file("in.exr");
    WriteImage(in, img);
    std::string pfm = dir.file("out.pfm");
    ASSERT_EQ(RunTool(dir, {"convert", in, pfm, "--exposure", "1", "--scale", "0.5"}).code, 0);
    EXPECT_EQ(ReadImage(pfm).data(), Make(2, 1, {0.25f, 0.5f, 1, 0, 0.125f, 2}).data());
    ASSERT_EQ(RunTool(dir, {"convert", in, pfm, "--layer", "primal", "--exposure", "-1"}).code, 0);
    EXPECT_EQ(ReadImage(pfm).at(1, 0, 2), 4.f);
    std::string png = dir.file("out.png");
    ASSERT_EQ(RunTool(dir, {"convert", in, png}).code, 0);
    Image p = ReadImage(png);
    EXPECT_NEAR(p.at(0, 0, 1), 0.5f, 0.01f);
    EXPECT_FLOAT_EQ(p.at(1, 0, 2), 1.f);  // clamped
    EXPECT_EQ(RunTool(dir, {"convert", in, dir.file("out.bmp")}).code, 2);

    Image a = Make(1, 1, {1, 1, 1}), b = Make(1, 1, {3, 3, 3});
    a.metadata["spp"] = "10";
    b.metadata["spp"] = "30";
    std::string fa = dir.file("a.exr"), fb = dir.file("b.exr"), out = dir.file("m.exr");
    WriteImage(fa, a);
    WriteImage(fb, b);
    ASSERT_EQ(RunTool(dir, {"merge", out, fa, fb}).code, 0);
    Image m = ReadImage(out);
    EXPECT_NEAR(m.at(0, 0, 0), 2.5f, 1e-6f);
    EXPECT_EQ(m.metadata.at("spp"), "40");
    ASSERT_EQ(RunTool(dir, {"merge", out, fa, fb, "--weights", "1,1"}).code, 0);
    EXPECT_NEAR(ReadImage(out).at(0, 0, 0), 2.f, 1e-6f);
    EXPECT_EQ(RunTool(dir, {"merge", out, fa, fb, "--weights", "1"}).code, 2);
    std::string big = dir.file("big.exr");
    WriteImage(big, Image::RGB(2, 1));
    RunResult mm = RunTool(dir, {"merge", out, fa, big});
    EXPECT_EQ(mm.code, 2);
    EXPECT_NE(mm.err.find("2x1"), std::string::npos) << mm.err;

    std::string fc = dir.file("fc.png");
    ASSERT_EQ(RunTool(dir, {"falsecolor", fb, fa, fc, "--max", "1"}).code, 0);
    Image c = ReadImage(fc);
    EXPECT_EQ(c.width(), 1);
    EXPECT_NEAR(c.at(0, 0, 0), 1.f, 1e-6f);  // relMSE 4/1.001 > max: white
}

// Cross-check on the pbrt-v3 Cornell box pair: the README gives MSE 1.05921e-05 for
// ref_q against ref (pbrt-v3's own imgtool) and ref.noise = relMSE / 5.
TEST(Imgtool, CornellReferencePair) {
    const std::string dirRef = std::string(GRADUS_SOURCE_DIR) + "/../shared/references/cornell-box/";
    if (!std::ifstream(dirRef + "ref_q.exr") || !std::ifstream(dirRef + "ref.exr"))
        GTEST_SKIP() << "cornell-box references not present";
    TempDir dir;
    RunResult r = RunTool(dir, {"diff", dirRef + "ref_q.exr", dirRef + "ref.exr", "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    nlohmann::json j = nlohmann::json::parse(r.out);
    EXPECT_NEAR(j["mse"].get<double>(), 1.05921e-05, 1e-9);
    EXPECT_NEAR(j["mean_rel_diff"].get<double>() * 100, -0.009891, 1e-5);
    double noise = std::stod(ReadBytes(dirRef + "ref.noise"));
    EXPECT_NEAR(j["relmse"].get<double>() / 5, noise, 0.01 * noise);
}

// merge records its inputs, sums spp and render time, and refuses renders
// that share a seed unless told otherwise.
TEST(Imgtool, MergeProvenanceAndEqualSeeds) {
    TempDir dir;
    Image a = Make(1, 1, {1, 1, 1}), b = Make(1, 1, {3, 3, 3});
    a.metadata["spp"] = MetaValue::Int(10);
    b.metadata["spp"] = MetaValue::Int(30);
    a.metadata["render_seconds"] = MetaValue::Double(1.5);
    b.metadata["render_seconds"] = MetaValue::Double(2.0);
    a.metadata["seed"] = "1";
    b.metadata["seed"] = "1";
    std::string fa = dir.file("a.exr"), fb = dir.file("b.exr"), out = dir.file("m.exr");
    WriteImage(fa, a);
    WriteImage(fb, b);
    RunResult same = RunTool(dir, {"merge", out, fa, fb});
    EXPECT_EQ(same.code, 2);
    EXPECT_NE(same.err.find("same seed"), std::string::npos) << same.err;
    ASSERT_EQ(RunTool(dir, {"merge", out, fa, fb, "--allow-equal-seeds"}).code, 0);
    b.metadata["seed"] = "2";
    WriteImage(fb, b);
    ASSERT_EQ(RunTool(dir, {"merge", out, fa, fb}).code, 0);
    Image m = ReadImage(out);
    EXPECT_EQ(m.metadata.at("spp"), "40");
    EXPECT_EQ(m.metadata.at("render_seconds").number(), 3.5);
    EXPECT_NE(m.metadata.at("merged_inputs").str().find("a.exr (seed 1)"), std::string::npos);
    EXPECT_NE(m.metadata.at("merged_inputs").str().find("b.exr (seed 2)"), std::string::npos);
    EXPECT_EQ(m.metadata.count("seed"), 0u);
}

// --ref-layer picks the reference's layer independently of --layer.
TEST(Imgtool, DiffRefLayer) {
    TempDir dir;
    Image img = Make(2, 1, {1, 1, 1, 2, 2, 2});
    Image ref = Make(2, 1, {0, 0, 0, 0, 0, 0});
    ref.setLayerRGB("truth", Make(2, 1, {1, 1, 1, 2, 2, 2}));
    std::string fi = dir.file("i.exr"), fr = dir.file("r.exr");
    WriteImage(fi, img);
    WriteImage(fr, ref);
    RunResult r = RunTool(dir, {"diff", fi, fr, "--ref-layer", "truth", "--metric", "mse", "--tolerance", "0"});
    EXPECT_EQ(r.code, 0) << r.out << r.err;
    EXPECT_EQ(RunTool(dir, {"diff", fi, fr, "--metric", "mse", "--tolerance", "0"}).code, 1);
}

// merge of partial checkpoints (gradus --passes): exact sums through the CLI,
// exit 2 with a message for a gap; info describes a checkpoint.
TEST(Imgtool, MergeCheckpoints) {
    TempDir dir;
    auto part = [](int a, int b, double v) {
        Checkpoint c;
        c.identity = "spp: 4\n";
        c.integrator = "path";
        c.passBegin = c.sppBegin = a;
        c.passEnd = c.sppEnd = b;
        c.complete = b == 4;
        // A film state of 2 x 1 pixels, no layers: header, then the doubles.
        const Float crop[4] = {0, 1, 0, 1};
        Film film(Point2i{2, 1}, crop, CreateFilter(EntityDesc()), "x.exr", 1);
        // All four arrays (sums, weights, splats, counts) set to v: tag 1 and the doubles.
        std::string s = film.saveState();
        s.resize(s.size() - 4);
        for (size_t count : {6, 2, 6, 2}) {
            s.push_back(1);
            for (size_t i = 0; i < count; ++i) s.append(reinterpret_cast<const char *>(&v), 8);
        }
        c.film = s;
        return c;
    };
    WriteCheckpoint(dir.file("a.ckpt"), part(0, 1, 1));
    WriteCheckpoint(dir.file("b.ckpt"), part(1, 3, 2));
    WriteCheckpoint(dir.file("c.ckpt"), part(3, 4, 4));
    RunResult r = RunTool(dir, {"merge", dir.file("m.ckpt"), dir.file("c.ckpt"), dir.file("a.ckpt"), dir.file("b.ckpt")});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("complete"), std::string::npos) << r.out;
    Checkpoint m = ReadCheckpoint(dir.file("m.ckpt"));
    EXPECT_EQ(m.passEnd, 4);
    EXPECT_EQ(m.film, part(0, 4, 7).film);
    r = RunTool(dir, {"info", dir.file("m.ckpt")});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("passes: [0, 4)"), std::string::npos) << r.out;
    r = RunTool(dir, {"merge", dir.file("g.ckpt"), dir.file("a.ckpt"), dir.file("c.ckpt")});
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("gap"), std::string::npos) << r.err;
}

namespace {

// data.js of a comparison page: "window.GRADUS_COMPARE = {...};".
nlohmann::json ReadPageData(const std::string &file) {
    std::string s = ReadBytes(file);
    size_t a = s.find('{'), b = s.rfind('}');
    if (a == std::string::npos || b == std::string::npos) return nlohmann::json();
    return nlohmann::json::parse(s.substr(a, b - a + 1));
}

// The RGB floats of an img-K.js: base64 of zlib data of half floats, planes
// R, G, B, low bytes then high bytes.
std::vector<float> ReadPageImage(const std::string &file, size_t npix) {
    std::string s = ReadBytes(file);
    size_t a = s.find("= \""), b = s.rfind('"');
    std::string b64 = s.substr(a + 3, b - a - 3);
    std::vector<unsigned char> packed;
    uint32_t acc = 0;
    int bits = 0;
    for (char c : b64) {
        const char *alpha = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        const char *p = c == '=' ? nullptr : std::strchr(alpha, c);
        if (!p) break;
        acc = (acc << 6) | uint32_t(p - alpha);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            packed.push_back((unsigned char)((acc >> bits) & 0xff));
        }
    }
    size_t n = npix * 3;
    std::vector<unsigned char> raw(2 * n);
    uLongf len = uLongf(raw.size());
    if (uncompress(raw.data(), &len, packed.data(), uLong(packed.size())) != Z_OK || len != raw.size()) return {};
    std::vector<float> out(n);
    for (int c = 0; c < 3; ++c)
        for (size_t i = 0; i < npix; ++i) {
            size_t k = size_t(c) * npix + i;
            Imath::half h;
            h.setBits(uint16_t(raw[k] | (raw[n + k] << 8)));
            out[i * 3 + c] = float(h);
        }
    return out;
}

}  // namespace

TEST(Imgtool, ComparePageFilesMetricsAndData) {
    TempDir dir;
    Pair p = WritePair(dir);
    Image b = Make(2, 1, {1.5f, 1, 0.75f, 1e-3f, 7e4f, 0.5f});  // 7e4: beyond the half range
    b.metadata["integrator"] = "bdpt";
    b.metadata["spp"] = MetaValue::Int(16);
    b.metadata["render_seconds"] = MetaValue::Double(1.25);
    std::string fb = dir.file("b.exr"), page = dir.file("page");
    WriteImage(fb, b);
    RunResult r = RunTool(dir, {"compare", p.ref, p.img, fb, "-o", page, "--labels", "R,A,B", "--exposure", "1.5"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("index.html"), std::string::npos) << r.out;
    for (const char *f : {"index.html", "viewer.js", "viewer.css", "data.js", "img-0.js", "img-1.js", "img-2.js"})
        EXPECT_FALSE(ReadBytes(page + "/" + f).empty()) << f;
    EXPECT_NE(ReadBytes(page + "/index.html").find("viewer.js"), std::string::npos);

    nlohmann::json d = ReadPageData(page + "/data.js");
    ASSERT_TRUE(d.is_object());
    EXPECT_EQ(d["width"].get<int>(), 2);
    EXPECT_EQ(d["height"].get<int>(), 1);
    EXPECT_DOUBLE_EQ(d["exposure"].get<double>(), 1.5);
    ASSERT_EQ(d["images"].size(), 3u);
    EXPECT_EQ(d["images"][0]["label"], "R");
    EXPECT_TRUE(d["images"][0]["reference"].get<bool>());
    EXPECT_EQ(d["images"][2]["metadata"]["integrator"], "bdpt");
    EXPECT_EQ(d["images"][2]["metadata"]["spp"].get<int>(), 16);
    EXPECT_DOUBLE_EQ(d["images"][2]["metadata"]["render_seconds"].get<double>(), 1.25);
    // The figures are imgtool diff's, to the last bit.
    for (int k : {1, 2}) {
        RunResult j = RunTool(dir, {"diff", k == 1 ? p.img : fb, p.ref, "--json"});
        ASSERT_EQ(j.code, 0) << j.err;
        nlohmann::json dj = nlohmann::json::parse(j.out), m = d["images"][k]["metrics"];
        EXPECT_EQ(m["relmse"].get<double>(), dj["relmse"].get<double>());
        EXPECT_EQ(m["psnr"].get<double>(), dj["psnr"].get<double>());
        EXPECT_EQ(m["mse"].get<double>(), dj["mse"].get<double>());
        EXPECT_EQ(m["mean"].get<double>(), dj["mean_image"].get<double>());
    }
    EXPECT_NEAR(d["images"][1]["metrics"]["relmse"].get<double>(), (5.0 / 1.001 + 250.0 + 0.25 / 1.001) / 6, 1e-5);

    // The embedded pixels: the images as half floats (beyond the range: 65504).
    std::vector<float> px = ReadPageImage(page + "/img-2.js", 2);
    ASSERT_EQ(px.size(), 6u);
    for (int i = 0; i < 6; ++i) {
        float want = std::min(b.data()[i], 65504.f);
        EXPECT_NEAR(px[i], want, std::abs(want) * 1e-3f) << i;
    }
    EXPECT_EQ(ReadPageImage(page + "/img-0.js", 2), Make(2, 1, {1, 1, 1, 0, 1, 0.5f}).data());
}

TEST(Imgtool, ComparePageErrors) {
    TempDir dir;
    Pair p = WritePair(dir);
    std::string page = dir.file("page");
    auto fails = [&](const std::vector<std::string> &args, const std::string &msg) {
        RunResult r = RunTool(dir, args);
        EXPECT_EQ(r.code, 2) << r.out;
        EXPECT_NE(r.err.find(msg), std::string::npos) << r.err;
    };
    fails({"compare", p.ref, p.img}, "-o DIR");
    fails({"compare", p.ref, "-o", page}, "at least 2");
    fails({"compare", p.ref, dir.file("missing.exr"), "-o", page}, "missing.exr");
    fails({"compare", p.ref, p.img, "-o", page, "--labels", "a,b,c"}, "3 labels");
    fails({"compare", p.ref, p.img, "-o", page, "--layer", "primal"}, "primal");
    fails({"compare", p.ref, p.img, "-o", page, "--exposure", "x"}, "--exposure");
    fails({"compare", p.ref, p.img, "-o", page, "--error-max", "0"}, "--error-max");
    std::string big = dir.file("big.exr");
    WriteImage(big, Image::RGB(3, 1));
    fails({"compare", p.ref, p.img, big, "-o", page}, "size mismatch");
    // Nothing is written when an input is refused.
    EXPECT_FALSE(std::filesystem::exists(page));
    // A file where the folder should be.
    fails({"compare", p.ref, p.img, "-o", p.img}, "folder");
    RunResult h = RunTool(dir, {"compare", "--help"});
    EXPECT_EQ(h.code, 0);
    EXPECT_NE(h.out.find("relative-error"), std::string::npos);
}
