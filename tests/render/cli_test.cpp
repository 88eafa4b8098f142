// The gradus command line: located errors with exit status 1, successful
// renders with metadata, and Ctrl-C writing the partial image.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "image/image.h"
#include "render/cli_fixture.h"

namespace fs = std::filesystem;

namespace {

using gradus::test::RunResult;
using CliTest = gradus::test::GradusCliTest;

const char *kTiny =
    "LookAt 0 0 -3  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" [40]\n"
    "Film \"image\" \"integer xresolution\" [16] \"integer yresolution\" [16] \"string filename\" [\"tiny.exr\"]\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n"
    "Shape \"sphere\" \"float radius\" [1]\n"
    "WorldEnd\n";

}  // namespace

TEST_F(CliTest, RendersAndWritesMetadata) {
    write("tiny.pbrt", kTiny);
    RunResult r = run("tiny.pbrt --spp 2 --seed 5 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    gradus::Image img = gradus::ReadImage((dir_ / "tiny.exr").string());
    EXPECT_EQ(img.width(), 16);
    EXPECT_EQ(img.metadata["spp"], "2");
    EXPECT_EQ(img.metadata["seed"], "5");
    EXPECT_EQ(img.metadata["integrator"], "path");
    // The sphere's centre is lit head-on: non-zero.
    EXPECT_GT(img.at(8, 8, 0), 0.0f);
}

// Variance layers only with --variance (or a weighted reconstruction, which
// reads them); the other layers do not change; a checkpoint of one kind is not
// resumed as the other.
TEST_F(CliTest, VarianceLayersOnlyWhenAskedFor) {
    write("tiny.pbrt", kTiny);
    auto render = [&](const std::string &args, const std::string &out) {
        RunResult r = run("tiny.pbrt --integrator gpt --spp 2 --seed 3 --quiet --outfile " + out + " " + args);
        EXPECT_EQ(r.status, 0) << r.err;
        return gradus::ReadImage((dir_ / out).string());
    };
    auto has = [](const gradus::Image &img, const char *layer) {
        const std::vector<std::string> l = img.layers();
        return std::find(l.begin(), l.end(), layer) != l.end();
    };
    gradus::Image plain = render("", "plain.exr"), var = render("--variance", "var.exr");
    gradus::Image weighted = render("--param reconstruction=weighted", "weighted.exr");
    for (const char *l : {"primal_var", "dx_var", "dy_var"}) {
        EXPECT_FALSE(has(plain, l)) << l;
        EXPECT_TRUE(has(var, l)) << l;
        EXPECT_TRUE(has(weighted, l)) << l;
    }
    EXPECT_EQ(plain.metadata["variance_layers"], "0");
    EXPECT_EQ(var.metadata["variance_layers"], "1");
    for (const char *l : {"", "primal", "dx", "dy", "reconstructed_l1", "reconstructed_l2"})
        EXPECT_EQ(plain.layerRGB(l).data(), var.layerRGB(l).data()) << l;
    RunResult c = run("tiny.pbrt --integrator gpt --spp 2 --seed 3 --quiet --passes 0:1 --checkpoint part.ckpt");
    ASSERT_EQ(c.status, 0) << c.err;
    RunResult r = run("tiny.pbrt --integrator gpt --spp 2 --seed 3 --quiet --variance --resume part.ckpt");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("variance layers"), std::string::npos) << r.err;
}

TEST_F(CliTest, OutfileAndCropWindow) {
    write("tiny.pbrt", kTiny);
    RunResult r = run("tiny.pbrt --spp 1 --quiet --outfile out.pfm --cropwindow 0.25 0.75 0 0.5");
    ASSERT_EQ(r.status, 0) << r.err;
    gradus::Image img = gradus::ReadImage((dir_ / "out.pfm").string());
    EXPECT_EQ(img.width(), 8);
    EXPECT_EQ(img.height(), 8);
}

TEST_F(CliTest, UnknownDirectiveIsLocated) {
    write("bad.pbrt", "Camera \"perspective\"\nWorldBegin\n  Shpe \"sphere\"\nWorldEnd\n");
    RunResult r = run("bad.pbrt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:3:3"), std::string::npos) << r.err;
}

TEST_F(CliTest, MisspeltParameterIsLocated) {
    write("bad.pbrt", "Camera \"perspective\" \"float fvo\" [45]\nWorldBegin\nWorldEnd\n");
    RunResult r = run("bad.pbrt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:1:22"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("fvo"), std::string::npos) << r.err;
}

TEST_F(CliTest, MalformedNumberIsLocated) {
    write("bad.pbrt", "WorldBegin\nShape \"sphere\" \"float radius\" [1.2.3]\nWorldEnd\n");
    RunResult r = run("bad.pbrt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:2:"), std::string::npos) << r.err;
}

TEST_F(CliTest, UnsupportedFeatureIsNamed) {
    // An area light on a curve (pbrt-v3 allows it; Gradus does not).
    write("bad.pbrt", "WorldBegin\nAreaLightSource \"diffuse\"\nShape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n");
    RunResult r = run("bad.pbrt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:2:1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not support"), std::string::npos) << r.err;
}

TEST_F(CliTest, UnknownIntegratorListsValidNames) {
    write("tiny.pbrt", kTiny);
    RunResult r = run("tiny.pbrt --integrator nosuch --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("path"), std::string::npos) << r.err;
}

TEST_F(CliTest, BadArgumentsExitOne) {
    EXPECT_EQ(run("").status, 1);
    EXPECT_EQ(run("missing.pbrt").status, 1);
    write("tiny.pbrt", kTiny);
    EXPECT_EQ(run("tiny.pbrt --bogus").status, 1);
    EXPECT_EQ(run("tiny.pbrt --spp abc").status, 1);
    EXPECT_EQ(run("tiny.pbrt --spp 0").status, 1);
}

TEST_F(CliTest, InterruptWritesPartialImage) {
    write("tiny.pbrt", kTiny);
    // Many samples; SIGINT after a moment must stop, write the image and exit 130.
    std::string errFile = (dir_ / "stderr.txt").string();
    std::string cmd = "cd '" + dir_.string() + "' && ( '" + GRADUS_BIN +
                      "' tiny.pbrt --spp 100000000 --quiet --nthreads 1 2> '" + errFile +
                      "' & pid=$!; sleep 1.5; kill -INT $pid; wait $pid; exit $? )";
    int st = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(st));
    EXPECT_EQ(WEXITSTATUS(st), 130);
    ASSERT_TRUE(fs::exists(dir_ / "tiny.exr"));
    gradus::Image img = gradus::ReadImage((dir_ / "tiny.exr").string());
    EXPECT_GT(std::stoi(img.metadata["spp"]), 0);
    EXPECT_GT(img.at(8, 8, 0), 0.0f);
}

TEST_F(CliTest, TerminateWritesPartialImage) {
    write("tiny.pbrt", kTiny);
    std::string cmd = "cd '" + dir_.string() + "' && ( '" + GRADUS_BIN +
                      "' tiny.pbrt --spp 100000000 --quiet --nthreads 1 2> /dev/null & pid=$!; sleep 1.5; "
                      "kill -TERM $pid; wait $pid; exit $? )";
    int st = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(st));
    EXPECT_EQ(WEXITSTATUS(st), 130);
    ASSERT_TRUE(fs::exists(dir_ / "tiny.exr"));
    EXPECT_GT(std::stoi(gradus::ReadImage((dir_ / "tiny.exr").string()).metadata["spp"]), 0);
}

// --debugpixel re-runs one pixel's samples with the random numbers of the full
// render: with the box filter (radius 0.5) a pixel is the mean of its own
// samples' radiance, so the mean of the printed contributions must equal the
// pixel of the full multi-threaded render (up to the printed precision).
TEST_F(CliTest, DebugPixelReproducesThePixelOfTheFullRender) {
    write("tiny.pbrt", kTiny);
    ASSERT_EQ(run("tiny.pbrt --spp 8 --seed 4 --quiet --nthreads 2").status, 0);
    gradus::Image full = gradus::ReadImage((dir_ / "tiny.exr").string());
    fs::remove(dir_ / "tiny.exr");
    for (const char *integrator : {"path", "bdpt"}) {
        std::string out = (dir_ / "debug.txt").string();
        std::string cmd = "cd '" + dir_.string() + "' && '" + GRADUS_BIN + "' tiny.pbrt --spp 8 --seed 4 --integrator " +
                          integrator + " --debugpixel 9,6 > '" + out + "' 2> /dev/null";
        ASSERT_EQ(std::system(cmd.c_str()), 0) << integrator;
        EXPECT_FALSE(fs::exists(dir_ / "tiny.exr")) << "--debugpixel writes no image";
        std::ifstream in(out);
        std::string line;
        double sum[3] = {0, 0, 0};
        int samples = 0, radiance = 0, vertices = 0;
        while (std::getline(in, line)) {
            if (line.rfind("sample ", 0) == 0) ++samples;
            if (line.find("vertex") != std::string::npos || line.find("bounce") != std::string::npos) ++vertices;
            const std::string key = "radiance pixel (9, 6): ";
            size_t at = line.find(key);
            if (at == std::string::npos) continue;
            std::istringstream v(line.substr(at + key.size()));
            double r, g, b;
            v >> r >> g >> b;
            sum[0] += r, sum[1] += g, sum[2] += b;
            ++radiance;
        }
        EXPECT_EQ(samples, 8) << integrator;
        EXPECT_EQ(radiance, 8) << integrator;
        EXPECT_GT(vertices, 0) << integrator;
        if (std::string(integrator) == "path") {
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c] / 8, full.at(9, 6, c), 1e-6 * (1 + full.at(9, 6, c))) << c;
        }
    }
    // A single sample; a pixel outside the image and malformed values are errors.
    std::string cmd = "cd '" + dir_.string() + "' && '" + GRADUS_BIN +
                      "' tiny.pbrt --spp 8 --debugpixel 9,6,3 2> /dev/null | grep -c '^sample '";
    FILE *p = popen(cmd.c_str(), "r");
    char buf[16] = {0};
    ASSERT_TRUE(fgets(buf, sizeof buf, p));
    pclose(p);
    EXPECT_EQ(std::atoi(buf), 1);
    EXPECT_EQ(run("tiny.pbrt --debugpixel 100,3").status, 1);
    EXPECT_EQ(run("tiny.pbrt --debugpixel 3").status, 1);
    EXPECT_EQ(run("tiny.pbrt --debugpixel 3,4,x").status, 1);
}

// Hostile numbers fail with located messages before any allocation.
TEST_F(CliTest, HostileNumbersAreLocatedErrors) {
    std::string scene = kTiny;
    auto with = [&](const std::string &from, const std::string &to) {
        std::string s = scene;
        s.replace(s.find(from), from.size(), to);
        write("bad.pbrt", s);
        return run("bad.pbrt --quiet");
    };
    RunResult r = with("\"rgb I\" [5 5 5]", "\"rgb I\" [5 nan 5]");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:5:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("non-finite"), std::string::npos) << r.err;
    r = with("\"integer xresolution\" [16]", "\"integer xresolution\" [100000000]");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:3:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("xresolution"), std::string::npos) << r.err;
    // 2^17 x 2^17 pixels: 1 TiB of accumulators, more than any machine this runs on.
    r = with("\"integer xresolution\" [16] \"integer yresolution\" [16]",
             "\"integer xresolution\" [131072] \"integer yresolution\" [131072]");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:3:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("GiB"), std::string::npos) << r.err;
    // Beyond the ray tracer's range (Embree aborted on these before): refused with a location.
    r = with("\"float fov\" [40]", "\"float fov\" [40] \"float lensradius\" [0.5] \"float focaldistance\" [1e200]");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:2:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("focaldistance"), std::string::npos) << r.err;
    r = with("LookAt 0 0 -3", "LookAt 0 0 -1e19");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:2:1"), std::string::npos) << r.err;
    r = with("\"float radius\" [1]", "\"float radius\" [1e16]");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:6:1"), std::string::npos) << r.err;
    // A pixel filter a million pixels wide would sample the whole plane.
    r = with("WorldBegin", "PixelFilter \"box\" \"float ywidth\" [1e6]\nWorldBegin");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("bad.pbrt:4:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("ywidth"), std::string::npos) << r.err;
}

// pbrt-v3 features Gradus lacks are located errors, never dropped silently.
// Media render with path; an integrator without media support refuses them at
// the medium (no Integrator directive here), naming itself. Motion blur is a
// named error.
TEST_F(CliTest, MediaRefusalsAndMotionBlurAreNamedErrors) {
    write("media.pbrt",
          "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer xresolution\" [8] "
          "\"integer yresolution\" [8] \"string filename\" [\"media.exr\"]\nWorldBegin\n"
          "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
          "MediumInterface \"fog\" \"\"\nMaterial \"\"\nShape \"sphere\"\nWorldEnd\n");
    EXPECT_EQ(run("media.pbrt --quiet --spp 1").status, 0);
    RunResult r = run("media.pbrt --quiet --spp 1 --integrator gvcm");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("media.pbrt:5:1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("\"gvcm\" does not render participating media"), std::string::npos) << r.err;
    write("motion.pbrt",
          "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\nTransformTimes 0 1\nWorldBegin\n"
          "ActiveTransform EndTime\nTranslate 0 1 0\nActiveTransform All\nShape \"sphere\"\nWorldEnd\n");
    r = run("motion.pbrt --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("motion.pbrt:8:1"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("motion blur"), std::string::npos) << r.err;
    // Equal start and end transforms are no motion: renders.
    write("still.pbrt",
          "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"image\" \"integer xresolution\" [8] "
          "\"integer yresolution\" [8] \"string filename\" [\"still.exr\"]\nTransformTimes 0 1\nWorldBegin\n"
          "Translate 0 1 0\nShape \"sphere\"\nWorldEnd\n");
    EXPECT_EQ(run("still.pbrt --quiet --spp 1").status, 0);
}

// Fuzz findings that crashed, aborted in Embree or wrote Inf: each now renders
// (exit 0, finite layers) or fails with a message (exit 1), never a signal.
TEST_F(CliTest, FuzzRegressionsEndCleanly) {
    const fs::path dir = fs::path(GRADUS_SOURCE_DIR) / "tests/fuzz/regressions";
    int n = 0;
    for (const auto &e : fs::directory_iterator(dir)) {
        const std::string ext = e.path().extension().string();
        if (ext != ".pbrt" && ext != ".gltf") continue;
        ++n;
        RunResult r = run("'" + e.path().string() + "' --spp 1 --seed 7 --nthreads 1 --quiet --outfile out.exr");
        EXPECT_TRUE(r.status == 0 || r.status == 1) << e.path() << ": " << r.err;
        if (r.status == 1) {
            EXPECT_NE(r.err.find(ext + ":"), std::string::npos) << e.path() << ": " << r.err;
            continue;
        }
        gradus::Image img = gradus::ReadImage((dir_ / "out.exr").string());
        for (float v : img.data()) ASSERT_TRUE(std::isfinite(v)) << e.path();
        fs::remove(dir_ / "out.exr");
    }
    EXPECT_GE(n, 9);
}
