// Live display of a render (gradus --display-server HOST:PORT, as pbrt-v4's
// option of that name): the film is streamed to a viewer speaking tev's TCP
// protocol while it renders. A thread of its own connects, creates the image
// (tev's CreateImage: the film's cropped size, channels R, G, B and optionally
// each written film layer's "name.R", "name.G", "name.B") and, at most 4
// times a second, sends the display tiles that merges changed since
// (UpdateImage, version 3: interleaved channels); the render never waits on
// the viewer. finish() sends the final image (after the integrator's finish,
// e.g. a gradient reconstruction; with layers every channel of the output,
// re-created under the same name, which tev replaces) and waits for it to go
// out, a few seconds at most. A failed connection or a dropped one prints one
// warning; the render goes on.
//
// tev's packets (tev's src/Ipc.cpp): uint32 length of the whole packet
// (these 4 bytes included), a type byte, then the fields: booleans as one
// byte, strings NUL-terminated, int32/int64/float little-endian.
//   CreateImage (4):   grabFocus, name, width, height, nChannels, channel names
//   UpdateImageV3 (6): grabFocus, name, nChannels, channel names, x, y, width,
//                      height, int64 offset and int64 stride per channel, floats
#pragma once
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "image/image.h"
#include "render/film.h"

namespace gradus {

// HOST:PORT (host a name, an IPv4 address or an [IPv6] one; port 1-65535).
struct DisplayAddress {
    std::string host, port;
    std::string str() const;
};
// Parses and resolves the address; throws Error saying what is wrong with it.
DisplayAddress ParseDisplayAddress(const std::string &text);

// The bytes of tev's packets (for the client and the tests' receivers).
namespace tev {
constexpr uint8_t kCreateImage = 4, kUpdateImageV3 = 6;
std::string CreateImagePacket(const std::string &name, int width, int height, const std::vector<std::string> &channels);
// values: width x height pixels, row-major, channels.size() floats each (interleaved).
std::string UpdateImagePacket(const std::string &name, const std::vector<std::string> &channels, int x, int y,
                              int width, int height, const float *values);
}  // namespace tev

class FilmDisplay : public FilmWatcher {
  public:
    // Starts streaming `film` (image `name`); with layers, the film's written
    // layers too. quiet: no progress bar on stderr (its warning need not start a line).
    FilmDisplay(const DisplayAddress &address, Film &film, const std::string &name, bool layers, bool quiet = true);
    ~FilmDisplay() override;  // stops watching and sending (without the final image)
    // Stops watching the film and sends the final image's channels (those of
    // the created image that `final` has; its size is the film's cropped size).
    void finish(const Image &final);
    void merged(const Bounds2i &pixels, bool allPixels) override;

    static constexpr int kTileSize = 64;           // display tiles (pixels per side)
    static constexpr int kUpdateMilliseconds = 250;  // at most 4 updates per second
    static constexpr int kStallMilliseconds = 3000;  // a packet not out by then drops the viewer

  private:
    void run();
    bool connectToViewer();
    bool send(const std::string &packet);
    bool sendTiles(const Image *final);
    void warn(const std::string &what);

    DisplayAddress address_;
    Film &film_;
    std::string name_;
    bool wantLayers_, quiet_;
    std::vector<std::string> channels_;
    std::vector<int> layers_;  // film layers after R, G, B
    Bounds2i bounds_;          // the film's pixel bounds
    int tilesX_ = 0, tilesY_ = 0;
    std::unique_ptr<std::atomic<uint32_t>[]> changed_;  // per display tile: merges since it was sent
    std::vector<uint32_t> sent_;
    std::mutex m_;
    std::condition_variable cv_;
    bool stop_ = false, watching_ = true;
    const Image *final_ = nullptr;
    int fd_ = -1;
    bool warned_ = false;
    std::thread thread_;
};

}  // namespace gradus
