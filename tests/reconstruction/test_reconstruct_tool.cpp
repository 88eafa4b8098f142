// The gradus::Image bridge and the reconstruct tool end to end (exit codes,
// messages, layers written). Files go to a fresh temporary directory.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/error.h"
#include "image/image.h"
#include "recon_test_util.h"
#include "reconstruction/reconstruction.h"

using namespace gradus;
using namespace gradus::testutil;

namespace {

const int W = 24, H = 16;

// Film-like image with layers primal, dx, dy (and variances when asked).
Image MakeFilm(const GradientImages &g, bool variances) {
    Image img(g.width, g.height, {});
    auto put = [&](const std::string &layer, const std::vector<float> &v) {
        Image rgb = Image::RGB(g.width, g.height);
        for (int y = 0; y < g.height; ++y)
            for (int x = 0; x < g.width; ++x)
                for (int c = 0; c < 3; ++c) rgb.at(x, y, c) = v[(size_t(y) * g.width + x) * 3 + c];
        img.setLayerRGB(layer, rgb);
    };
    put("primal", g.primal);
    put("dx", g.dx);
    put("dy", g.dy);
    if (variances) {
        put("primal_var", std::vector<float>(g.primal.size(), 0.04f));
        put("dx_var", std::vector<float>(g.primal.size(), 0.01f));
        put("dy_var", std::vector<float>(g.primal.size(), 0.01f));
    }
    return img;
}

class ToolTest : public ::testing::Test {
  protected:
    void SetUp() override {
        char tmpl[] = "/tmp/gradus_recon_XXXXXX";
        ASSERT_NE(mkdtemp(tmpl), nullptr);
        dir_ = tmpl;
        truth_ = SceneImage(W, H);
    }
    void TearDown() override { std::system(("rm -rf '" + dir_ + "'").c_str()); }
    std::string path(const std::string &f) const { return dir_ + "/" + f; }

    // Runs the tool; returns its exit status, stdout and stderr.
    int run(const std::string &args, std::string *out = nullptr, std::string *err = nullptr) {
        std::string cmd = std::string(GRADUS_BINARY_DIR) + "/bin/reconstruct " + args + " >'" +
                          path("stdout.txt") + "' 2>'" + path("stderr.txt") + "'";
        int st = std::system(cmd.c_str());
        auto slurp = [](const std::string &f) {
            std::ifstream in(f);
            std::stringstream ss;
            ss << in.rdbuf();
            return ss.str();
        };
        if (out) *out = slurp(path("stdout.txt"));
        if (err) *err = slurp(path("stderr.txt"));
        return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    }

    std::string dir_;
    std::vector<float> truth_;
};

bool FileExists(const std::string &f) { return std::ifstream(f).good(); }

}  // namespace

TEST(ReconstructionImage, BridgeAndIntegratorLayers) {
    GradientImages g = ExactInputs(SceneImage(W, H), W, H);
    Image film = MakeFilm(g, false);
    GradientImages back = GradientImagesFromImage(film);
    EXPECT_EQ(back.primal, g.primal);
    EXPECT_EQ(back.dx, g.dx);
    EXPECT_FALSE(back.hasVariance());
    AddReconstructionLayers(film, 0.2);
    for (const char *layer : {"reconstructed_l1", "reconstructed_l2"}) {
        Image r = film.layerRGB(layer);
        double m = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    m = std::max(m, double(std::fabs(r.at(x, y, c) - g.primal[(size_t(y) * W + x) * 3 + c])));
        EXPECT_LT(m, 1e-5 * MaxAbs(g.primal)) << layer;
    }
    Image noDy(W, H, {});
    noDy.setLayerRGB("primal", film.layerRGB("primal"));
    noDy.setLayerRGB("dx", film.layerRGB("dx"));
    try {
        GradientImagesFromImage(noDy);
        ADD_FAILURE() << "missing layer accepted";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("no layer 'dy'"), std::string::npos) << e.what();
    }
}

TEST_F(ToolTest, MultiLayerInputWritesExrPngAndJson) {
    GradientImages g = ExactInputs(truth_, W, H);
    AddNoise(g, 0.1, 0.02, 3);
    WriteImage(path("film.exr"), MakeFilm(g, false));
    for (const char *norm : {"l1", "l2"}) {
        std::string out, err;
        std::string outfile = path(std::string("out_") + norm + ".exr");
        ASSERT_EQ(run("'" + path("film.exr") + "' --norm " + norm + " --outfile '" + outfile + "' --json", &out, &err), 0)
            << err;
        Image res = ReadImage(outfile);
        ASSERT_EQ(res.width(), W);
        ASSERT_EQ(res.height(), H);
        ASSERT_GE(res.channelIndex("R"), 0);
        ASSERT_GE(res.channelIndex("B"), 0);
        EXPECT_TRUE(FileExists(path(std::string("out_") + norm + ".png")));
        // Same pixels as the library call.
        ReconstructionOptions o = std::string(norm) == "l1" ? ReconstructionOptions::L1Default()
                                                            : ReconstructionOptions::L2Exact();
        ReconstructionResult lib = Reconstruct(g, o);
        double m = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    m = std::max(m, double(std::fabs(res.at(x, y, res.channelIndex("R") + c) - lib.at(x, y, c))));
        EXPECT_LT(m, 1e-6);
        nlohmann::json j = nlohmann::json::parse(out);
        EXPECT_EQ(j["norm"], norm);
        EXPECT_GT(j["residuals"]["gradient_l2"].get<double>(), 0.0);
        EXPECT_GE(j["seconds"].get<double>(), 0.0);
    }
}

TEST_F(ToolTest, SeparateFilesAndWeighted) {
    GradientImages g = ExactInputs(truth_, W, H);
    Image film = MakeFilm(g, true);
    WriteImage(path("p.exr"), film.layerRGB("primal"));
    WriteImage(path("dx.exr"), film.layerRGB("dx"));
    WriteImage(path("dy.exr"), film.layerRGB("dy"));
    std::string err;
    ASSERT_EQ(run("--primal '" + path("p.exr") + "' --dx '" + path("dx.exr") + "' --dy '" + path("dy.exr") +
                      "' --norm l2 --outfile '" + path("sep.exr") + "' --no-png",
                  nullptr, &err),
              0)
        << err;
    EXPECT_FALSE(FileExists(path("sep.png")));
    Image res = ReadImage(path("sep.exr"));
    double m = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c)
                m = std::max(m, double(std::fabs(res.at(x, y, res.channelIndex("R") + c) - truth_[(size_t(y) * W + x) * 3 + c])));
    EXPECT_LT(m, 1e-5 * MaxAbs(truth_));
    WriteImage(path("var.exr"), film);
    EXPECT_EQ(run("'" + path("var.exr") + "' --norm weighted --outfile '" + path("w.exr") + "'", nullptr, &err), 0) << err;
    EXPECT_TRUE(FileExists(path("w.exr")));
}

TEST_F(ToolTest, ErrorsExitOneWithMessage) {
    GradientImages g = ExactInputs(truth_, W, H);
    Image film = MakeFilm(g, false);
    WriteImage(path("film.exr"), film);
    std::string err;
    // Weighted without variance layers.
    EXPECT_EQ(run("'" + path("film.exr") + "' --norm weighted --outfile '" + path("o.exr") + "'", nullptr, &err), 1);
    EXPECT_NE(err.find("variance"), std::string::npos) << err;
    // NaN in a gradient.
    Image nanFilm = film;
    nanFilm.at(3, 2, nanFilm.channelIndex("dx.G")) = std::numeric_limits<float>::quiet_NaN();
    WriteImage(path("nan.exr"), nanFilm);
    EXPECT_EQ(run("'" + path("nan.exr") + "' --outfile '" + path("o.exr") + "'", nullptr, &err), 1);
    EXPECT_NE(err.find("NaN value at pixel (3, 2)"), std::string::npos) << err;
    EXPECT_FALSE(FileExists(path("o.exr")));
    // Missing layer.
    Image noDy(W, H, {});
    noDy.setLayerRGB("primal", film.layerRGB("primal"));
    noDy.setLayerRGB("dx", film.layerRGB("dx"));
    WriteImage(path("nody.exr"), noDy);
    EXPECT_EQ(run("'" + path("nody.exr") + "' --outfile '" + path("o.exr") + "'", nullptr, &err), 1);
    EXPECT_NE(err.find("no layer 'dy'"), std::string::npos) << err;
    // Bad options and arguments.
    EXPECT_EQ(run("'" + path("film.exr") + "' --outfile '" + path("o.exr") + "' --norm l3", nullptr, &err), 1);
    EXPECT_NE(err.find("unknown reconstruction norm 'l3'"), std::string::npos) << err;
    EXPECT_EQ(run("'" + path("film.exr") + "' --outfile '" + path("o.exr") + "' --alpha -1", nullptr, &err), 1);
    EXPECT_NE(err.find("alpha"), std::string::npos) << err;
    EXPECT_EQ(run("'" + path("film.exr") + "' --outfile '" + path("o.exr") + "' --bogus", nullptr, &err), 1);
    EXPECT_NE(err.find("unknown option '--bogus'"), std::string::npos) << err;
    EXPECT_EQ(run("'" + path("film.exr") + "'", nullptr, &err), 1);
    EXPECT_NE(err.find("missing --outfile"), std::string::npos) << err;
    EXPECT_EQ(run("'" + path("missing.exr") + "' --outfile '" + path("o.exr") + "'", nullptr, &err), 1);
    EXPECT_NE(err.find("missing.exr"), std::string::npos) << err;
    EXPECT_EQ(run("--help", nullptr, &err), 0);
}

// The render's provenance and crop placement survive a reconstruction.
TEST_F(ToolTest, MetadataAndCropPlacementCarriedThrough) {
    GradientImages g = ExactInputs(truth_, W, H);
    Image film = MakeFilm(g, false);
    film.metadata["integrator"] = "gpt";
    film.metadata["seed"] = "17";
    film.metadata["spp"] = MetaValue::Int(32);
    film.originX = 3, film.originY = 4, film.displayWidth = W + 10, film.displayHeight = H + 8;
    WriteImage(path("film.exr"), film);
    std::string err;
    ASSERT_EQ(run("'" + path("film.exr") + "' --norm l2 --outfile '" + path("out.exr") + "' --no-png", nullptr, &err), 0)
        << err;
    Image res = ReadImage(path("out.exr"));
    EXPECT_EQ(res.metadata.at("integrator"), "gpt");
    EXPECT_EQ(res.metadata.at("seed"), "17");
    EXPECT_EQ(res.metadata.at("spp").type(), MetaValue::Type::Int);
    EXPECT_EQ(res.metadata.at("reconstruction_norm"), "l2");
    EXPECT_NE(res.metadata.at("reconstruct_command_line").str().find("--norm l2"), std::string::npos);
    EXPECT_EQ(res.originX, 3);
    EXPECT_EQ(res.originY, 4);
    EXPECT_EQ(res.displayWidth, W + 10);
}

// Separated light (reconstruction.h): a "separated" layer is part of the
// primal but not of the gradients; every norm solves for primal - separated
// and adds separated back. Exact gradients of a smooth image I with two
// pixels of a bright emitter S in the primal only: the output is I + S (the
// solve of exact inputs returns I), where a solve of the primal I + S would
// spread the two pixels over the image (the gradients say they are not there).
TEST_F(ToolTest, SeparatedLayerIsAddedAfterTheSolve) {
    GradientImages g = ExactInputs(truth_, W, H);
    std::vector<float> sep(g.primal.size(), 0.f);
    for (int c = 0; c < 3; ++c) {
        sep[(size_t(5) * W + 7) * 3 + c] = 1000.f + c;
        sep[(size_t(6) * W + 7) * 3 + c] = 250.f;
    }
    std::vector<float> expected = truth_;
    for (size_t i = 0; i < sep.size(); ++i) {
        g.primal[i] += sep[i];
        expected[i] += sep[i];
    }
    Image film = MakeFilm(g, true);
    Image sepImg = Image::RGB(W, H);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c) sepImg.at(x, y, c) = sep[(size_t(y) * W + x) * 3 + c];
    film.setLayerRGB("separated", sepImg);
    WriteImage(path("film.exr"), film);
    // The library reads the layer.
    GradientImages back = GradientImagesFromImage(film);
    EXPECT_EQ(back.separated, sep);
    auto maxErr = [&](const Image &res) {
        double m = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    m = std::max(m, double(std::fabs(res.at(x, y, res.channelIndex("R") + c) -
                                                     expected[(size_t(y) * W + x) * 3 + c])));
        return m;
    };
    // Tolerance: the solve's float error on an image of maximum ~2.6, plus the
    // rounding of (I + S) - S at the emitter's pixels (ulp of 1000: 6e-5).
    const double tol = 1e-5 * MaxAbs(truth_) + 2e-4;
    for (const char *norm : {"l1", "l2", "hybrid", "weighted"}) {
        std::string err;
        const std::string out = path(std::string("sep_") + norm + ".exr");
        ASSERT_EQ(run("'" + path("film.exr") + "' --norm " + norm + " --outfile '" + out + "' --no-png", nullptr, &err), 0)
            << err;
        EXPECT_LT(maxErr(ReadImage(out)), tol) << norm;
    }
    // Separate files: --separated.
    WriteImage(path("p.exr"), film.layerRGB("primal"));
    WriteImage(path("dx.exr"), film.layerRGB("dx"));
    WriteImage(path("dy.exr"), film.layerRGB("dy"));
    WriteImage(path("s.exr"), sepImg);
    std::string err;
    ASSERT_EQ(run("--primal '" + path("p.exr") + "' --dx '" + path("dx.exr") + "' --dy '" + path("dy.exr") +
                      "' --separated '" + path("s.exr") + "' --norm l2 --outfile '" + path("files.exr") + "' --no-png",
                  nullptr, &err),
              0)
        << err;
    EXPECT_LT(maxErr(ReadImage(path("files.exr"))), tol);
    // An image without the layer (written before the separation) is solved as
    // it is: the emitter's pixels are spread, far from I + S there.
    WriteImage(path("old.exr"), MakeFilm(g, true));
    ASSERT_EQ(run("'" + path("old.exr") + "' --norm l2 --outfile '" + path("old_out.exr") + "' --no-png", nullptr, &err), 0)
        << err;
    EXPECT_GT(maxErr(ReadImage(path("old_out.exr"))), 100);
    // A separated image of another size is an error.
    WriteImage(path("small.exr"), Image::RGB(W - 1, H));
    EXPECT_EQ(run("--primal '" + path("p.exr") + "' --dx '" + path("dx.exr") + "' --dy '" + path("dy.exr") +
                      "' --separated '" + path("small.exr") + "' --outfile '" + path("x.exr") + "'",
                  nullptr, &err),
              1);
    EXPECT_NE(err.find("separated image differs in size"), std::string::npos) << err;
}
