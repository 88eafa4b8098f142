#include "core/provenance.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <vector>

namespace gradus {

namespace {
std::mutex gMutex;
std::vector<uint64_t> gHashes;
uint64_t gBytes = 0;
}  // namespace

uint64_t HashBytes(const void *data, size_t n, uint64_t h) {
    const unsigned char *p = static_cast<const unsigned char *>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ULL;
    return h;
}

void RecordInputFile(const std::string &, const void *data, size_t n) {
    uint64_t h = HashBytes(data, n);
    std::lock_guard<std::mutex> lock(gMutex);
    gHashes.push_back(h);
    gBytes += n;
}

namespace {
template <class Bytes>
FileRead ReadInto(const std::string &path, Bytes *out) {
    out->clear();
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) return FileRead::ReadError;  // opens, but has nothing to read
    std::ifstream in(path, std::ios::binary);
    if (!in) return FileRead::CannotOpen;
    const auto size = std::filesystem::is_regular_file(path, ec) ? std::filesystem::file_size(path, ec) : 0;
    if (size > 0 && !ec) {
        out->resize(size_t(size));
        if (!in.read(reinterpret_cast<char *>(&(*out)[0]), std::streamsize(size))) {
            out->clear();
            return FileRead::ReadError;
        }
        return FileRead::Ok;
    }
    // Pipes and devices (a scene on /dev/stdin) have no size: read to the end.
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) return FileRead::ReadError;
    const std::string text = ss.str();
    out->assign(text.begin(), text.end());
    return FileRead::Ok;
}
}  // namespace

FileRead ReadFileBytes(const std::string &path, std::string *out) { return ReadInto(path, out); }
FileRead ReadFileBytes(const std::string &path, std::vector<unsigned char> *out) { return ReadInto(path, out); }

void RecordInputFile(const std::string &path) {
    std::string bytes;
    ReadFileBytes(path, &bytes);  // an unreadable file records as empty, as before
    RecordInputFile(path, bytes.data(), bytes.size());
}

InputFilesSummary InputFiles() {
    std::lock_guard<std::mutex> lock(gMutex);
    InputFilesSummary s;
    s.files = int(gHashes.size());
    s.bytes = gBytes;
    uint64_t h = HashBytes(gHashes.data(), gHashes.size() * sizeof(uint64_t));
    char buf[24];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
    s.hash = buf;
    return s;
}

void ResetInputFiles() {
    std::lock_guard<std::mutex> lock(gMutex);
    gHashes.clear();
    gBytes = 0;
}

}  // namespace gradus
