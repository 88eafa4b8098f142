// Matrix bidirectional path tracing (Chaitanya, Belcour, Hachisuka, Premoze,
// Pantaleoni, Nowrouzezahrai 2018; matrix-bdpt.md),
// built on the shared bidirectional core in integrators/common/.
//
// One iteration (Algorithm 1) = one sample per pixel:
//   1. generation: one camera subpath per sampled pixel and as many light
//      subpaths (N = L), stored with the BSDFs of their generation (lobes
//      kept in per-tile arenas for the iteration), and a connection record
//      per eligible light vertex (after stage 2, in column order);
//   2. reordering: for every camera prefix length t and light prefix length
//      s the eligible subpaths (enough vertices, connectible end vertex) are
//      sorted by the Sec. 4.2 metric (a parallel sort with a total order);
//   3. connection: the image is split into tiles of camera subpaths; each
//      camera subpath connects, for every strategy (s >= 2, t >= 2), to m
//      light subpaths chosen by a stratified 2D point set over the reordered
//      matrix M_{s,t} (Sec. 4.3). s = 0 (emitter hits), s = 1 (next-event
//      estimation with a fresh light sample, as in pbrt-v3) and t = 1 (light
//      tracing) use the diagonal (Sec. 5.1, Fig. 5): plain BDPT. With
//      nexteventmatrix, s = 1 has its matrices M_{1,t} too (the paper leaves
//      only s = 0 and t = 1 on the diagonal): the columns are the light
//      subpaths' emitter vertices (connection_record.h ConnectLightOrigin). A row's
//      connections are chosen first, the first few of their records
//      prefetched (a random place in the image-wide store) while the diagonal
//      strategies run, the others a few connections ahead. A matrix connection reads the light
//      endpoint's compact record (common/connection_record.h: vertex,
//      Lambertian parameters, the light side of the MIS sum; two cache
//      lines) and the row's camera-side MIS sums, so it walks neither
//      subpath; other materials and medium vertices fall back to the
//      store's vertex and BSDF for f and the pdfs only.
// matrixsampler "pixel" replaces the row order by the pixel sampler: a row's
// participation and column coordinates are dimensions of the pixel's own
// sample (fixed dimensions, so over the iterations a pixel's connections are
// stratified along the sorted light subpaths), the camera subpath is
// generated tile by tile in stage 3 and never stored, and next-event samples
// come from the sampler as in bdpt.
// Random numbers are addressed by (pixel, iteration) and the seed; the
// result does not depend on the thread count.
// Participating media: the stored subpaths hold medium vertices (common/bidir.h),
// connections carry transmittance (a per-row RNG); the reordering treats a
// medium vertex as any connectible end vertex.
//
// Parameters (bidirectional family, integrators/common/bidir_family.h):
//   integer maxdepth 5              maximum path depth (edges - 1)
//   string lightsamplestrategy "power"  uniform | power | spatial (= power)
//   string misheuristic "balance"   balance (pbrt-v3) | power (exponent 2)
//   bool visualizestrategies false  layers "mbdpt_s<S>_t<T>" (t >= 1): unweighted contribution of each strategy
//   bool visualizeweights false     the same layers, MIS-weighted
//   integer rrdepth 3               Russian roulette on subpaths after this many bounces (-1: off)
//   integer pixelbounds []          accepted (use --cropwindow instead)
// mbdpt's own:
//   string reorder "distance"       distance (Sec. 4.2) | morton (end vertex) | none
//   integer connections 1           m: light subpaths per camera subpath and strategy
//   string matrixrows "matched"     matched: a camera subpath takes part in M_{s,t} with probability
//                                   L_s / L (same expected connections as BDPT) | all: always
//   bool combinatorial false        connect every camera subpath to all columns (Eq. 6; quadratic cost)
//   string matrixsampler "lattice"  lattice (rank-1 lattice, 2D low discrepancy) | lhs | random | diagonal |
//                                   pixel (per-pixel sampler dimensions; no stored camera subpaths)
//   bool nexteventmatrix false      next-event estimation (s = 1) through the matrix: camera vertices connect
//                                   to the emitter vertices of other pixels' light subpaths (infinite and
//                                   distant lights stay on the diagonal)
//   string configuration "default"  default | paper: the paper's configuration (Sec. 5: every eye subpath in
//                                   every matrix, no Russian roulette, next-event estimation through the
//                                   matrix) = matrixrows "all", rrdepth -1, nexteventmatrix true (giving
//                                   any of the three beside it is an error)
//   string visualizematrix ""       "s,t": image of the matrix M_{s,t} of the first iteration (Fig. 4)
//   integer matrixresolution 256    its maximum width/height (rows and columns subsampled evenly)
//   string matrixfile ""            where to write it (default: <film name>_matrix_s<S>_t<T>.exr);
//                                   main RGB = reordered matrix, layer "unordered" = random order
#pragma once
#include <atomic>
#include <cstdlib>
#include <string>
#include <vector>

#include "image/image.h"
#include "integrators/common/bidir_family.h"
#include "integrators/common/connection_record.h"
#include "integrators/common/subpath_store.h"
#include "render/integrator.h"
#include "integrators/mbdpt/matrix.h"

namespace gradus {

// Every table field is set by the parameter table (mbdpt.cpp; defaults there).
struct MBDPTSettings : BidirSettings {
    mbdpt::Reorder reorder;
    mbdpt::MatrixSampling sampling;
    int connections;
    bool combinatorial;
    bool allRows;
    bool nextEventMatrix;       // s = 1 through the matrix
    std::string configuration;  // default | paper
    std::string visualizeMatrix;
    int visS = -1, visT = -1;  // visualised matrix (from visualizematrix)
    int matrixResolution;
    std::string matrixFile;
};

class MBDPTIntegrator : public Integrator, public BidirFamily {
  public:
    explicit MBDPTIntegrator(const EntityDesc &desc);
    std::string name() const override { return "mbdpt"; }
    bool rendersMedia() const override { return true; }  // medium vertices of the shared core
    void preprocess(const Scene &scene, Film &film) override;
    int samplesPerPass(const RenderOptions &) const override { return 1; }  // one iteration = 1 spp
    void runPass(PassContext &ctx) override;
    void endPass(PassContext &ctx) override;
    std::string statistics() const override;

    const MBDPTSettings &settings() const { return set_; }
    static std::string LayerName(int s, int t) { return StrategyLayerName("mbdpt", s, t); }
    // Matrix visualisation of the first iteration (empty unless visualizematrix is set).
    const Image &matrixImage() const { return matrixImage_; }
    // Bytes of stored subpaths and reordering tables per sampled pixel (last iteration).
    double bytesPerPixel() const { return bytesPerPixel_; }

  private:
    void buildRecords(PassContext &ctx);
    void reorder(PassContext &ctx);
    void connect(PassContext &ctx);
    struct TileConnector;  // stage 3 for one tile's camera subpaths (connect())
    void visualizeMatrix(PassContext &ctx);

    MBDPTSettings set_;
    FileLoc loc_;

    // Per-iteration data (reused across iterations).
    ImageSubpaths paths_;                      // one camera and one light subpath per sampled pixel
    bool pathsReady_ = false;
    std::vector<std::vector<uint32_t>> rows_;  // [t]: eligible camera subpaths in reordered order
    std::vector<std::vector<int32_t>> rank_;   // [t][p]: rank of camera subpath p in rows_[t], or -1
    std::vector<std::vector<uint32_t>> cols_;  // [s]: eligible light subpaths in reordered order
                                               // ([1]: emitter vertices, IsMatrixLightOrigin)
    int maxColumnS_ = 0;                       // largest s with a column (0: none)
    bool farLights_ = false;                   // infinite or distant lights (diagonal s = 1 with nexteventmatrix)
    // Records of the columns' light endpoints (buildRecords), matrix after
    // matrix: cols_[s][k]'s at colStart_[s] + k; colPos_: per light vertex its k (or UINT32_MAX).
    class RecordBuffer {
      public:
        RecordBuffer() = default;
        RecordBuffer(const RecordBuffer &) = delete;
        RecordBuffer &operator=(const RecordBuffer &) = delete;
        ~RecordBuffer() { std::free(data_); }
        void reserve(size_t n);  // uninitialised (records are trivially copyable)
        LightRecord *data() const { return data_; }
        size_t capacity() const { return cap_; }

      private:
        LightRecord *data_ = nullptr;
        size_t cap_ = 0;
    };
    RecordBuffer colRecords_;
    std::vector<size_t> colStart_;
    std::vector<uint32_t> colPos_;
    const LightRecord *columns(int s) const { return colRecords_.data() + colStart_[size_t(s)]; }
    // reorder()'s sort keys and scratch, one pair per sort
    std::vector<std::pair<std::vector<std::pair<uint64_t, uint32_t>>, std::vector<std::pair<uint64_t, uint32_t>>>>
        sortBufs_;
    std::vector<double> lightDist_, camDist_;  // per stored vertex: d(y) of the prefix ending there (Sec. 4.2)

    Image matrixImage_;
    double bytesPerPixel_ = 0;
    int iterations_ = 0;
    double secGen_ = 0, secSort_ = 0, secConnect_ = 0;
    std::atomic<uint64_t> nConnect_{0}, nShadow_{0}, nCamVerts_{0}, nLightVerts_{0}, nOrigin_{0};
};

}  // namespace gradus
