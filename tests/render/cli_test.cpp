// The gradus command line: located errors with exit status 1, successful
// renders with metadata, and Ctrl-C writing the partial image.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "image/image.h"

namespace fs = std::filesystem;

namespace {

struct RunResult {
    int status;
    std::string err;
};

class CliTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("gradus_cli_" + std::to_string(::getpid()) + "_" +
                                            ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    std::string write(const std::string &name, const std::string &text) {
        std::ofstream(dir_ / name) << text;
        return (dir_ / name).string();
    }
    RunResult run(const std::string &args) {
        std::string errFile = (dir_ / "stderr.txt").string();
        std::string cmd = "cd '" + dir_.string() + "' && '" + GRADUS_BIN + "' " + args + " 2> '" + errFile + "' > /dev/null";
        int st = std::system(cmd.c_str());
        std::ifstream in(errFile);
        std::stringstream ss;
        ss << in.rdbuf();
        return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, ss.str()};
    }
    fs::path dir_;
};

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
    write("bad.pbrt", "WorldBegin\nShape \"curve\" \"point P\" [0 0 0 1 0 0 2 0 0 3 0 0]\nWorldEnd\n");
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
