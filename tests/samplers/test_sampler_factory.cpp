// CreateSampler: names, pbrt-v3 aliases and defaults, spp rounding and
// overrides, located errors.
#include <gtest/gtest.h>

#include <memory>

#include "core/error.h"
#include "samplers/samplers.h"

using namespace gradus;

namespace {

EntityDesc Desc(const std::string &type) {
    EntityDesc d;
    d.type = type;
    d.loc.file = std::make_shared<const std::string>("scene.pbrt");
    d.loc.line = 12;
    d.loc.column = 3;
    d.present = true;
    return d;
}

void AddInt(EntityDesc &d, const std::string &name, int v, int line = 13) {
    Param p;
    p.type = "integer";
    p.name = name;
    p.numbers = {double(v)};
    p.loc = d.loc;
    p.loc.line = line;
    d.params.add(p);
}

void AddBool(EntityDesc &d, const std::string &name, bool v) {
    Param p;
    p.type = "bool";
    p.name = name;
    p.bools = {v};
    p.loc = d.loc;
    d.params.add(p);
}

}  // namespace

TEST(CreateSampler, NamesAndDefaults) {
    struct Case {
        const char *type, *name;
        int spp;
    } cases[] = {{"random", "random", 4},         {"stratified", "stratified", 4},
                 {"halton", "halton", 16},        {"sobol", "sobol", 16},
                 {"lowdiscrepancy", "sobol", 16}, {"02sequence", "sobol", 16},
                 {"maxmindist", "stratified", 16}};
    for (const Case &c : cases) {
        auto s = CreateSampler(Desc(c.type), 1, 0);
        EXPECT_EQ(s->name(), c.name) << c.type;
        EXPECT_EQ(s->samplesPerPixel(), c.spp) << c.type;
    }
    auto st = CreateSampler(Desc("stratified"), 1, 0);
    auto *ss = dynamic_cast<StratifiedSampler *>(st.get());
    ASSERT_NE(ss, nullptr);
    EXPECT_EQ(ss->xSamples(), 2);
    EXPECT_EQ(ss->ySamples(), 2);
    EXPECT_TRUE(ss->jitter());
}

TEST(CreateSampler, ParametersRoundingAndOverride) {
    auto d = Desc("sobol");
    AddInt(d, "pixelsamples", 10);
    EXPECT_EQ(CreateSampler(d, 1, 0)->samplesPerPixel(), 16);  // rounded up to 2^k as in pbrt-v3
    EXPECT_EQ(CreateSampler(Desc("02sequence"), 1, 5)->samplesPerPixel(), 8);
    EXPECT_EQ(CreateSampler(Desc("random"), 1, 7)->samplesPerPixel(), 7);
    EXPECT_EQ(CreateSampler(Desc("halton"), 1, 7)->samplesPerPixel(), 7);
    auto s = CreateSampler(Desc("stratified"), 1, 6);
    EXPECT_EQ(s->samplesPerPixel(), 6);
    auto *ss = dynamic_cast<StratifiedSampler *>(s.get());
    ASSERT_NE(ss, nullptr);
    EXPECT_EQ(ss->xSamples() * ss->ySamples(), 6);
    EXPECT_EQ(ss->xSamples(), 2);

    auto st = Desc("stratified");
    AddInt(st, "xsamples", 3);
    AddInt(st, "ysamples", 5);
    AddBool(st, "jitter", false);
    AddInt(st, "dimensions", 7);
    auto s2 = CreateSampler(st, 1, 0);
    auto *ss2 = dynamic_cast<StratifiedSampler *>(s2.get());
    ASSERT_NE(ss2, nullptr);
    EXPECT_EQ(ss2->xSamples(), 3);
    EXPECT_EQ(ss2->ySamples(), 5);
    EXPECT_FALSE(ss2->jitter());

    auto mm = Desc("maxmindist");
    AddInt(mm, "pixelsamples", 32);
    EXPECT_EQ(CreateSampler(mm, 1, 0)->samplesPerPixel(), 32);
}

TEST(CreateSampler, SeedSelectsTheSequence) {
    auto a = CreateSampler(Desc("sobol"), 1, 0), b = CreateSampler(Desc("sobol"), 1, 0),
         c = CreateSampler(Desc("sobol"), 2, 0);
    a->startPixelSample({4, 5}, 3);
    b->startPixelSample({4, 5}, 3);
    c->startPixelSample({4, 5}, 3);
    Float va = a->get1D();
    EXPECT_EQ(va, b->get1D());
    EXPECT_NE(va, c->get1D());
}

TEST(CreateSampler, ErrorsAreLocated) {
    try {
        CreateSampler(Desc("bestcandidate"), 1, 0);
        FAIL() << "no error for an unknown sampler";
    } catch (const Error &e) {
        std::string m = e.what();
        EXPECT_NE(m.find("scene.pbrt:12:3"), std::string::npos) << m;
        EXPECT_NE(m.find("bestcandidate"), std::string::npos) << m;
        for (const char *n : {"random", "stratified", "halton", "sobol"})
            EXPECT_NE(m.find(n), std::string::npos) << m;
    }
    auto bad = Desc("random");
    AddInt(bad, "pixelsamples", 0, 20);
    try {
        CreateSampler(bad, 1, 0);
        FAIL() << "no error for pixelsamples 0";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("scene.pbrt:20"), std::string::npos) << e.what();
    }
    auto misspelt = Desc("halton");
    AddInt(misspelt, "pixelsample", 8);
    EXPECT_THROW(CreateSampler(misspelt, 1, 0), Error);
    auto center = Desc("halton");
    AddBool(center, "samplepixelcenter", true);
    EXPECT_THROW(CreateSampler(center, 1, 0), Error);
}
