// Provenance of a render: the input files it read (scene, includes, meshes,
// textures, spectra) and a hash of their contents, and the build's version.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace gradus {

// 64-bit FNV-1a of a byte range, continuing from `h`.
uint64_t HashBytes(const void *data, size_t n, uint64_t h = 0xcbf29ce484222325ULL);

// The loaders' whole-file reader: one sized read for regular files
// (std::istreambuf_iterator reads a byte at a time: veach-ajar's PLY meshes
// were read twice that way, 0.1 s of its load), pipes and devices to their end.
enum class FileRead { Ok, CannotOpen, ReadError };
FileRead ReadFileBytes(const std::string &path, std::string *out);
FileRead ReadFileBytes(const std::string &path, std::vector<unsigned char> *out);

// Records that the renderer read an input file (thread-safe). Readers of
// scene inputs call it with the file's bytes.
void RecordInputFile(const std::string &path, const void *data, size_t n);
// Reads a file only to record it (for readers that stream).
void RecordInputFile(const std::string &path);

struct InputFilesSummary {
    int files = 0;
    uint64_t bytes = 0;
    std::string hash;  // hex: hash of the per-file content hashes in read order
};
InputFilesSummary InputFiles();
void ResetInputFiles();

// Version and git commit of the build (set at build time).
const char *GradusVersion();
const char *GradusGitCommit();

}  // namespace gradus
