// gradus --describe NAME through the binary, and table errors in a scene file.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "render/integrator.h"
#include "integrators/registry.h"

namespace gradus {
namespace {

namespace fs = std::filesystem;

struct RunResult {
    int status = -1;
    std::string out;  // stdout and stderr
};

RunResult Gradus(const std::string &args) {
    RunResult r;
    std::string cmd = std::string("'") + GRADUS_BIN + "' " + args + " 2>&1";
    FILE *p = popen(cmd.c_str(), "r");
    if (!p) return r;
    char buf[4096];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
    int st = pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

TEST(Describe, EveryIntegratorPrintsItsTable) {
    for (const auto &info : IntegratorRegistry()) {
        RunResult r = Gradus("--describe " + info.name);
        EXPECT_EQ(r.status, 0) << info.name << "\n" << r.out;
        EXPECT_EQ(r.out.rfind(info.name + ": " + info.description + "\n", 0), 0u) << r.out;
        std::string group;
        size_t at = 0;
        for (const ParamInfo &p : info.parameters()) {
            if (p.group != group) {
                group = p.group;
                at = r.out.find("  " + group + ":\n", at);
                ASSERT_NE(at, std::string::npos) << info.name << ": no heading " << group << "\n" << r.out;
            }
            // Entries in table order under their heading: name, type, default, help on one line.
            size_t line = r.out.find("\n    " + p.name + " ", at);
            ASSERT_NE(line, std::string::npos) << info.name << ": " << p.name << "\n" << r.out;
            std::string text = r.out.substr(line + 1, r.out.find('\n', line + 1) - line - 1);
            EXPECT_NE(text.find(std::string(" ") + p.typeName() + " "), std::string::npos) << text;
            EXPECT_NE(text.find(" " + p.defaultText + " "), std::string::npos) << text;
            EXPECT_NE(text.find(p.help), std::string::npos) << text;
            at = line + 1;
        }
    }
}

TEST(Describe, UnknownIntegratorListsValidNames) {
    RunResult r = Gradus("--describe nosuch");
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.out.find("nosuch"), std::string::npos) << r.out;
    for (const auto &info : IntegratorRegistry()) EXPECT_NE(r.out.find(info.name), std::string::npos) << r.out;
    EXPECT_EQ(Gradus("--describe").status, 1);  // NAME missing
}

TEST(Describe, TableErrorsInASceneAreLocated) {
    fs::path dir = fs::temp_directory_path() / ("gradus_describe_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "bad.pbrt") << "Integrator \"path\" \"integer maxdepth\" [-1]\nWorldBegin\nWorldEnd\n";
    RunResult r = Gradus("'" + (dir / "bad.pbrt").string() + "' --quiet");
    fs::remove_all(dir);
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.out.find("bad.pbrt:1:19: \"maxdepth\" must be >= 0"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace gradus
