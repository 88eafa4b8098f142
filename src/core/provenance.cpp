#include "core/provenance.h"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <mutex>
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

void RecordInputFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
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
