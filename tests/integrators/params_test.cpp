// The parameter table type (render/params.h) and the located errors of
// the integrators' tables.
#include <gtest/gtest.h>

#include <cmath>

#include "render/integrator.h"
#include "render/params.h"
#include "param_test_util.h"
#include "integrators/registry.h"

namespace gradus::params_test {
namespace {

enum class Mode { Fast, Careful, Alias };

struct PartSettings {
    int depth;
    std::string strategy;
};

struct Settings : PartSettings {
    bool flag;
    Float x;
    Mode mode;
    std::vector<int> list;
    std::string text;
    int fromText = -1;
    FileLoc textLoc;
};

ParamTable<PartSettings> Part() {
    ParamTable<PartSettings> t("the part");
    t.integer("depth", &PartSettings::depth, 5, "depth", AtLeast(0));
    t.enumeration("strategy", &PartSettings::strategy, "b", {"a", "b"}, "a or b");
    return t;
}

ParamTable<Settings> Table() {
    using S = Settings;
    ParamTable<S> t("own");
    t.append(Part());
    t.boolean("flag", &S::flag, true, "a flag");
    t.real("x", &S::x, 0.25, "a number", Range(0, 1));
    t.enumeration<Mode>("mode", &S::mode, "fast",
                        {{"fast", Mode::Fast},
                         {"careful", Mode::Careful},
                         {"slow", Mode::Fast, "is not supported yet"},
                         {"FAST", Mode::Fast, "", true}},
                        "how");
    t.integers("list", &S::list, "some integers");
    t.string("text", &S::text, "", "free text").then([](S &s, const FileLoc &loc) {
        s.fromText = int(s.text.size());
        s.textLoc = loc;
    });
    return t;
}

std::string ErrorOf(const Desc &d) {
    try {
        Table().parse(d.desc);
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

TEST(ParamTable, DefaultsWhenAbsent) {
    Settings s = Table().parse(Desc().desc);
    EXPECT_EQ(s.depth, 5);
    EXPECT_EQ(s.strategy, "b");
    EXPECT_TRUE(s.flag);
    EXPECT_EQ(s.x, 0.25);
    EXPECT_EQ(s.mode, Mode::Fast);
    EXPECT_TRUE(s.list.empty());
    EXPECT_EQ(s.text, "");
    EXPECT_EQ(s.fromText, 0);
    EXPECT_EQ(s.textLoc.str(), "test.pbrt:1:1");  // absent: the directive's location
}

TEST(ParamTable, ReadsEveryEntryAndMarksItUsed) {
    Desc d;
    d.integer("depth", {2}).string("strategy", "a").boolean("flag", false).real("x", 1);
    d.string("mode", "careful").integer("list", {1, 2, 3}).string("text", "abc", Loc(7, 3));
    Settings s = Table().parse(d.desc);
    EXPECT_EQ(s.depth, 2);
    EXPECT_EQ(s.strategy, "a");
    EXPECT_FALSE(s.flag);
    EXPECT_EQ(s.x, 1);
    EXPECT_EQ(s.mode, Mode::Careful);
    EXPECT_EQ(s.list, (std::vector<int>{1, 2, 3}));
    EXPECT_EQ(s.fromText, 3);
    EXPECT_EQ(s.textLoc.str(), "test.pbrt:7:3");
    EXPECT_NO_THROW(d.desc.params.checkUnused("Integrator"));
}

TEST(ParamTable, UnknownNamesStayUnused) {
    Desc d;
    d.integer("dpeth", {2}, Loc(4, 9));
    Table().parse(d.desc);
    try {
        d.desc.params.checkUnused("Integrator \"x\"");
        FAIL() << "no error for a misspelt parameter";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("test.pbrt:4:9"), std::string::npos) << e.what();
    }
}

TEST(ParamTable, OutOfRangeNumbersAreLocated) {
    EXPECT_EQ(ErrorOf(Desc().integer("depth", {-1}, Loc(3, 7))), "test.pbrt:3:7: \"depth\" must be >= 0");
    EXPECT_EQ(ErrorOf(Desc().real("x", 1.5, Loc(5, 2))), "test.pbrt:5:2: \"x\" must be in [0, 1]");
    EXPECT_EQ(ErrorOf(Desc().real("x", std::nan(""), Loc(5, 2))), "test.pbrt:5:2: \"x\" must be in [0, 1]");
}

TEST(ParamTable, BadEnumerationValuesAreLocatedAndListValidOnes) {
    EXPECT_EQ(ErrorOf(Desc().string("mode", "sideways", Loc(3, 7))),
              "test.pbrt:3:7: unknown \"mode\" \"sideways\" (valid: fast, careful)");
    EXPECT_EQ(ErrorOf(Desc().string("mode", "slow", Loc(3, 7))),
              "test.pbrt:3:7: \"mode\" \"slow\" is not supported yet (valid: fast, careful)");
    EXPECT_EQ(ErrorOf(Desc().string("strategy", "c", Loc(2, 4))),
              "test.pbrt:2:4: unknown \"strategy\" \"c\" (valid: a, b)");
    EXPECT_EQ(Table().parse(Desc().string("mode", "FAST").desc).mode, Mode::Fast);  // alias
}

TEST(ParamTable, WrongTypeIsLocated) {
    std::string e = ErrorOf(Desc().string("depth", "five", Loc(6, 1)));
    EXPECT_NE(e.find("test.pbrt:6:1"), std::string::npos) << e;
}

TEST(ParamTable, DescribesItselfInTableOrderWithGroups) {
    std::vector<ParamInfo> info = Table().describe();
    ASSERT_EQ(info.size(), 7u);
    EXPECT_EQ(info[0].name, "depth");
    EXPECT_EQ(info[0].group, "the part");
    EXPECT_STREQ(info[0].typeName(), "integer");
    EXPECT_EQ(info[0].defaultText, "5");
    EXPECT_EQ(info[0].values, ">= 0");
    EXPECT_EQ(info[1].defaultText, "\"b\"");
    EXPECT_EQ(info[1].values, "a | b");
    EXPECT_EQ(info[2].group, "own");
    EXPECT_EQ(info[2].defaultText, "true");
    EXPECT_EQ(info[3].defaultText, "0.25");
    EXPECT_STREQ(info[4].typeName(), "string");
    EXPECT_EQ(info[4].values, "fast | careful; \"slow\" is not supported yet");  // the alias is not listed
    EXPECT_EQ(info[5].defaultText, "[]");
    EXPECT_EQ(info[6].defaultText, "\"\"");
    std::string text = FormatParams(info);
    EXPECT_LT(text.find("the part:"), text.find("own:"));
    EXPECT_NE(text.find("a number"), std::string::npos);
}

TEST(ParamTable, RangeTexts) {
    EXPECT_EQ(Range().text(), "");
    EXPECT_EQ(AtLeast(1).text(), ">= 1");
    EXPECT_EQ(Range(1, 1024).text(), "in [1, 1024]");
    EXPECT_EQ(Range(-1, -1, "why").text(), "-1");
    EXPECT_EQ(Range(-1, -1, "why").describe(), "-1: why");
}

// ---------------------------------------------------------------- the integrators' tables

std::string CreateError(const std::string &type, Desc d) {
    d.desc.type = type;
    try {
        CreateIntegrator(d.desc);
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

bool Registered(const std::string &name) {
    for (const auto &info : IntegratorRegistry())
        if (info.name == name) return true;
    return false;
}

// Every entry of every table is read: a parameter list with all of them at
// their defaults builds the integrator and leaves nothing unused.
TEST(IntegratorTables, EveryEntryIsConsumed) {
    for (const auto &info : IntegratorRegistry()) {
        Desc d(info.name);
        for (const ParamInfo &p : info.parameters()) {
            const std::string &v = p.defaultText;
            switch (p.kind) {
            case ParamKind::Bool: d.boolean(p.name, v == "true"); break;
            case ParamKind::Int: d.integer(p.name, {std::stod(v)}); break;
            case ParamKind::Float: d.real(p.name, std::stod(v)); break;
            case ParamKind::String:
            case ParamKind::Enum: d.string(p.name, v.substr(1, v.size() - 2)); break;
            case ParamKind::IntList: d.integer(p.name, {0, 1, 0, 1}); break;
            }
        }
        EXPECT_NO_THROW(CreateIntegrator(d.desc)) << info.name;
        EXPECT_NO_THROW(d.desc.params.checkUnused("Integrator \"" + info.name + "\"")) << info.name;
    }
}

TEST(IntegratorTables, BadEnumerationIsLocated) {
    EXPECT_EQ(CreateError("path", Desc().string("lightsamplestrategy", "nearest", Loc(3, 20))),
              "test.pbrt:3:20: unknown \"lightsamplestrategy\" \"nearest\" (valid: uniform, power, spatial)");
    if (Registered("bdpt")) {
        EXPECT_EQ(CreateError("bdpt", Desc().string("misheuristic", "maximum", Loc(2, 19))),
                  "test.pbrt:2:19: unknown \"misheuristic\" \"maximum\" (valid: balance, power)");
    }
    if (Registered("gpt")) {
        EXPECT_EQ(CreateError("gpt", Desc().string("reconstruction", "l3", Loc(4, 5))),
                  "test.pbrt:4:5: unknown \"reconstruction\" \"l3\" (valid: hybrid, l1, l2, weighted)");
    }
}

TEST(IntegratorTables, OutOfRangeIntIsLocated) {
    EXPECT_EQ(CreateError("path", Desc().integer("maxdepth", {-2}, Loc(5, 8))),
              "test.pbrt:5:8: \"maxdepth\" must be >= 0");
    if (Registered("mbdpt")) {
        EXPECT_EQ(CreateError("mbdpt", Desc().integer("connections", {0}, Loc(2, 30))),
                  "test.pbrt:2:30: \"connections\" must be in [1, 1024]");
    }
    for (const char *name : {"gpt", "gbdpt", "gvcm"}) {
        if (Registered(name)) {
            EXPECT_EQ(CreateError(name, Desc().integer("separatedsamples", {-1}, Loc(6, 3))),
                      "test.pbrt:6:3: \"separatedsamples\" must be >= 0")
                << name;
        }
    }
    if (Registered("mlt")) {
        EXPECT_EQ(CreateError("mlt", Desc().integer("chains", {0}, Loc(3, 9))), "test.pbrt:3:9: \"chains\" must be >= 1");
        EXPECT_EQ(CreateError("mlt", Desc().integer("bootstrapsamples", {0}, Loc(4, 2))),
                  "test.pbrt:4:2: \"bootstrapsamples\" must be >= 1");
        EXPECT_EQ(CreateError("mlt", Desc().integer("mutationsperpixel", {-3}, Loc(5, 2))),
                  "test.pbrt:5:2: \"mutationsperpixel\" must be >= 1");
    }
}

TEST(IntegratorTables, OutOfRangeFloatIsLocated) {
    if (!Registered("mlt")) GTEST_SKIP() << "mlt not built";
    EXPECT_EQ(CreateError("mlt", Desc().real("largestepprobability", 1.5, Loc(2, 7))),
              "test.pbrt:2:7: \"largestepprobability\" must be in [0, 1]");
    EXPECT_EQ(CreateError("mlt", Desc().real("sigma", 0, Loc(3, 7))),
              "test.pbrt:3:7: \"sigma\" must be in [1e-07, 1]: a positive deviation within the unit interval");
    EXPECT_EQ(CreateError("mlt", Desc().real("sigma", std::nan(""), Loc(3, 7))).rfind("test.pbrt:3:7: \"sigma\"", 0), 0u);
    EXPECT_EQ(CreateError("mlt", Desc().real("sigma", 0.05).real("largestepprobability", 0)), "");
}

// gbdpt takes the family's parameters as bdpt does: roulette, the film filter
// and "spatial" (= power, position-free) are accepted; its own are checked.
TEST(IntegratorTables, GBDPTParametersAreLocated) {
    if (!Registered("gbdpt")) GTEST_SKIP() << "gbdpt not built";
    EXPECT_EQ(CreateError("gbdpt", Desc().string("lightsamplestrategy", "spatial")), "");
    EXPECT_EQ(CreateError("gbdpt", Desc().integer("rrdepth", {-1}).string("pixelfilter", "box")), "");
    EXPECT_EQ(CreateError("gbdpt", Desc().integer("rrdepth", {0}).string("pixelfilter", "film")), "");
    std::string e = CreateError("gbdpt", Desc().string("pixelfilter", "gaussian", Loc(3, 4)));
    EXPECT_EQ(e, "test.pbrt:3:4: unknown \"pixelfilter\" \"gaussian\" (valid: film, box)");
    e = CreateError("gbdpt", Desc().string("manifoldsolver", "lm", Loc(5, 2)));
    EXPECT_EQ(e, "test.pbrt:5:2: unknown \"manifoldsolver\" \"lm\" (valid: ceres, newton)");
}

}  // namespace
}  // namespace gradus::params_test
