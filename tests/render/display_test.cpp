// gradus --display-server: a loopback receiver written here (independently of
// render/display.cpp) decodes tev's packets and rebuilds the image; the last
// pixels it receives must equal the EXR's, for plain, cropped and layered
// renders. A refused connection, a viewer that stops reading and a bad
// address are checked too. (That the render does not wait on the viewer is
// by construction, a thread of its own; timings on a shared machine would not
// show it reliably.)
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "image/image.h"
#include "render/cli_fixture.h"

using namespace gradus;
using gradus::test::RunResult;
using DisplayTest = gradus::test::GradusCliTest;

namespace {

const char *kScene =
    "LookAt 0 0 -3  0 0 0  0 1 0\n"
    "Camera \"perspective\" \"float fov\" [40]\n"
    "Film \"image\" \"integer xresolution\" [70] \"integer yresolution\" [45] \"string filename\" [\"d.exr\"]\n"
    "WorldBegin\n"
    "LightSource \"point\" \"point from\" [0 0 -3] \"rgb I\" [5 5 5]\n"
    "Shape \"sphere\" \"float radius\" [1]\n"
    "Material \"matte\" \"rgb Kd\" [0.2 0.5 0.8]\n"
    "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point P\" [-3 -3 1 3 -3 1 3 3 1 -3 3 1]\n"
    "WorldEnd\n";

// Listens on 127.0.0.1 (an ephemeral port) and receives one connection's
// bytes until the sender closes it.
class Receiver {
  public:
    explicit Receiver(int rcvbuf = 0) {
        fd_ = socket(AF_INET, SOCK_STREAM, 0);
        if (rcvbuf > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        a.sin_port = 0;
        EXPECT_EQ(bind(fd_, reinterpret_cast<sockaddr *>(&a), sizeof a), 0);
        EXPECT_EQ(listen(fd_, 1), 0);
        socklen_t len = sizeof a;
        getsockname(fd_, reinterpret_cast<sockaddr *>(&a), &len);
        port_ = ntohs(a.sin_port);
    }
    ~Receiver() {
        if (thread_.joinable()) thread_.join();
        close(fd_);
    }
    int port() const { return port_; }
    // read = false: accept and never read (a stalled viewer), until stop().
    void start(bool read = true) {
        thread_ = std::thread([this, read] {
            pollfd p{fd_, POLLIN, 0};
            if (poll(&p, 1, 60000) <= 0) return;
            int c = accept(fd_, nullptr, nullptr);
            if (c < 0) return;
            char buf[1 << 16];
            while (read) {
                ssize_t n = recv(c, buf, sizeof buf, 0);
                if (n <= 0) break;
                bytes.append(buf, size_t(n));
            }
            while (!read && !stopped_) usleep(10000);
            close(c);
        });
    }
    void stop() { stopped_ = true; }
    void join() { thread_.join(); }
    std::string bytes;

  private:
    int fd_ = -1, port_ = 0;
    std::thread thread_;
    std::atomic<bool> stopped_{false};
};

// The image the packets leave in a viewer (tev semantics: CreateImage makes
// or replaces an image of zeros; UpdateImage writes a rectangle of channels
// at their offsets and strides).
struct Viewer {
    std::string name;
    int width = 0, height = 0;
    std::vector<std::string> channels;
    std::vector<std::vector<float>> planes;  // per channel, row-major
    std::map<int, int> packets;              // per type
};

struct Reader {
    const std::string &p;
    size_t at;
    template <class T>
    T get() {
        if (at + sizeof(T) > p.size()) throw std::runtime_error("packet too short");
        T v;
        std::memcpy(&v, p.data() + at, sizeof v);  // little-endian host (x86, arm64)
        at += sizeof v;
        return v;
    }
    std::string str() {
        size_t end = p.find('\0', at);
        if (end == std::string::npos) throw std::runtime_error("unterminated string");
        std::string s = p.substr(at, end - at);
        at = end + 1;
        return s;
    }
};

Viewer Decode(const std::string &bytes) {
    Viewer v;
    size_t at = 0;
    while (at < bytes.size()) {
        if (bytes.size() - at < 5) throw std::runtime_error("truncated packet header");
        uint32_t n;
        std::memcpy(&n, bytes.data() + at, 4);
        if (n < 5 || at + n > bytes.size()) throw std::runtime_error("bad packet length");
        const std::string p = bytes.substr(at, n);
        at += n;
        Reader r{p, 4};
        const int type = r.get<uint8_t>();
        v.packets[type]++;
        r.get<uint8_t>();  // grab focus
        const std::string name = r.str();
        if (type == 4) {  // CreateImage
            v.name = name;
            v.width = r.get<int32_t>();
            v.height = r.get<int32_t>();
            const int k = r.get<int32_t>();
            v.channels.clear();
            for (int c = 0; c < k; ++c) v.channels.push_back(r.str());
            v.planes.assign(size_t(k), std::vector<float>(size_t(v.width) * v.height, 0.f));
        } else if (type == 6) {  // UpdateImage V3
            if (name != v.name) throw std::runtime_error("update of an image never created");
            const int k = r.get<int32_t>();
            std::vector<std::string> names;
            for (int c = 0; c < k; ++c) names.push_back(r.str());
            const int x = r.get<int32_t>(), y = r.get<int32_t>(), w = r.get<int32_t>(), h = r.get<int32_t>();
            std::vector<int64_t> off(static_cast<size_t>(k)), stride(static_cast<size_t>(k));
            for (auto &o : off) o = r.get<int64_t>();
            for (auto &s : stride) s = r.get<int64_t>();
            const size_t floats = (p.size() - r.at) / 4;
            for (int c = 0; c < k; ++c) {
                int idx = -1;
                for (size_t i = 0; i < v.channels.size(); ++i)
                    if (v.channels[i] == names[size_t(c)]) idx = int(i);
                if (idx < 0) throw std::runtime_error("update of an unknown channel " + names[size_t(c)]);
                for (int j = 0; j < h; ++j)
                    for (int i = 0; i < w; ++i) {
                        const size_t e = size_t(off[size_t(c)] + (int64_t(j) * w + i) * stride[size_t(c)]);
                        if (e >= floats || x + i >= v.width || y + j >= v.height) throw std::runtime_error("out of range");
                        float f;
                        std::memcpy(&f, p.data() + r.at + 4 * e, 4);
                        v.planes[size_t(idx)][size_t(y + j) * v.width + x + i] = f;
                    }
            }
        } else {
            throw std::runtime_error("unexpected packet type " + std::to_string(type));
        }
    }
    return v;
}

// Every channel the viewer holds equals the EXR's, bit for bit.
void ExpectViewerEqualsImage(const Viewer &v, const Image &img, size_t channels) {
    ASSERT_EQ(v.width, img.width());
    ASSERT_EQ(v.height, img.height());
    ASSERT_EQ(v.channels.size(), channels);
    for (size_t c = 0; c < v.channels.size(); ++c) {
        const int k = img.channelIndex(v.channels[c]);
        ASSERT_GE(k, 0) << v.channels[c];
        int differ = 0;
        for (int y = 0; y < img.height(); ++y)
            for (int x = 0; x < img.width(); ++x) {
                float a = v.planes[c][size_t(y) * v.width + x], b = img.at(x, y, k);
                differ += std::memcmp(&a, &b, 4) != 0;
            }
        EXPECT_EQ(differ, 0) << "channel " << v.channels[c];
    }
}

}  // namespace

TEST_F(DisplayTest, FinalPixelsEqualTheExr) {
    write("s.pbrt", kScene);
    struct Case {
        std::string args;
        size_t channels;  // in the viewer at the end
    } cases[] = {
        {"--spp 4", 3},
        {"--spp 4 --cropwindow 0.2 0.9 0.1 0.6", 3},
        // With layers, the output's every channel (gbdpt: RGB, primal, dx, dy, separated and the
        // three reconstructions: 8 layers of 3 channels).
        {"--spp 2 --integrator gbdpt --display-layers", 24},
    };
    for (const Case &c : cases) {
        SCOPED_TRACE(c.args);
        Receiver rx;
        rx.start();
        RunResult r = run("s.pbrt --quiet --outfile d.exr --display-server 127.0.0.1:" + std::to_string(rx.port()) +
                          " " + c.args);
        rx.join();
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
        Viewer v;
        ASSERT_NO_THROW(v = Decode(rx.bytes));
        EXPECT_EQ(v.name, "d.exr");
        ExpectViewerEqualsImage(v, ReadImage((dir_ / "d.exr").string()), c.channels);
    }
}

// While it renders (a time budget of 1.2 s), the viewer gets several rounds of
// updates, at most 4 a second: the 2 display tiles of a 70x45 film each round.
TEST_F(DisplayTest, UpdatesWhileRendering) {
    write("s.pbrt", kScene);
    Receiver rx;
    rx.start();
    RunResult r = run("s.pbrt --quiet --outfile d.exr --time 1.2 --display-server 127.0.0.1:" +
                      std::to_string(rx.port()));
    rx.join();
    ASSERT_EQ(r.status, 0) << r.err;
    Viewer v = Decode(rx.bytes);
    const int tiles = 2, rounds = v.packets[6] / tiles;  // the final image is one more round
    EXPECT_GE(rounds, 3) << v.packets[6] << " updates";
    EXPECT_LE(rounds, 1 + int(1.3 * 4) + 1) << v.packets[6] << " updates";
    ExpectViewerEqualsImage(v, ReadImage((dir_ / "d.exr").string()), 3);
}

// Nothing listening: one warning, the render succeeds and writes its image.
TEST_F(DisplayTest, RefusedConnectionWarnsAndRenders) {
    write("s.pbrt", kScene);
    int port;
    {
        Receiver closed;  // a port that was free a moment ago, now closed
        port = closed.port();
    }
    RunResult r = run("s.pbrt --outfile d.exr --spp 2 --quiet --display-server 127.0.0.1:" + std::to_string(port));
    ASSERT_EQ(r.status, 0) << r.err;
    const size_t w = r.err.find("warning: display server 127.0.0.1:" + std::to_string(port) + ": cannot connect");
    EXPECT_NE(w, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("warning", w + 1), std::string::npos) << "one warning only:\n" << r.err;
    EXPECT_EQ(ReadImage((dir_ / "d.exr").string()).width(), 70);
}

// A viewer that accepts and never reads (12 MB of float RGB a round, more
// than the socket buffers hold): the render goes on and ends; the sender
// gives up on it with one warning when a packet is not out within 3 s.
TEST_F(DisplayTest, StalledViewerIsDroppedWithOneWarning) {
    write("e.pbrt", "LookAt 0 0 -3  0 0 0  0 1 0\nCamera \"perspective\"\n"
                    "Film \"image\" \"integer xresolution\" [1024] \"integer yresolution\" [1024]\nWorldBegin\nWorldEnd\n");
    Receiver rx(4096);
    rx.start(false);
    RunResult r = run("e.pbrt --outfile d.exr --spp 1 --quiet --display-server 127.0.0.1:" + std::to_string(rx.port()));
    rx.stop();
    ASSERT_EQ(r.status, 0) << r.err;
    const size_t w = r.err.find("the connection was lost");
    EXPECT_NE(w, std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("warning", w), std::string::npos) << "one warning only:\n" << r.err;
    Image img = ReadImage((dir_ / "d.exr").string());
    const double busy = img.metadata["render_seconds"].number() + img.metadata["scene_load_seconds"].number();
    // Slack 1.5 s: start, the 12 MB EXR, exit (0.2-0.3 s measured without a viewer). A sender
    // that waited 3 s after each send call that made progress took 4.9 s more, one that
    // waited 3 s per call 8 s more.
    EXPECT_LT(r.wall, busy + 3 + 1.5) << "render and load " << busy << " s, the viewer's timeout 3 s";
}

// A bad address is an error before the scene is read (here a broken one).
TEST_F(DisplayTest, BadAddressIsAnErrorBeforeTheScene) {
    write("broken.pbrt", "WorldBegin\nShape \"nonsense\"\n");
    for (const char *a : {"localhost", "localhost:0", "localhost:99999", ":80", "127.0.0.1:http"}) {
        RunResult r = run(std::string("broken.pbrt --quiet --display-server ") + a);
        EXPECT_EQ(r.status, 1) << a;
        EXPECT_NE(r.err.find(std::string("--display-server \"") + a + "\""), std::string::npos) << r.err;
        EXPECT_EQ(r.err.find("nonsense"), std::string::npos) << r.err;
    }
}
