#include "integrators/common/subpath_store.h"

#include <algorithm>

#include "scene/scene.h"

namespace gradus {

namespace {
constexpr uint64_t kLightMediaTag = 0x7375627061746831ULL;  // light subpaths' media RNG
}  // namespace

void ImageSubpaths::init(const TileGrid &tiles) {
    tiles_ = tiles;
    tileStart_.assign(1, 0);
    for (int t = 0; t < tiles.count(); ++t) tileStart_.push_back(tileStart_.back() + uint32_t(tiles.tile(t).area()));
}

size_t ImageSubpaths::bytes() const {
    return camera.bytes() + light.bytes() + pFilm.capacity() * sizeof(Point2) + camWeight.capacity() * sizeof(float);
}

void ImageSubpaths::generate(PassContext &ctx, const BidirContext &bidir, int maxDepth, bool withCamera,
                             int lightDimension, bool keepLightBSDFs, bool keepCameraBSDFs) {
    const Scene &scene = ctx.scene();
    const int ntiles = tiles_.count();
    const size_t N = size();
    const int maxCam = maxDepth + 2, maxLight = maxDepth + 1;
    const int sampleIndex = ctx.firstSample();
    auto makeArenas = [&](bool keep, std::vector<std::unique_ptr<Arena>> &arenas) {
        if (!keep || arenas.size() == size_t(ntiles)) return;
        arenas.clear();
        for (int t = 0; t < ntiles; ++t) arenas.push_back(std::make_unique<Arena>());
    };
    keepCameraBSDFs = keepCameraBSDFs && withCamera;
    makeArenas(keepLightBSDFs, tileArenas_);
    makeArenas(keepCameraBSDFs, camTileArenas_);
    // Per-tile output, kept across passes (its capacity: no page faults per pass).
    std::vector<TileOut> &out = tileOut_;
    out.resize(size_t(ntiles));
    for (TileOut &o : out) o.clear();
    pFilm.resize(withCamera ? N : 0);
    camWeight.resize(withCamera ? N : 0);
    ctx.parallelFor(ntiles, 1, [&](int64_t begin, int64_t end, Worker &wk) {
        std::vector<PathVertex> camV(maxCam), lightV(maxLight);
        std::vector<BSDF> camB(maxCam), lightB(maxLight);
        for (int64_t ti = begin; ti < end; ++ti) {
            TileOut &o = out[ti];
            const Bounds2i tb = tiles_.tile(int(ti));
            Arena *lightArena = keepLightBSDFs ? tileArenas_[ti].get() : &wk.arena;
            if (keepLightBSDFs) lightArena->reset();
            Arena *camArena = keepCameraBSDFs ? camTileArenas_[ti].get() : &wk.arena;
            if (keepCameraBSDFs) camArena->reset();
            uint32_t p = tileStart_[ti];
            for (int y = tb.pMin.y; y < tb.pMax.y; ++y)
                for (int x = tb.pMin.x; x < tb.pMax.x; ++x, ++p) {
                    Sampler &smp = *wk.sampler;
                    smp.startPixelSample({x, y}, sampleIndex);
                    // camB and lightB are not reset: the walks assign the BSDF of every vertex they
                    // create and only those are read (maxdepth + 2 BSDFs per subpath otherwise).
                    int nC = 0, nL = 0;
                    // Media: the camera subpath's distances from the camera sample's RNG, the
                    // light subpath's from one keyed by (seed, pixel, sample).
                    RNG camRng, lightRng;
                    const bool media = scene.features.media;
                    if (media)
                        lightRng = RNG(Hash(smp.seed() ^ kLightMediaTag, uint64_t(x) << 32 | uint32_t(y),
                                            uint64_t(sampleIndex)));
                    if (withCamera) {
                        CameraSample cs;
                        Point2 u = smp.get2D();
                        cs.pFilm = Point2(x + u.x, y + u.y);
                        cs.pLens = smp.get2D();
                        Ray ray;
                        Float w = scene.camera->generateRay(cs, &ray);
                        if (w > 0)
                            nC = GenerateCameraSubpath(bidir, ray, smp, *camArena, maxCam, camV.data(), camB.data(),
                                                       media ? &(camRng = CameraSampleMediaRNG(smp, cs)) : nullptr);
                        pFilm[p] = cs.pFilm;
                        camWeight[p] = float(w);
                    }
                    if (lightDimension >= 0) smp.startPixelSample({x, y}, sampleIndex, lightDimension);
                    if (!scene.lights.empty())
                        nL = GenerateLightSubpath(bidir, smp, *lightArena, maxLight, lightV.data(), lightB.data(),
                                                  media ? &lightRng : nullptr);
                    for (int i = 0; i < nC; ++i) {
                        if (keepCameraBSDFs) o.cb.push_back(camB[i]);
                        o.cv.push_back(camV[i]);
                        o.cc.push_back(camV[i].scatters() && IsConnectible(camV[i], &camB[i]));
                    }
                    for (int i = 0; i < nL; ++i) {
                        if (keepLightBSDFs) o.lb.push_back(lightB[i]);
                        o.lv.push_back(lightV[i]);
                        o.lc.push_back(lightV[i].scatters() && IsConnectible(lightV[i], &lightB[i]));
                    }
                    o.nc.push_back(uint32_t(nC));
                    o.nl.push_back(uint32_t(nL));
                    wk.arena.reset();
                }
        }
    });
    // Deterministic concatenation in tile order.
    auto concat = [&](SubpathStore &store, bool cam) {
        std::vector<size_t> vstart(ntiles + 1, 0);
        for (int ti = 0; ti < ntiles; ++ti) vstart[ti + 1] = vstart[ti] + (cam ? out[ti].cv.size() : out[ti].lv.size());
        store.v.resize(vstart[ntiles]);
        store.b.resize((cam ? keepCameraBSDFs : keepLightBSDFs) ? vstart[ntiles] : 0);
        store.connectible.resize(vstart[ntiles]);
        store.offset.resize(N + 1);
        store.offset[N] = uint32_t(vstart[ntiles]);
        ctx.parallelFor(ntiles, 1, [&](int64_t begin, int64_t end, Worker &) {
            for (int64_t ti = begin; ti < end; ++ti) {
                const TileOut &o = out[ti];
                const auto &vs = cam ? o.cv : o.lv;
                const auto &cs = cam ? o.cc : o.lc;
                const auto &ns = cam ? o.nc : o.nl;
                std::copy(vs.begin(), vs.end(), store.v.begin() + vstart[ti]);
                const auto &bs = cam ? o.cb : o.lb;
                if (!store.b.empty()) std::copy(bs.begin(), bs.end(), store.b.begin() + vstart[ti]);
                std::copy(cs.begin(), cs.end(), store.connectible.begin() + vstart[ti]);
                uint32_t off = uint32_t(vstart[ti]);
                for (size_t j = 0; j < ns.size(); ++j) {
                    store.offset[tileStart_[ti] + j] = off;
                    off += ns[j];
                }
            }
        });
    };
    concat(camera, true);
    concat(light, false);
}

}  // namespace gradus
