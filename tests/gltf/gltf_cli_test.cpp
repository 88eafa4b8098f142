// The gradus binary on glTF files: a .glb renders to EXR with every registered
// integrator (these need the "gltfpbr" material), and malformed files or
// unknown cameras exit 1 with a located message.
#include <gtest/gtest.h>

#include <regex>

#include "conformance/table_util.h"
#include "gltf_test_util.h"

namespace gradus::gltftest {
namespace {

using conformance::ProcResult;
using conformance::RunGradus;
using conformance::ScratchDir;

TEST(GltfCli, GlbRendersToExr) {
    ScratchDir dir;
    ProcResult r = RunGradus({Data("cornell.glb"), "--resolution", "16x16", "--spp", "1", "--outfile", "X.exr"},
                             dir.path());
    ASSERT_TRUE(r.exited && r.exitCode == 0) << r.describe();
    Image img = ReadImage((dir.path() / "X.exr").string());
    EXPECT_EQ(img.width(), 16);
    EXPECT_EQ(img.height(), 16);
}

TEST(GltfCli, RendersWithEveryIntegrator) {
    const auto &names = conformance::Integrators();
    ASSERT_FALSE(names.empty()) << "gradus --list-integrators printed nothing";
    ScratchDir dir;
    for (const auto &name : names) {
        SCOPED_TRACE(name);
        const std::string out = name + ".exr";
        ProcResult r = RunGradus({Data("cornell.glb"), "--integrator", name, "--resolution", "8x8", "--spp", "1",
                                  "--nthreads", "2", "--quiet", "--outfile", out},
                                 dir.path());
        EXPECT_TRUE(r.exited && r.exitCode == 0) << r.describe();
        if (!r.exited || r.exitCode != 0) continue;
        Image img = ReadImage((dir.path() / out).string());
        EXPECT_EQ(conformance::NonFiniteReport(img), "");
    }
}

TEST(GltfCli, MalformedFileExitsOneWithALocatedMessage) {
    ScratchDir dir;
    ProcResult r = RunGradus({Data("bad-index.gltf"), "--resolution", "8x8", "--spp", "1"}, dir.path());
    EXPECT_TRUE(r.exited && r.exitCode == 1) << r.describe();
    EXPECT_TRUE(std::regex_search(r.err, std::regex("bad-index\\.gltf:[0-9]+:[0-9]+: index 7 .* out of range")))
        << r.err;
    r = RunGradus({Data("bad-cut-bin.glb")}, dir.path());
    EXPECT_TRUE(r.exited && r.exitCode == 1) << r.describe();
    EXPECT_NE(r.err.find("bad-cut-bin.glb (JSON chunk):1:1: .glb: the BIN chunk"), std::string::npos) << r.err;
}

TEST(GltfCli, UnknownCameraExitsOne) {
    ScratchDir dir;
    ProcResult r = RunGradus({Data("cornell.gltf"), "--camera", "nope"}, dir.path());
    EXPECT_TRUE(r.exited && r.exitCode == 1) << r.describe();
    EXPECT_NE(r.err.find("no camera named \"nope\" (cameras: view)"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace gradus::gltftest
