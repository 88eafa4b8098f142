// Checkpoint files and film states: round trip, refusal of every truncation
// and of every corrupted byte, and the rules of merging partial renders.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>

#include "job/checkpoint.h"
#include "render/film.h"

using namespace gradus;

namespace {

std::string TempPath(const std::string &name) {
    return "/tmp/gradus_ckpt_test_" + std::to_string(::getpid()) + "_" + name;
}

std::string ReadAll(const std::string &p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteAll(const std::string &p, const std::string &s) { std::ofstream(p, std::ios::binary) << s; }

std::unique_ptr<Film> SmallFilm(int w = 4, int h = 3) {
    const Float crop[4] = {0, 1, 0, 1};
    auto f = std::make_unique<Film>(Point2i{w, h}, crop, CreateFilter(EntityDesc()), "x.exr", 1);
    f->addLayer("primal");
    return f;
}

// The state of `film` after every accumulator was set to v (through a film
// tile would need a sampler; the layout is documented in film.cpp: header,
// then per array a tag byte and its doubles).
std::string StateOf(const Film &film, double v) {
    std::string s = film.saveState();  // all arrays zero: header + one tag byte per array
    const size_t n = size_t(film.pixelBounds().area());
    std::vector<size_t> sizes = {3 * n, n, 3 * n, n};
    for (int l = 0; l < film.numLayers(); ++l) sizes.insert(sizes.end(), {3 * n, 3 * n});
    std::string out = s.substr(0, s.size() - sizes.size());
    for (size_t count : sizes) {
        out.push_back(v == 0 ? 0 : 1);
        if (v != 0)
            for (size_t i = 0; i < count; ++i) out.append(reinterpret_cast<const char *>(&v), sizeof v);
    }
    return out;
}

Checkpoint Sample(int a, int b, const std::string &film) {
    Checkpoint c;
    c.identity = "scene_hash: x\nspp: 6\n";
    c.integrator = "path";
    c.seed = 7;
    c.passBegin = c.sppBegin = a;
    c.passEnd = c.sppEnd = b;
    c.complete = b == 6;
    c.seconds = 1.5;
    c.nonFinite = 2;
    c.film = film;
    return c;
}

TEST(Checkpoint, RoundTrip) {
    auto film = SmallFilm();
    Checkpoint c = Sample(2, 5, StateOf(*film, 0.25));
    c.state = std::string("\0mlt\xff", 5);
    const std::string p = TempPath("rt.ckpt");
    WriteCheckpoint(p, c);
    EXPECT_TRUE(IsCheckpointFile(p));
    EXPECT_FALSE(std::ifstream(p + ".tmp").good()) << "the temporary file must be renamed";
    Checkpoint r = ReadCheckpoint(p);
    EXPECT_EQ(r.identity, c.identity);
    EXPECT_EQ(r.integrator, c.integrator);
    EXPECT_EQ(r.seed, c.seed);
    EXPECT_EQ(r.passBegin, 2);
    EXPECT_EQ(r.passEnd, 5);
    EXPECT_EQ(r.sppBegin, 2);
    EXPECT_EQ(r.sppEnd, 5);
    EXPECT_FALSE(r.complete);
    EXPECT_EQ(r.seconds, 1.5);
    EXPECT_EQ(r.nonFinite, 2u);
    EXPECT_EQ(r.film, c.film);
    EXPECT_EQ(r.state, c.state);
    std::remove(p.c_str());
}

// The bytes of a small complete checkpoint, and a reader of variants of it:
// "" when a variant is accepted, else the error's message.
struct Variants {
    std::string data, path = TempPath("variant.ckpt");
    Variants() {
        auto film = SmallFilm(2, 2);
        const std::string p = TempPath("full.ckpt");
        WriteCheckpoint(p, Sample(0, 6, StateOf(*film, 1)));
        data = ReadAll(p);
        std::remove(p.c_str());
    }
    ~Variants() { std::remove(path.c_str()); }
    std::string refusal(const std::string &bytes) const {
        WriteAll(path, bytes);
        try {
            ReadCheckpoint(path);
        } catch (const Error &e) {
            return e.what();
        }
        return "";
    }
};

// Every prefix of a checkpoint is refused with a message naming the file (never read as data).
TEST(Checkpoint, EveryTruncationIsRefused) {
    Variants v;
    for (size_t n = 0; n < v.data.size(); ++n) {
        const std::string e = v.refusal(v.data.substr(0, n));
        EXPECT_FALSE(e.empty()) << "a checkpoint cut to " << n << " of " << v.data.size() << " bytes was accepted";
        EXPECT_NE(e.find(v.path), std::string::npos) << e;
    }
}

// Every single corrupted byte (magic, version, length, payload, checksum) is refused.
TEST(Checkpoint, EveryCorruptedByteIsRefused) {
    Variants v;
    for (size_t i = 0; i < v.data.size(); ++i) {
        std::string bad = v.data;
        bad[i] = char(bad[i] ^ 0x10);
        EXPECT_FALSE(v.refusal(bad).empty()) << "byte " << i << " flipped was accepted";
    }
}

TEST(Checkpoint, NotACheckpoint) {
    const std::string p = TempPath("image.exr");
    WriteAll(p, "\x76\x2f\x31\x01 an EXR header, not a checkpoint");
    EXPECT_FALSE(IsCheckpointFile(p));
    EXPECT_THROW(ReadCheckpoint(p), Error);
    EXPECT_THROW(ReadCheckpoint(TempPath("missing.ckpt")), Error);
    std::remove(p.c_str());
}

TEST(Checkpoint, MergeSumsDisjointRangesInAnyOrder) {
    auto film = SmallFilm();
    std::vector<Checkpoint> parts = {Sample(3, 6, StateOf(*film, 4)), Sample(0, 1, StateOf(*film, 1)),
                                     Sample(1, 3, StateOf(*film, 2))};
    Checkpoint m = MergeCheckpoints(parts, {"c", "a", "b"});
    EXPECT_EQ(m.passBegin, 0);
    EXPECT_EQ(m.passEnd, 6);
    EXPECT_EQ(m.sppEnd, 6);
    EXPECT_TRUE(m.complete);
    EXPECT_EQ(m.seconds, 4.5);
    EXPECT_EQ(m.nonFinite, 6u);
    EXPECT_EQ(m.film, StateOf(*film, 7));
    film->loadState(m.film);  // a state of this film
}

TEST(Checkpoint, MergeRefusesGapsOverlapsForeignRendersAndState) {
    auto film = SmallFilm();
    const std::string s = StateOf(*film, 1);
    auto error = [](std::vector<Checkpoint> parts) {
        try {
            MergeCheckpoints(parts, {"one", "two"});
        } catch (const Error &e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_NE(error({Sample(0, 2, s), Sample(3, 6, s)}).find("gap"), std::string::npos);
    EXPECT_NE(error({Sample(0, 3, s), Sample(2, 6, s)}).find("overlap"), std::string::npos);
    EXPECT_NE(error({Sample(1, 3, s), Sample(3, 6, s)}).find("pass 0"), std::string::npos);
    Checkpoint other = Sample(2, 6, s);
    other.seed = 8;
    EXPECT_NE(error({Sample(0, 2, s), other}).find("another render"), std::string::npos);
    other = Sample(2, 6, s);
    other.identity += "x";
    EXPECT_NE(error({Sample(0, 2, s), other}).find("another render"), std::string::npos);
    Checkpoint withState = Sample(2, 6, s);
    withState.state = "chains";
    EXPECT_NE(error({Sample(0, 2, s), withState}).find("depend on each other"), std::string::npos);
    auto bigger = SmallFilm(5, 3);
    EXPECT_NE(error({Sample(0, 2, s), Sample(2, 6, StateOf(*bigger, 1))}).find("different films"), std::string::npos);
}

TEST(FilmState, RoundTripAndRefusals) {
    auto film = SmallFilm();
    const std::string s = StateOf(*film, 0.5);
    film->loadState(s);
    EXPECT_EQ(film->saveState(), s);
    auto other = SmallFilm(3, 4);
    EXPECT_THROW(other->loadState(s), Error);  // other bounds
    auto moreLayers = SmallFilm();
    moreLayers->addLayer("dx");
    EXPECT_THROW(moreLayers->loadState(s), Error);  // other layers
    EXPECT_THROW(film->loadState(s.substr(0, s.size() - 8)), Error);
    EXPECT_THROW(film->loadState("FILM"), Error);
}

}  // namespace
