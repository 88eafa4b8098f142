// The "// Parameters" doc block at the top of src/integrators/<name>/<name>.h
// lists exactly the entries of the integrator's table, with their defaults:
// every registered integrator is checked, so the two cannot drift apart.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "render/integrator.h"
#include "integrators/registry.h"

namespace gradus {
namespace {

struct DocEntry {
    std::string type, defaultText;
    int line;
};

// Parameter lines of the comment block that starts at "// Parameters":
// "//   <type> <name> <default>  help", default a number, word, "quoted" or [list].
// Headings ("// (gradient family ...):") and continuation lines (more indented) are skipped.
std::map<std::string, DocEntry> ParseDocBlock(const std::string &path, std::string *problem) {
    std::ifstream in(path);
    if (!in) {
        *problem = "cannot read " + path;
        return {};
    }
    static const std::regex entry(R"(^//   (bool|integer|float|string) (\w+) ("[^"]*"|\[[^\]]*\]|\S+)(\s.*)?$)");
    std::map<std::string, DocEntry> doc;
    std::string line;
    bool inBlock = false, found = false;
    for (int n = 1; std::getline(in, line); ++n) {
        if (!inBlock) {
            inBlock = found = line.rfind("// Parameters", 0) == 0;
            continue;
        }
        if (line.rfind("//", 0) != 0) break;  // end of the comment block
        std::smatch m;
        if (!std::regex_match(line, m, entry)) continue;
        if (doc.count(m[2])) *problem += path + ":" + std::to_string(n) + ": \"" + m[2].str() + "\" documented twice\n";
        doc[m[2]] = {m[1], m[3], n};
    }
    if (!found) *problem = path + ": no \"// Parameters\" block";
    return doc;
}

TEST(IntegratorHeaderDocs, MatchTheParameterTables) {
    ASSERT_FALSE(IntegratorRegistry().empty());
    for (const auto &info : IntegratorRegistry()) {
        SCOPED_TRACE(info.name);
        std::string header = std::string(GRADUS_SOURCE_DIR) + "/src/integrators/" + info.name + "/" + info.name + ".h";
        std::string problem;
        std::map<std::string, DocEntry> doc = ParseDocBlock(header, &problem);
        ASSERT_EQ(problem, "");
        std::vector<ParamInfo> table = info.parameters();
        for (const ParamInfo &p : table) {
            auto it = doc.find(p.name);
            if (it == doc.end()) {
                ADD_FAILURE() << header << ": table entry \"" << p.typeName() << " " << p.name << "\" (default "
                              << p.defaultText << ") is not documented";
                continue;
            }
            const std::string where = header + ":" + std::to_string(it->second.line) + ": \"" + p.name + "\"";
            EXPECT_EQ(it->second.type, p.typeName()) << where << ": documented type differs from the table";
            EXPECT_EQ(it->second.defaultText, p.defaultText) << where << ": documented default differs from the table";
        }
        for (const auto &[name, d] : doc) {
            bool inTable = false;
            for (const ParamInfo &p : table) inTable |= p.name == name;
            EXPECT_TRUE(inTable) << header << ":" << d.line << ": documented parameter \"" << name
                                 << "\" is not in the table";
        }
    }
}

}  // namespace
}  // namespace gradus
