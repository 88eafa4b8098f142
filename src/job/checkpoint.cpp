#include "job/checkpoint.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

#include "core/error.h"
#include "core/provenance.h"
#include "render/film.h"

namespace gradus {
namespace {

// File layout: magic (8 bytes) | version u32 | payload length u64 | payload |
// FNV-1a 64 of the payload. Payload: length-prefixed strings and fixed-size
// numbers in the order of the fields of Checkpoint.
const char kMagic[8] = {'G', 'R', 'A', 'D', 'C', 'K', 'P', 'T'};
constexpr uint32_t kVersion = 1;

class Writer {
  public:
    template <typename T>
    void num(T v) { s.append(reinterpret_cast<const char *>(&v), sizeof v); }
    void str(const std::string &v) {
        num<uint64_t>(v.size());
        s += v;
    }
    std::string s;
};

class Reader {
  public:
    // Reads s[begin, end).
    Reader(const std::string &s, size_t begin, size_t end, const std::string &file)
        : s_(s), file_(file), at_(begin), end_(end) {}
    template <typename T>
    T num() {
        need(sizeof(T));
        T v;
        std::memcpy(&v, s_.data() + at_, sizeof v);
        at_ += sizeof v;
        return v;
    }
    std::string str() {
        uint64_t n = num<uint64_t>();
        need(n);
        std::string v = s_.substr(at_, n);
        at_ += n;
        return v;
    }
    bool done() const { return at_ == end_; }

  private:
    void need(uint64_t n) const {
        if (end_ - at_ < n) throw Error(file_ + ": checkpoint payload is inconsistent (a field runs past its end)");
    }
    const std::string &s_;
    const std::string &file_;
    size_t at_, end_;
};

// The payload as pieces (the film and state strings are not copied): the
// fixed fields, then each string with its length.
std::vector<std::pair<const char *, size_t>> PayloadPieces(const Checkpoint &c, std::string *fixed,
                                                           uint64_t lengths[4]) {
    Writer w;
    w.num<uint64_t>(c.seed);
    w.num<int32_t>(c.passBegin);
    w.num<int32_t>(c.passEnd);
    w.num<int32_t>(c.sppBegin);
    w.num<int32_t>(c.sppEnd);
    w.num<uint8_t>(c.complete ? 1 : 0);
    w.num<double>(c.seconds);
    w.num<uint64_t>(c.nonFinite);
    *fixed = std::move(w.s);
    lengths[0] = c.identity.size(), lengths[1] = c.integrator.size(), lengths[2] = c.film.size(),
    lengths[3] = c.state.size();
    return {{reinterpret_cast<const char *>(&lengths[0]), 8}, {c.identity.data(), c.identity.size()},
            {reinterpret_cast<const char *>(&lengths[1]), 8}, {c.integrator.data(), c.integrator.size()},
            {fixed->data(), fixed->size()},
            {reinterpret_cast<const char *>(&lengths[2]), 8}, {c.film.data(), c.film.size()},
            {reinterpret_cast<const char *>(&lengths[3]), 8}, {c.state.data(), c.state.size()}};
}

[[noreturn]] void SysFail(const std::string &what, const std::string &path) {
    throw Error("checkpoint: cannot " + what + " \"" + path + "\": " + std::strerror(errno));
}

}  // namespace

void WriteCheckpoint(const std::string &path, const Checkpoint &c) {
    std::string fixed;
    uint64_t lengths[4];
    const auto pieces = PayloadPieces(c, &fixed, lengths);
    uint64_t size = 0, hash = HashBytes(nullptr, 0);
    for (const auto &p : pieces) {
        size += p.second;
        hash = HashBytes(p.first, p.second, hash);
    }
    Writer head;
    head.s.append(kMagic, 8);
    head.num<uint32_t>(kVersion);
    head.num<uint64_t>(size);
    const std::string tmp = path + ".tmp";
    int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) SysFail("create", tmp);
    auto writeAll = [&](const char *p, size_t n) {
        while (n > 0) {
            ssize_t k = ::write(fd, p, n);
            if (k < 0) {
                if (errno == EINTR) continue;
                int e = errno;
                ::close(fd);
                ::unlink(tmp.c_str());
                errno = e;
                SysFail("write", tmp);
            }
            p += k, n -= size_t(k);
        }
    };
    writeAll(head.s.data(), head.s.size());
    for (const auto &p : pieces) writeAll(p.first, p.second);
    writeAll(reinterpret_cast<const char *>(&hash), sizeof hash);
    if (::fsync(fd) != 0) {
        ::close(fd);
        SysFail("fsync", tmp);
    }
    if (::close(fd) != 0) SysFail("close", tmp);
    if (std::rename(tmp.c_str(), path.c_str()) != 0) SysFail("rename " + tmp + " to", path);
    // The rename itself is durable once the directory is synced.
    size_t slash = path.find_last_of('/');
    std::string dir = slash == std::string::npos ? "." : path.substr(0, std::max<size_t>(1, slash));
    int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
    if (dfd >= 0) {
        ::fsync(dfd);
        ::close(dfd);
    }
}

bool IsCheckpointFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    char m[8] = {};
    in.read(m, 8);
    return in.gcount() == 8 && std::memcmp(m, kMagic, 8) == 0;
}

Checkpoint ReadCheckpoint(const std::string &path) {
    std::string data;
    if (ReadFileBytes(path, &data) == FileRead::CannotOpen)
        throw Error(path + ": cannot open checkpoint: " + std::strerror(errno));
    if (data.size() < 20 || std::memcmp(data.data(), kMagic, 8) != 0)
        throw Error(path + ": not a Gradus checkpoint (no checkpoint header)");
    uint32_t version;
    uint64_t len;
    std::memcpy(&version, data.data() + 8, 4);
    std::memcpy(&len, data.data() + 12, 8);
    if (version != kVersion)
        throw Error(path + ": checkpoint version " + std::to_string(version) + " (this build reads version " +
                    std::to_string(kVersion) + ")");
    if (len > data.size() || data.size() - 20 < len || data.size() - 20 - len != 8)
        throw Error(path + ": truncated or padded checkpoint (" + std::to_string(data.size()) + " bytes, the header says " +
                    std::to_string(len + 28) + ")");
    uint64_t stored;
    std::memcpy(&stored, data.data() + 20 + len, 8);
    if (HashBytes(data.data() + 20, len) != stored) throw Error(path + ": corrupted checkpoint (checksum mismatch)");
    Reader r(data, 20, 20 + len, path);
    Checkpoint c;
    c.identity = r.str();
    c.integrator = r.str();
    c.seed = r.num<uint64_t>();
    c.passBegin = r.num<int32_t>();
    c.passEnd = r.num<int32_t>();
    c.sppBegin = r.num<int32_t>();
    c.sppEnd = r.num<int32_t>();
    c.complete = r.num<uint8_t>() != 0;
    c.seconds = r.num<double>();
    c.nonFinite = r.num<uint64_t>();
    c.film = r.str();
    c.state = r.str();
    if (!r.done()) throw Error(path + ": checkpoint payload is inconsistent (trailing bytes)");
    if (c.passBegin < 0 || c.passEnd < c.passBegin || c.sppBegin < 0 || c.sppEnd < c.sppBegin)
        throw Error(path + ": checkpoint pass range is inconsistent");
    return c;
}

Checkpoint MergeCheckpoints(const std::vector<Checkpoint> &parts, const std::vector<std::string> &names) {
    if (parts.empty()) throw Error("merge: no checkpoints");
    std::vector<size_t> order(parts.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return parts[a].passBegin < parts[b].passBegin; });
    const Checkpoint &first = parts[order[0]];
    auto name = [&](size_t i) { return i < names.size() ? names[i] : "checkpoint " + std::to_string(i); };
    Checkpoint m = first;
    if (first.passBegin != 0)
        throw Error("merge: no checkpoint holds pass 0 (the first begins at pass " + std::to_string(first.passBegin) +
                    ": " + name(order[0]) + ")");
    for (size_t k = 1; k < order.size(); ++k) {
        const Checkpoint &p = parts[order[k]];
        if (p.identity != first.identity || p.integrator != first.integrator || p.seed != first.seed)
            throw Error("merge: " + name(order[k]) + " is a checkpoint of another render than " + name(order[0]) +
                        " (scene, integrator, parameters, spp or seed differ)");
        if (p.passBegin != m.passEnd || p.sppBegin != m.sppEnd)
            throw Error("merge: " + name(order[k]) + " holds passes [" + std::to_string(p.passBegin) + ", " +
                        std::to_string(p.passEnd) + "), but the checkpoints before it end at pass " +
                        std::to_string(m.passEnd) + (p.passBegin < m.passEnd ? " (overlap)" : " (gap)"));
        if (!p.state.empty() || !m.state.empty())
            throw Error("merge: " + name(order[k]) + ": this integrator's passes depend on each other (its state cannot be summed)");
        m.film = Film::AddStates(m.film, p.film);
        m.passEnd = p.passEnd;
        m.sppEnd = p.sppEnd;
        m.complete = p.complete;
        m.seconds += p.seconds;
        m.nonFinite += p.nonFinite;
    }
    return m;
}

std::string DescribeCheckpoint(const Checkpoint &c) {
    std::ostringstream o;
    o << "integrator: " << c.integrator << "\nseed: " << c.seed << "\npasses: [" << c.passBegin << ", " << c.passEnd
      << ")\nsamples per pixel: [" << c.sppBegin << ", " << c.sppEnd << ")\ncomplete: " << (c.complete ? "yes" : "no")
      << "\nrender seconds: " << c.seconds << "\nnon-finite contributions discarded: " << c.nonFinite
      << "\nfilm state bytes: " << c.film.size() << "\nintegrator state bytes: " << c.state.size()
      << "\nrender identity:\n" << c.identity;
    return o.str();
}

}  // namespace gradus
