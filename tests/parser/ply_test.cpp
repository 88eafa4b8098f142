// PLY reader: ASCII and binary (both byte orders), property orders and types,
// quads, and malformed input (errors, never crashes).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sys/stat.h>
#include <thread>
#include <unistd.h>
#include <string>
#include <vector>

#include "core/provenance.h"
#include "parser/ply.h"
#include "parser/scene_desc.h"

using namespace gradus;

namespace {

// Builds a binary PLY body value by value in the requested byte order.
struct BinWriter {
    bool bigEndian;
    std::string out;
    template <typename T>
    void put(T v) {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        if (bigEndian)
            for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
        out.append(reinterpret_cast<const char *>(b), sizeof(T));
    }
};

// A quad and a triangle; the vertex element lists properties out of the
// usual order, with extra ones, mixed types and an extra element before faces.
std::string BinaryPly(bool bigEndian) {
    std::string h = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\ncomment test\n"
                    "element vertex 5\n"
                    "property double z\nproperty uchar red\nproperty float x\nproperty float y\n"
                    "property float s\nproperty float t\nproperty list uchar int extra\n"
                    "element edge 1\nproperty int a\nproperty int b\n"
                    "element face 2\n"
                    "property uchar flags\nproperty list uint8 uint vertex_indices\n"
                    "end_header\n";
    BinWriter w{bigEndian, ""};
    for (int i = 0; i < 5; ++i) {
        w.put<double>(0.5 * i);       // z
        w.put<uint8_t>(200);          // red
        w.put<float>(float(i));       // x
        w.put<float>(float(-i));      // y
        w.put<float>(0.25f * i);      // s
        w.put<float>(1 - 0.25f * i);  // t
        w.put<uint8_t>(2);            // extra list of 2 ints
        w.put<int32_t>(7);
        w.put<int32_t>(8);
    }
    w.put<int32_t>(0);  // edge
    w.put<int32_t>(1);
    w.put<uint8_t>(1);  // face 0: quad
    w.put<uint8_t>(4);
    for (uint32_t v : {0u, 1u, 2u, 3u}) w.put<uint32_t>(v);
    w.put<uint8_t>(0);  // face 1: triangle
    w.put<uint8_t>(3);
    for (uint32_t v : {2u, 3u, 4u}) w.put<uint32_t>(v);
    return h + w.out;
}

PlyMesh FromString(const std::string &s, const std::string &name = "mem.ply") {
    return ReadPlyFromMemory(s.data(), s.size(), name);
}

std::string ErrorOf(const std::string &s) {
    try {
        FromString(s);
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

const char *kAsciiTri =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

}  // namespace

TEST(Ply, AsciiWithNormalsAndUV) {
    PlyMesh m = ReadPly(std::string(GRADUS_SOURCE_DIR) + "/tests/parser/data/quad.ply");
    ASSERT_EQ(m.P.size(), 4u);
    ASSERT_EQ(m.N.size(), 4u);
    ASSERT_EQ(m.uv.size(), 4u);
    EXPECT_EQ(m.P[2], Point3(1, 1, 0));
    EXPECT_EQ(m.N[0], Normal3(0, 0, 1));
    EXPECT_EQ(m.uv[3], Point2(0, 1));
    // Quad split into two triangles with the same winding.
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 0, 2, 3}));
}

TEST(Ply, AsciiTriangleWithCrLf) {
    std::string s = kAsciiTri;
    std::string crlf;
    for (char c : s) {
        if (c == '\n') crlf += '\r';
        crlf += c;
    }
    PlyMesh m = FromString(crlf);
    EXPECT_EQ(m.P.size(), 3u);
    EXPECT_TRUE(m.N.empty());
    EXPECT_TRUE(m.uv.empty());
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2}));
}

class PlyBinary : public ::testing::TestWithParam<bool> {};

TEST_P(PlyBinary, AnyPropertyOrderAndTypes) {
    PlyMesh m = FromString(BinaryPly(GetParam()));
    ASSERT_EQ(m.P.size(), 5u);
    for (int i = 0; i < 5; ++i) {
        EXPECT_EQ(m.P[i], Point3(i, -i, 0.5 * i));
        EXPECT_EQ(m.uv[i], Point2(0.25 * i, 1 - 0.25 * i));  // s t
    }
    EXPECT_TRUE(m.N.empty());
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 0, 2, 3, 2, 3, 4}));
}

TEST_P(PlyBinary, TruncationAnywhereIsAnErrorNamingTheFile) {
    std::string full = BinaryPly(GetParam());
    size_t header = full.find("end_header\n") + 11;
    for (size_t cut = header; cut < full.size(); ++cut) {
        try {
            FromString(full.substr(0, cut), "cut.ply");
            ADD_FAILURE() << "no error at cut " << cut;
        } catch (const Error &e) {
            std::string m = e.what();
            EXPECT_EQ(m.rfind("cut.ply: truncated PLY file", 0), 0u) << m;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Endianness, PlyBinary, ::testing::Values(false, true),
                         [](const auto &info) { return info.param ? "BigEndian" : "LittleEndian"; });

TEST(Ply, AlternativeUVNames) {
    std::string s =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float texture_u\nproperty float texture_v\n"
        "property float x\nproperty float y\nproperty float z\nproperty float nz\nproperty float nx\n"
        "property float ny\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
        "0.5 0.25 0 0 0 1 0 0\n0 0 1 0 0 1 0 0\n0 0 0 1 0 1 0 0\n3 2 1 0\n";
    PlyMesh m = FromString(s);
    EXPECT_EQ(m.uv[0], Point2(0.5, 0.25));
    EXPECT_EQ(m.N[0], Normal3(0, 0, 1));
    EXPECT_EQ(m.indices, (std::vector<int>{2, 1, 0}));
}

TEST(Ply, MalformedInputs) {
    std::string tri = kAsciiTri;
    auto replace = [&](const std::string &from, const std::string &to) {
        std::string s = tri;
        size_t p = s.find(from);
        EXPECT_NE(p, std::string::npos) << from;
        return s.replace(p, from.size(), to);
    };
    EXPECT_EQ(ErrorOf("plx\n"), "mem.ply:1: not a PLY file (missing 'ply' magic)");
    EXPECT_EQ(ErrorOf(""), "mem.ply:1: not a PLY file (missing 'ply' magic)");
    EXPECT_EQ(ErrorOf(tri.substr(0, tri.find("end_header"))), "mem.ply: truncated PLY header (no end_header)");
    EXPECT_EQ(ErrorOf(replace("end_header\n", "")), "mem.ply:9: unknown header keyword '0'");
    EXPECT_EQ(ErrorOf(replace("format ascii", "format utf8")), "mem.ply:2: unknown PLY format 'utf8'");
    EXPECT_EQ(ErrorOf(replace("property float z", "property quad z")), "mem.ply:6: unknown property type 'quad'");
    EXPECT_EQ(ErrorOf(replace("property float z", "property float w")), "mem.ply: vertex element lacks x, y or z");
    EXPECT_EQ(ErrorOf(replace("3 0 1 2", "5 0 1 2 0 1")),
              "mem.ply: face 0 has 5 vertices (only triangles and quads are supported)");
    EXPECT_EQ(ErrorOf(replace("3 0 1 2", "3 0 1 3")),
              "mem.ply: triangle 0 references vertex 3 but there are only 3 vertices");
    EXPECT_EQ(ErrorOf(replace("3 0 1 2", "3 0 -1 2")), "mem.ply: face 0: vertex index -1 out of range");
    EXPECT_EQ(ErrorOf(replace("1 0 0\n0 1 0", "1 0 0\n0 1 0x")), "mem.ply: malformed number '0x' in element 'vertex'");
    EXPECT_EQ(ErrorOf(replace("3 0 1 2\n", "3 0 1\n")),
              "mem.ply: truncated PLY file (unexpected end of data in element 'face')");
    EXPECT_EQ(ErrorOf(replace("element face 1", "element face 99999999999999")),
              "mem.ply: truncated PLY file (unexpected end of data in element 'face')");
    EXPECT_EQ(ErrorOf(replace("element vertex 3", "element vertex 3000000000000")),
              "mem.ply: too many vertices (3000000000000)");
    EXPECT_EQ(ErrorOf(replace("element vertex 3", "element vertex many")), "mem.ply:3: malformed element count 'many'");
}

TEST(Ply, MissingFileNamesIt) {
    try {
        ReadPly("/nonexistent/dir/mesh.ply");
        FAIL();
    } catch (const Error &e) {
        EXPECT_EQ(std::string(e.what()), "/nonexistent/dir/mesh.ply: cannot open PLY file");
    }
}

TEST(Ply, ReadFromTempFileAndPlymeshScene) {
    namespace fs = std::filesystem;
    fs::path dir = fs::temp_directory_path() / ("gradus_ply_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    {
        std::ofstream(dir / "m.ply", std::ios::binary) << BinaryPly(false);
        std::ofstream(dir / "s.pbrt") << "WorldBegin\nShape \"plymesh\" \"string filename\" \"m.ply\"\nWorldEnd\n";
    }
    SceneDesc s = ParseFile((dir / "s.pbrt").string());
    PlyMesh m = ReadPly(s.resolve(s.shapes[0].params.getString("filename", "")));
    EXPECT_EQ(m.indices.size(), 9u);
    // A truncated file on disk: the error names it.
    std::string full = BinaryPly(true);
    std::ofstream(dir / "t.ply", std::ios::binary) << full.substr(0, full.size() - 3);
    try {
        ReadPly((dir / "t.ply").string());
        ADD_FAILURE();
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find((dir / "t.ply").string()), std::string::npos);
    }
    fs::remove_all(dir);
}

// ReadFileBytes, the loader's one-read file reader: every byte back (NULs and
// all byte values, a size beyond one stream buffer), an empty file, a missing
// file, a directory and a named pipe; the provenance record of a PLY file hashes the bytes
// read (one record per ReadPly, with the file's size).
TEST(Ply, ReadFileBytesAndItsProvenanceRecord) {
    namespace fs = std::filesystem;
    fs::path dir = fs::temp_directory_path() / ("gradus_readbytes_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::string bytes(200003, '\0');
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = char((i * 131 + i / 7) & 0xff);
    std::ofstream(dir / "b.bin", std::ios::binary) << bytes;
    std::ofstream(dir / "e.bin", std::ios::binary).flush();
    std::string out = "stale";
    EXPECT_EQ(ReadFileBytes((dir / "b.bin").string(), &out), FileRead::Ok);
    EXPECT_TRUE(out == bytes);
    EXPECT_EQ(ReadFileBytes((dir / "e.bin").string(), &out), FileRead::Ok);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(ReadFileBytes((dir / "none.bin").string(), &out), FileRead::CannotOpen);
    EXPECT_EQ(ReadFileBytes(dir.string(), &out), FileRead::ReadError);
    EXPECT_TRUE(out.empty());
    // A pipe has no size (a scene given as /dev/stdin): read to its end.
    const std::string fifo = (dir / "pipe").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::thread writer([&] { std::ofstream(fifo, std::ios::binary) << bytes; });
    EXPECT_EQ(ReadFileBytes(fifo, &out), FileRead::Ok);
    writer.join();
    EXPECT_TRUE(out == bytes);

    const std::string ply = BinaryPly(false);
    std::ofstream(dir / "m.ply", std::ios::binary) << ply;
    ResetInputFiles();
    ReadPly((dir / "m.ply").string());
    const InputFilesSummary s = InputFiles();
    EXPECT_EQ(s.files, 1);
    EXPECT_EQ(s.bytes, ply.size());
    ResetInputFiles();
    RecordInputFile("m.ply", ply.data(), ply.size());
    EXPECT_EQ(InputFiles().hash, s.hash);
    ResetInputFiles();
    fs::remove_all(dir);
}

// Random byte mutations of valid files (fixed seed): the reader must either
// succeed with in-range indices or throw gradus::Error, never anything else.
TEST(Ply, RandomMutationsNeverCrash) {
    std::mt19937 rng(12345);
    const std::string seeds[] = {kAsciiTri, BinaryPly(false), BinaryPly(true)};
    int errors = 0, ok = 0;
    for (int iter = 0; iter < 3000; ++iter) {
        std::string s = seeds[iter % 3];
        int nmut = 1 + rng() % 4;
        for (int k = 0; k < nmut; ++k) {
            size_t p = rng() % s.size();
            switch (rng() % 3) {
                case 0: s[p] = char(rng()); break;
                case 1: s.erase(p, 1 + rng() % 8); break;
                default: s.insert(p, 1, char("0123456789 \n-."[rng() % 15])); break;
            }
            if (s.empty()) s = "p";
        }
        try {
            PlyMesh m = FromString(s);
            for (int i : m.indices) ASSERT_TRUE(i >= 0 && size_t(i) < m.P.size());
            ASSERT_TRUE(m.N.empty() || m.N.size() == m.P.size());
            ASSERT_TRUE(m.uv.empty() || m.uv.size() == m.P.size());
            ++ok;
        } catch (const Error &) {
            ++errors;
        }
    }
    EXPECT_GT(errors, 0);
    EXPECT_GT(ok, 0);
}
