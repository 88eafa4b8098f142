#include "render/display.h"

#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "core/error.h"

namespace gradus {

// ---------------------------------------------------------------- address

std::string DisplayAddress::str() const {
    return (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" + port;
}

DisplayAddress ParseDisplayAddress(const std::string &text) {
    const std::string what = "--display-server \"" + text + "\": ";
    const size_t colon = text.rfind(':');
    if (colon == std::string::npos) throw Error(what + "expected HOST:PORT (e.g. 127.0.0.1:14158)");
    DisplayAddress a;
    a.host = text.substr(0, colon);
    a.port = text.substr(colon + 1);
    if (a.host.size() >= 2 && a.host.front() == '[' && a.host.back() == ']') a.host = a.host.substr(1, a.host.size() - 2);
    if (a.host.empty()) throw Error(what + "no host before the port");
    const bool digits = !a.port.empty() && a.port.size() <= 5 &&
                        std::all_of(a.port.begin(), a.port.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits || std::stoi(a.port) < 1 || std::stoi(a.port) > 65535)
        throw Error(what + "the port must be a number in [1, 65535], got \"" + a.port + "\"");
    addrinfo hints{}, *res = nullptr;
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    const int err = getaddrinfo(a.host.c_str(), a.port.c_str(), &hints, &res);
    if (err != 0) throw Error(what + "cannot resolve host \"" + a.host + "\" (" + gai_strerror(err) + ")");
    freeaddrinfo(res);
    return a;
}

// ---------------------------------------------------------------- packets

namespace tev {
namespace {

struct Packet {
    std::string b;
    explicit Packet(uint8_t type) {
        b.assign(4, '\0');  // the length, set by done()
        b.push_back(char(type));
    }
    template <class T>
    void le(T v, int bytes) {  // little-endian, whatever the host
        uint64_t u = uint64_t(v);
        for (int i = 0; i < bytes; ++i) b.push_back(char((u >> (8 * i)) & 0xff));
    }
    void i32(int32_t v) { le(uint32_t(v), 4); }
    void i64(int64_t v) { le(uint64_t(v), 8); }
    void boolean(bool v) { b.push_back(v ? 1 : 0); }
    void str(const std::string &s) {
        b += s;
        b.push_back('\0');
    }
    void f32(float v) {
        uint32_t u;
        std::memcpy(&u, &v, 4);
        le(u, 4);
    }
    std::string done() {
        const uint32_t n = uint32_t(b.size());
        for (int i = 0; i < 4; ++i) b[size_t(i)] = char((n >> (8 * i)) & 0xff);
        return std::move(b);
    }
};

}  // namespace

std::string CreateImagePacket(const std::string &name, int width, int height, const std::vector<std::string> &channels) {
    Packet p(kCreateImage);
    p.boolean(true);  // grab focus
    p.str(name);
    p.i32(width);
    p.i32(height);
    p.i32(int32_t(channels.size()));
    for (const auto &c : channels) p.str(c);
    return p.done();
}

std::string UpdateImagePacket(const std::string &name, const std::vector<std::string> &channels, int x, int y,
                              int width, int height, const float *values) {
    Packet p(kUpdateImageV3);
    const int k = int(channels.size());
    p.b.reserve(64 + name.size() + size_t(k) * 24 + size_t(width) * size_t(height) * size_t(k) * 4);
    p.boolean(false);
    p.str(name);
    p.i32(k);
    for (const auto &c : channels) p.str(c);
    for (int v : {x, y, width, height}) p.i32(v);
    for (int c = 0; c < k; ++c) p.i64(c);  // offsets: interleaved ...
    for (int c = 0; c < k; ++c) p.i64(k);  // ... strides
    for (size_t i = 0; i < size_t(width) * size_t(height) * size_t(k); ++i) p.f32(values[i]);
    return p.done();
}

}  // namespace tev

// ---------------------------------------------------------------- client

FilmDisplay::FilmDisplay(const DisplayAddress &address, Film &film, const std::string &name, bool layers, bool quiet)
    : address_(address), film_(film), name_(name), wantLayers_(layers), quiet_(quiet), bounds_(film.pixelBounds()) {
    channels_ = {"R", "G", "B"};
    if (layers)
        for (int l = 0; l < film.numLayers(); ++l) {
            if (!film.layerWritten(l)) continue;
            layers_.push_back(l);
            for (const std::string &c : Image::LayerRGBNames(film.layerName(l))) channels_.push_back(c);
        }
    tilesX_ = (bounds_.width() + kTileSize - 1) / kTileSize;
    tilesY_ = (bounds_.height() + kTileSize - 1) / kTileSize;
    const size_t n = size_t(tilesX_) * size_t(tilesY_);
    changed_.reset(new std::atomic<uint32_t>[n]);
    for (size_t i = 0; i < n; ++i) changed_[i] = 1;  // everything is sent once (a resumed film is not black)
    sent_.assign(n, 0);
    film_.setWatcher(this);
    thread_ = std::thread([this] { run(); });
}

FilmDisplay::~FilmDisplay() {
    if (watching_) film_.setWatcher(nullptr);
    {
        std::lock_guard<std::mutex> lock(m_);
        stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) close(fd_);
}

void FilmDisplay::finish(const Image &final) {
    film_.setWatcher(nullptr);
    watching_ = false;
    {
        std::lock_guard<std::mutex> lock(m_);
        final_ = &final;
        stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
}

void FilmDisplay::merged(const Bounds2i &b, bool all) {
    const int x0 = all ? 0 : (b.pMin.x - bounds_.pMin.x) / kTileSize;
    const int y0 = all ? 0 : (b.pMin.y - bounds_.pMin.y) / kTileSize;
    const int x1 = all ? tilesX_ - 1 : (b.pMax.x - 1 - bounds_.pMin.x) / kTileSize;
    const int y1 = all ? tilesY_ - 1 : (b.pMax.y - 1 - bounds_.pMin.y) / kTileSize;
    for (int ty = y0; ty <= y1; ++ty)
        for (int tx = x0; tx <= x1; ++tx) changed_[size_t(ty) * tilesX_ + tx].fetch_add(1, std::memory_order_relaxed);
}

void FilmDisplay::warn(const std::string &what) {
    if (warned_) return;
    warned_ = true;
    std::fprintf(stderr, "%sgradus: warning: display server %s: %s; the render goes on without it\n",
                 quiet_ ? "" : "\n", address_.str().c_str(), what.c_str());
}

bool FilmDisplay::connectToViewer() {
    addrinfo hints{}, *res = nullptr;
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    if (int err = getaddrinfo(address_.host.c_str(), address_.port.c_str(), &hints, &res); err != 0) {
        warn(std::string("cannot resolve the host (") + gai_strerror(err) + ")");
        return false;
    }
    std::string failure = "no address";
    for (addrinfo *a = res; a && fd_ < 0; a = a->ai_next) {
        int fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
        if (fd < 0) continue;
        // Non-blocking connect, waited for at most 3 s (in slices, so that
        // the destructor's stop is seen; finish() waits for it).
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
        int rc = ::connect(fd, a->ai_addr, a->ai_addrlen), err = rc == 0 ? 0 : errno;
        if (err == EINPROGRESS) {
            err = ETIMEDOUT;
            for (int waited = 0; waited < 3000; waited += 100) {
                {
                    std::lock_guard<std::mutex> lock(m_);
                    if (stop_ && !final_) {  // the render failed: give up quietly
                        close(fd);
                        freeaddrinfo(res);
                        return false;
                    }
                }
                pollfd p{fd, POLLOUT, 0};
                if (poll(&p, 1, 100) > 0) {
                    socklen_t len = sizeof err;
                    getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
                    break;
                }
            }
        }
        if (err != 0) {
            failure = std::strerror(err);
            close(fd);
            continue;
        }
        fd_ = fd;  // stays non-blocking: send() waits with poll()
    }
    freeaddrinfo(res);
    if (fd_ < 0) warn("cannot connect (" + failure + ")");
    return fd_ >= 0;
}

// A packet that is not out kStallMilliseconds after its first byte was
// offered drops the viewer (a stalled or far too slow one).
bool FilmDisplay::send(const std::string &packet) {
    using Clock = std::chrono::steady_clock;
    const auto deadline = Clock::now() + std::chrono::milliseconds(kStallMilliseconds);
    size_t off = 0;
    std::string failure;
    while (off < packet.size()) {
        const ssize_t n = ::send(fd_, packet.data() + off, packet.size() - off, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (n > 0) {
            off += size_t(n);
            continue;
        }
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
            pollfd p{fd_, POLLOUT, 0};
            const int ready = left > 0 ? poll(&p, 1, int(left)) : 0;
            if (ready > 0 || (ready < 0 && errno == EINTR)) continue;
            failure = "a packet still unsent after " + std::to_string(kStallMilliseconds / 1000) + " s";
        } else {
            failure = n < 0 ? std::strerror(errno) : "closed";
        }
        warn("the connection was lost (" + failure + ")");
        close(fd_);
        fd_ = -1;
        return false;
    }
    return true;
}

// The tiles the film's merges changed since they were last sent, or (final)
// every tile of the final image.
bool FilmDisplay::sendTiles(const Image *final) {
    const bool all = final != nullptr;
    const size_t k = channels_.size();
    std::vector<float> values;
    std::vector<int> index;
    if (final)
        for (const auto &c : channels_) index.push_back(final->channelIndex(c));  // -1: zeros
    for (int ty = 0; ty < tilesY_; ++ty)
        for (int tx = 0; tx < tilesX_; ++tx) {
            const size_t t = size_t(ty) * tilesX_ + tx;
            const uint32_t c = changed_[t].load(std::memory_order_relaxed);
            if (!all && c == sent_[t]) continue;
            const int x = tx * kTileSize, y = ty * kTileSize;
            const int w = std::min(kTileSize, bounds_.width() - x), h = std::min(kTileSize, bounds_.height() - y);
            values.assign(size_t(w) * size_t(h) * k, 0.f);
            if (final) {
                for (int j = 0; j < h; ++j)
                    for (int i = 0; i < w; ++i)
                        for (size_t ch = 0; ch < k; ++ch)
                            if (index[ch] >= 0)
                                values[(size_t(j) * w + i) * k + ch] = final->at(x + i, y + j, index[ch]);
            } else {
                Bounds2i b{{bounds_.pMin.x + x, bounds_.pMin.y + y}, {bounds_.pMin.x + x + w, bounds_.pMin.y + y + h}};
                film_.readPixels(b, layers_, values.data());
            }
            if (!send(tev::UpdateImagePacket(name_, channels_, x, y, w, h, values.data()))) return false;
            sent_[t] = c;
        }
    return true;
}

void FilmDisplay::run() {
    if (!connectToViewer()) return;
    if (!send(tev::CreateImagePacket(name_, bounds_.width(), bounds_.height(), channels_))) return;
    std::unique_lock<std::mutex> lock(m_);
    while (!stop_) {
        cv_.wait_for(lock, std::chrono::milliseconds(kUpdateMilliseconds), [&] { return stop_; });
        if (stop_) break;
        lock.unlock();
        const bool ok = sendTiles(nullptr);
        lock.lock();
        if (!ok) return;
    }
    const Image *final = final_;
    lock.unlock();
    if (final && final->width() == bounds_.width() && final->height() == bounds_.height()) {
        // With layers: every channel of the output (e.g. a gradient integrator's
        // reconstructions), in an image created anew under the same name.
        if (wantLayers_ && final->channelNames() != channels_) {
            channels_ = final->channelNames();
            if (!send(tev::CreateImagePacket(name_, bounds_.width(), bounds_.height(), channels_))) return;
        }
        if (!sendTiles(final)) return;
    }
    close(fd_);  // the viewer sees the end of the stream
    fd_ = -1;
}

}  // namespace gradus
