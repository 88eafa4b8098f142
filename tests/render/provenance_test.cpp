// What a render records and refuses (issue "Results a researcher can
// reproduce"): typed provenance metadata, the scene hash over included files,
// crop placement, --param, notes about dropped parameters, outputs checked
// before rendering, time budgets that include reconstruction.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "image/image.h"
#include "render/cli_fixture.h"

namespace fs = std::filesystem;
using gradus::Image;
using gradus::MetaValue;
using gradus::ReadImage;

namespace {

class Provenance : public gradus::test::GradusCliTest {
  protected:
    using Run = gradus::test::RunResult;
    Image image(const std::string &name) { return ReadImage((dir_ / name).string()); }
};

const char *kScene =
    "LookAt 0 0 -3  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" [40]\n"
    "Film \"image\" \"integer xresolution\" [20] \"integer yresolution\" [16] \"string filename\" [\"out.exr\"]\n"
    "Integrator \"bdpt\" \"integer maxdepth\" [3] \"string misheuristic\" \"power\"\n"
    "WorldBegin\n"
    "Include \"lights.pbrt\"\n"
    "Material \"matte\"\n"
    "Shape \"sphere\" \"float radius\" [1]\n"
    "WorldEnd\n";

}  // namespace

TEST_F(Provenance, TypedMetadataOfEveryRender) {
    write("scene.pbrt", kScene);
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    Run r = run("scene.pbrt --spp 2 --seed 9 --nthreads 2 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    Image img = image("out.exr");
    auto &m = img.metadata;
    for (const char *k : {"gradus_version", "command_line", "camera", "sampler", "film", "pixelfilter",
                          "integrator_parameters", "resolution", "cropwindow", "scene_hash", "scene"})
        EXPECT_EQ(m.at(k).type(), MetaValue::Type::String) << k;
    for (const char *k : {"spp", "passes", "threads", "quick", "scene_files", "nonfinite_discarded"})
        EXPECT_EQ(m.at(k).type(), MetaValue::Type::Int) << k;
    for (const char *k : {"render_seconds", "seconds_preprocess", "seconds_passes", "seconds_finish", "cpu_seconds",
                          "cpu_seconds_passes", "seconds_parallel", "lane_occupancy",
                          "peak_rss_mb", "scene_load_seconds"})
        EXPECT_EQ(m.at(k).type(), MetaValue::Type::Double) << k;
    EXPECT_EQ(m.at("spp"), "2");
    EXPECT_EQ(m.at("seed"), "9");
    EXPECT_EQ(m.at("threads"), "2");
    EXPECT_EQ(m.at("scene_files"), "2");  // the scene and its Include
    EXPECT_EQ(m.at("stop_reason"), "completed");
    EXPECT_EQ(m.at("resolution"), "20x16");
    EXPECT_NE(m.at("command_line").str().find("--seed 9"), std::string::npos);
    // Resolved parameters, given and default.
    EXPECT_NE(m.at("integrator_parameters").str().find("\"integer maxdepth\" 3"), std::string::npos) << m.at("integrator_parameters");
    EXPECT_NE(m.at("integrator_parameters").str().find("\"integer rrdepth\" 3"), std::string::npos) << m.at("integrator_parameters");
    EXPECT_NE(m.at("camera").str().find("\"float fov\" 40"), std::string::npos) << m.at("camera");
    EXPECT_GT(m.at("peak_rss_mb").number(), 1);
    EXPECT_LE(m.at("cpu_seconds_passes").number(), m.at("cpu_seconds").number() + 1e-6);
    EXPECT_LE(m.at("seconds_parallel").number(), m.at("seconds_passes").number() + 1e-6);
    EXPECT_GT(m.at("lane_occupancy").number(), 0);
    EXPECT_LE(m.at("lane_occupancy").number(), 1 + 1e-9);
    const double total = m.at("render_seconds").number();
    EXPECT_NEAR(total, m.at("seconds_preprocess").number() + m.at("seconds_passes").number() +
                           m.at("seconds_finish").number(), 1e-3);
}

TEST_F(Provenance, SceneHashCoversIncludedFiles) {
    write("scene.pbrt", kScene);
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    ASSERT_EQ(run("scene.pbrt --spp 1 --quiet").status, 0);
    std::string h1 = image("out.exr").metadata.at("scene_hash");
    ASSERT_EQ(run("scene.pbrt --spp 1 --quiet --seed 4").status, 0);
    EXPECT_EQ(image("out.exr").metadata.at("scene_hash").str(), h1);  // same inputs, same hash
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 6]\n");
    ASSERT_EQ(run("scene.pbrt --spp 1 --quiet").status, 0);
    EXPECT_NE(image("out.exr").metadata.at("scene_hash").str(), h1);
}

TEST_F(Provenance, CropKeepsItsPlaceAndPixels) {
    write("scene.pbrt", kScene);
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    ASSERT_EQ(run("scene.pbrt --spp 4 --quiet --integrator path --outfile full.exr").status, 0);
    ASSERT_EQ(run("scene.pbrt --spp 4 --quiet --integrator path --outfile crop.exr --cropwindow 0.25 0.75 0.5 1").status, 0);
    Image full = image("full.exr"), crop = image("crop.exr");
    ASSERT_EQ(crop.width(), 10);
    ASSERT_EQ(crop.height(), 8);
    EXPECT_EQ(crop.originX, 5);
    EXPECT_EQ(crop.originY, 8);
    EXPECT_EQ(crop.displayWidth, 20);
    EXPECT_EQ(crop.displayHeight, 16);
    // Random numbers are addressed by pixel: the crop is the full render's pixels.
    for (int y = 0; y < crop.height(); ++y)
        for (int x = 0; x < crop.width(); ++x)
            for (int c = 0; c < 3; ++c) ASSERT_EQ(crop.at(x, y, c), full.at(x + 5, y + 8, c)) << x << "," << y;
}

TEST_F(Provenance, ParamOverridesAndDroppedParametersAreSaid) {
    write("scene.pbrt", kScene);
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    Run r = run("scene.pbrt --spp 1 --quiet --param maxdepth=1 --param misheuristic=balance");
    ASSERT_EQ(r.status, 0) << r.err;
    std::string ip = image("out.exr").metadata.at("integrator_parameters");
    EXPECT_NE(ip.find("\"integer maxdepth\" 1"), std::string::npos) << ip;
    EXPECT_NE(ip.find("\"string misheuristic\" \"balance\""), std::string::npos) << ip;
    Run bad = run("scene.pbrt --spp 1 --quiet --param maxdepth=x");
    EXPECT_EQ(bad.status, 1);
    EXPECT_NE(bad.err.find("--param maxdepth"), std::string::npos) << bad.err;
    EXPECT_EQ(run("scene.pbrt --spp 1 --quiet --param nosuch=1").status, 1);
    // The scene's bdpt parameter misheuristic is not path's: said even with --quiet.
    Run o = run("scene.pbrt --spp 1 --quiet --integrator path");
    ASSERT_EQ(o.status, 0) << o.err;
    EXPECT_NE(o.err.find("misheuristic"), std::string::npos) << o.err;
    EXPECT_NE(o.err.find("is ignored by \"path\""), std::string::npos) << o.err;
}

TEST_F(Provenance, OutputsAreCheckedBeforeRendering) {
    write("scene.pbrt", kScene);
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    // A render of 10^8 spp would take hours: these must fail at once.
    for (const char *out : {"/nonexistent/x.exr", "x.tiff"}) {
        Run r = run(std::string("scene.pbrt --spp 100000000 --quiet --outfile ") + out);
        EXPECT_EQ(r.status, 1) << out;
        EXPECT_LT(r.wall, 10) << out;
        EXPECT_NE(r.err.find(out), std::string::npos) << r.err;
    }
    // The same for the Film's own filename.
    std::string s = kScene;
    s.replace(s.find("\"out.exr\""), 9, "\"missing/out.exr\"");
    write("badfilm.pbrt", s);
    Run r = run("badfilm.pbrt --spp 100000000 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_LT(r.wall, 10);
    EXPECT_NE(r.err.find("missing"), std::string::npos) << r.err;
}

TEST_F(Provenance, PbrtIntegratorsRenderAndRestrictingPixelBoundsAreNamed) {
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    std::string s = kScene;
    const std::string line = "Integrator \"bdpt\" \"integer maxdepth\" [3] \"string misheuristic\" \"power\"";
    std::string v = s;
    // pbrt-v3's eight integrators render under their names (sppm and volpath below).
    for (const char *pbrt : {"whitted", "directlighting", "ambientocclusion", "path", "bdpt", "mlt"}) {
        std::string d = s;
        d.replace(d.find(line), line.size(), std::string("Integrator \"") + pbrt + "\"");
        write("direct.pbrt", d);
        Run r = run("direct.pbrt --spp 1 --quiet");
        EXPECT_EQ(r.status, 0) << pbrt << ": " << r.err;
    }
    // A misspelt parameter of one of them is a located error.
    s.replace(s.find(line), line.size(), "Integrator \"directlighting\" \"string stratgy\" \"one\"");
    write("direct.pbrt", s);
    Run r = run("direct.pbrt --spp 1 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("direct.pbrt:4:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("stratgy"), std::string::npos) << r.err;
    // pbrt-v3's volpath renders with path.
    v.replace(v.find(line), line.size(), "Integrator \"volpath\" \"integer maxdepth\" [3]");
    write("volpath.pbrt", v);
    EXPECT_EQ(run("volpath.pbrt --spp 1 --quiet").status, 0);
    std::string pb = kScene;
    pb.replace(pb.find("\"string misheuristic\" \"power\""), 29, "\"integer pixelbounds\" [0 10 0 16]");
    write("pb.pbrt", pb);
    r = run("pb.pbrt --spp 1 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("pixelbounds"), std::string::npos) << r.err;
    pb.replace(pb.find("[0 10 0 16]"), 11, "[0 20 0 16]");  // the whole film: accepted
    write("pb.pbrt", pb);
    EXPECT_EQ(run("pb.pbrt --spp 1 --quiet").status, 0);
}

// pbrt-v3's "sppm" renders as vcm's merging-only mode: numiterations are the
// samples per pixel, pbrt-v3's parameters are read (a misspelt one is an error),
// photonsperiteration other than one subpath per pixel is refused at its location.
TEST_F(Provenance, PbrtSppmRendersAsVcmMerging) {
    write("lights.pbrt", "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n");
    const std::string line = "Integrator \"bdpt\" \"integer maxdepth\" [3] \"string misheuristic\" \"power\"";
    auto with = [&](const std::string &integrator) {
        std::string s = kScene;
        s.replace(s.find(line), line.size(), integrator);
        return s;
    };
    write("sppm.pbrt", with("Integrator \"sppm\" \"integer numiterations\" [3] \"float radius\" [0.05] "
                            "\"integer imagewritefrequency\" [1]"));
    Run r = run("sppm.pbrt --quiet --outfile sppm.exr");
    ASSERT_EQ(r.status, 0) << r.err;
    Image img = ReadImage((dir_ / "sppm.exr").string());
    EXPECT_EQ(img.metadata.at("spp").str(), "3");
    EXPECT_NE(img.metadata.at("integrator_parameters").str().find("\"string mode\" \"vm\""), std::string::npos)
        << img.metadata.at("integrator_parameters").str();
    write("bad.pbrt", with("Integrator \"sppm\" \"integer numiteration\" [3]"));
    r = run("bad.pbrt --spp 1 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("numiteration"), std::string::npos) << r.err;
    write("photons.pbrt", with("Integrator \"sppm\" \"integer photonsperiteration\" [1000]"));
    r = run("photons.pbrt --spp 1 --quiet");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("photons.pbrt:4:"), std::string::npos) << r.err;
}

// --time covers everything after scene loading, reconstruction included: a
// gradient render ends within the budget plus one pass. The scene (512^2, no
// geometry) makes passes cheap and the reconstruction a large share, so a loop
// that spent the whole budget on passes would end after budget + finish.
TEST_F(Provenance, TimeBudgetIncludesReconstruction) {
    write("empty.pbrt",
          "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\n"
          "Film \"image\" \"integer xresolution\" [512] \"integer yresolution\" [512] \"string filename\" [\"out.exr\"]\n"
          "WorldBegin\nWorldEnd\n");
    const double budget = 3;
    Run r = run("empty.pbrt --quiet --integrator gpt --time 3");
    ASSERT_EQ(r.status, 0) << r.err;
    const gradus::Metadata m = image("out.exr").metadata;
    const double total = m.at("render_seconds").number(), finish = m.at("seconds_finish").number();
    const double before = m.at("seconds_preprocess").number() + m.at("seconds_passes").number();
    const double onePass = m.at("seconds_passes").number() / std::max(1.0, m.at("passes").number());
    EXPECT_EQ(m.at("stop_reason"), "time budget");
    EXPECT_GT(finish, 0.05);
    EXPECT_LE(total, budget + onePass) << "finish " << finish << ", pass " << onePass;
    // The loop left room for the reconstruction (0.1 s for timing noise).
    EXPECT_LE(before, budget - finish + 0.1) << "finish " << finish << ", before " << before;
}
