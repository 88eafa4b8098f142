// Image-wide subpath generation and storage for pass-based bidirectional
// integrators (M-BDPT today; VCM's light pass and MLT's bootstrap next).
//
// One pass generates one camera and one light subpath per sampled pixel with
// the pixel sampler positioned on (pixel, PassContext::firstSample()), so a
// pass draws the same random numbers as sample `firstSample` of a
// pixel-sample integrator. Subpaths are numbered tile by tile
// (PassContext::tiles()) and stored compactly: vertices only (PathVertex holds
// what RebuildBSDF needs), concatenated in tile order so the store does not
// depend on the thread count.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "integrators/common/bidir.h"
#include "render/render_loop.h"

namespace gradus {

// Subpaths of one pass, indexed in generation order.
struct SubpathStore {
    std::vector<PathVertex> v;
    std::vector<BSDF> b;               // per vertex, when kept (ImageSubpaths::generate keep*BSDFs)
    std::vector<uint8_t> connectible;  // per vertex: a connection may end here (surface, non-specular)
    std::vector<uint32_t> offset;      // subpath i: v[offset[i], offset[i+1])
    int count(size_t i) const { return int(offset[i + 1] - offset[i]); }
    const PathVertex *path(size_t i) const { return v.data() + offset[i]; }
    const BSDF *bsdfs(size_t i) const { return b.empty() ? nullptr : b.data() + offset[i]; }
    bool eligible(size_t i, int len) const { return count(i) >= len && connectible[offset[i] + len - 1]; }
    size_t bytes() const {
        return v.capacity() * sizeof(PathVertex) + b.capacity() * sizeof(BSDF) + connectible.capacity() +
               offset.capacity() * sizeof(uint32_t);
    }
};

class ImageSubpaths {
  public:
    // Numbers the subpaths over the tiles (call once, after the film is known).
    void init(const TileGrid &tiles);
    // Generates the pass's subpaths (camera subpaths up to maxDepth + 2
    // vertices, light subpaths up to maxDepth + 1). withCamera = false: light
    // subpaths only (the camera store stays empty, pFilm and camWeight are not
    // set). lightDimension >= 0: the light subpath draws from that sampler
    // dimension of the pixel sample on (else it follows the camera subpath's).
    // keepLightBSDFs: the light vertices' BSDFs from generation are kept in
    // light.b (their lobes in per-tile arenas that live until the next call),
    // so no connection rebuilds them; keepCameraBSDFs: the same for the
    // camera vertices (camera.b).
    void generate(PassContext &ctx, const BidirContext &bidir, int maxDepth, bool withCamera = true,
                  int lightDimension = -1, bool keepLightBSDFs = false, bool keepCameraBSDFs = false);

    size_t size() const { return tileStart_.empty() ? 0 : tileStart_.back(); }
    uint32_t tileBegin(int tile) const { return tileStart_[tile]; }
    uint32_t tileEnd(int tile) const { return tileStart_[tile + 1]; }
    size_t bytes() const;

    SubpathStore camera, light;
    std::vector<Point2> pFilm;     // per camera subpath: film position
    std::vector<float> camWeight;  // per camera subpath: camera ray weight (0: no subpath)

  private:
    struct TileOut {
        std::vector<BSDF> lb, cb;
        std::vector<PathVertex> cv, lv;
        std::vector<uint8_t> cc, lc;
        std::vector<uint32_t> nc, nl;
        void clear() {
            lb.clear(), cb.clear(), cv.clear(), lv.clear(), cc.clear(), lc.clear(), nc.clear(), nl.clear();
        }
    };
    TileGrid tiles_;
    std::vector<TileOut> tileOut_;  // generate()'s per-tile output
    std::vector<std::unique_ptr<Arena>> tileArenas_;     // kept light BSDFs' lobes, one arena per tile
    std::vector<std::unique_ptr<Arena>> camTileArenas_;  // kept camera BSDFs' lobes
    std::vector<uint32_t> tileStart_;  // first subpath of each tile
};

}  // namespace gradus
