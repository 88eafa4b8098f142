// M-BDPT estimator (notation of bidir.h: strategy (s, t) uses s light and t
// camera vertices; C_{s,t}(y, z) = w_{s,t}(x) f(x) / p(x) is BDPT's MIS-weighted
// contribution of the path x formed by camera subpath y and light subpath z,
// Eq. 3, i.e. the matrix entry M_{s,t}^{p,q} of Eq. 5).
//
// Per iteration: N camera subpaths y^p (one per pixel) and L = N light
// subpaths z^q, all independent, with BDPT's subpath densities p(y), p(z);
// the path density p(x) = p(y) p(z) is the same as in BDPT, so Eq. 3's MIS
// weights apply unchanged. Q_s = columns whose light subpath has >= s vertices
// and a connectible vertex s-1 (|Q_s| = L_s); every other column has
// M^{p,q} = 0 and is dropped. For s >= 2, t >= 2 and row p (Eq. 4 with the
// pairs S chosen as in Sec. 4.3):
//   I_p^{s,t} = B_p / rho * L_s / (L m) * sum_{c<m} M^{p, q_c},  q_c = pi_s[floor(L_s eps_c)],
// pi_s the reordered columns (Sec. 4.2), eps_c the column coordinate of the
// c-th 2D point of row p (matrix.h), and B_p in {0, 1} whether row p takes part
// in this matrix, Pr(B_p = 1) = rho (rho = L_s / L, "matrixrows" "matched": the
// expected number of connections per strategy equals BDPT's; rho = 1 for "all").
// B_p and the eps_c are uniform-marginal whatever the ordering (each eps_c, or
// for LHS their mixture over c), so (1/m) sum_c Pr(q_c = q) = 1 / L_s for each
// q in Q_s, independently of B_p, and
//   E[I_p^{s,t} | subpaths] = 1/L sum_{q in Q_s} M^{p,q}     (Eq. 6, row p),
// whose expectation over the light subpaths is E_z[C_{s,t}(y^p, z)], the
// expectation of BDPT's diagonal estimator (Eq. 7). `combinatorial` evaluates
// Eq. 6 exactly; the `diagonal` sampler uses q = p with weight 1 (Eq. 7).
// s = 0, s = 1 and t = 1 always use the diagonal (Sec. 5.1).
#include "integrators/mbdpt/mbdpt.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <new>

#include <sys/mman.h>
#include <sstream>

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"
#include "render/parallel.h"

namespace gradus {

using namespace mbdpt;

std::unique_ptr<Integrator> CreateMBDPTIntegrator(const EntityDesc &d) { return std::make_unique<MBDPTIntegrator>(d); }

namespace {

constexpr uint64_t kConnectTag = 0x6d62647074000001ULL;
constexpr uint64_t kMediaTag = 0x6d62647074000002ULL;  // transmittance of the connections
constexpr uint64_t kMatrixTag = 0x6d62647074000002ULL;
constexpr uint64_t kRowTag = 0x6d62647074000003ULL;
// Sampler dimensions of "matrixsampler" "pixel" (per pixel sample; camera
// subpath from 0 as in bdpt): the diagonal strategies' next-event and lens
// samples from kConnectDim, the light subpath from kLightDim, the row participation number at kMatrixDim and strategy (s, t)'s
// column coordinates from kMatrixDim + 1 + (s (maxdepth + 1) + t) m, the same
// dimensions in every iteration so that each is stratified over a pixel's
// iterations.
constexpr int kConnectDim = 1 << 15;
constexpr int kLightDim = 1 << 16;
constexpr int kMatrixDim = 1 << 17;

// Light subpath i has a column in M_{1,t}: an emitter vertex ConnectLightOrigin takes.
bool HasMatrixOrigin(const SubpathStore &light, size_t i) {
    return light.count(i) >= 1 && IsMatrixLightOrigin(*light.path(i));
}

double Seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

ParamTable<MBDPTSettings> Table() {
    using S = MBDPTSettings;
    ParamTable<S> t("mbdpt");
    t.append(BidirParams());  // rrdepth 3
    t.enumeration<Reorder>("reorder", &S::reorder, "distance",
                           {{"distance", Reorder::Distance}, {"morton", Reorder::Morton}, {"none", Reorder::None}},
                           "order of the matrix rows and columns: Sec. 4.2 distance, Morton code of the end "
                           "vertex, none");
    t.integer("connections", &S::connections, 1, "m: light subpaths per camera subpath and strategy",
              Range{1, 1024});
    t.enumeration<bool>("matrixrows", &S::allRows, "matched", {{"matched", false}, {"all", true}},
                        "matched: a camera subpath takes part in M_{s,t} with probability L_s / L | all: always");
    t.boolean("combinatorial", &S::combinatorial, false,
              "connect every camera subpath to all columns (Eq. 6; quadratic cost)");
    t.enumeration<MatrixSampling>("matrixsampler", &S::sampling, "lattice",
                                  {{"lattice", MatrixSampling::Lattice},
                                   {"lhs", MatrixSampling::LHS},
                                   {"random", MatrixSampling::Random},
                                   {"diagonal", MatrixSampling::Diagonal},
                                   {"pixel", MatrixSampling::Pixel}},
                                  "columns of a row: rank-1 lattice (2D low discrepancy), Latin hypercube, "
                                  "random, q = p, or pixel (the pixel sample's own dimensions: stratified "
                                  "over the iterations; camera subpaths generated tile by tile, not stored)");
    t.boolean("nexteventmatrix", &S::nextEventMatrix, false,
              "next-event estimation (s = 1) through the matrix: emitter vertices of other pixels' light subpaths");
    t.enumeration("configuration", &S::configuration, "default", {"default", "paper"},
                  "paper: every eye subpath in every matrix, no Russian roulette, next-event estimation through "
                  "the matrix (= matrixrows \"all\", rrdepth -1, nexteventmatrix true)")
        .thenWithParams([](S &s, const ParamSet &ps, const FileLoc &loc) {
            if (s.configuration != "paper") return;
            for (const char *n : {"rrdepth", "matrixrows", "nexteventmatrix"})
                if (ps.has(n))
                    throw Error(ps.locOf(n, loc), std::string("mbdpt: \"configuration\" \"paper\" sets \"") + n +
                                                      "\"; give one or the other");
            s.allRows = true;
            s.rrDepth = -1;
            s.nextEventMatrix = true;
        });
    t.string("visualizematrix", &S::visualizeMatrix, "",
             "\"s,t\": image of the matrix M_{s,t} of the first iteration (Fig. 4)")
        .then([](S &s, const FileLoc &loc) {
            if (s.visualizeMatrix.empty()) return;
            char extra;
            if (std::sscanf(s.visualizeMatrix.c_str(), "%d , %d %c", &s.visS, &s.visT, &extra) != 2 ||
                s.visS < 2 || s.visT < 2 || s.visS + s.visT - 2 > s.maxDepth)
                throw Error(loc, "\"visualizematrix\" must be \"s,t\" with s >= 2, t >= 2 and s + t - 2 <= maxdepth");
        });
    t.integer("matrixresolution", &S::matrixResolution, 256,
              "maximum width/height of the matrix image (rows and columns subsampled evenly)", AtLeast(1));
    t.string("matrixfile", &S::matrixFile, "",
             "where to write it (\"\": <film name>_matrix_s<S>_t<T>.exr); layer \"unordered\" = random order");
    return t;
}

}  // namespace

std::vector<ParamInfo> MBDPTParameters() { return Table().describe(); }

MBDPTIntegrator::MBDPTIntegrator(const EntityDesc &desc)
    : BidirFamily("mbdpt", 1), set_(Table().parse(desc)), loc_(desc.loc) {
    if (set_.visS >= 0 && set_.sampling == MatrixSampling::Pixel)
        throw Error(desc.loc, "mbdpt: \"visualizematrix\" needs the stored, reordered camera subpaths of a "
                              "row-ordered \"matrixsampler\" (lattice, lhs, random or diagonal), not \"pixel\"");
}

void MBDPTIntegrator::preprocess(const Scene &scene, Film &film) {
    // One light subpath per sampled pixel: light tracing estimates the full image.
    preprocessBidir(scene, film, set_, loc_);
    farLights_ = false;
    for (const auto &l : scene.lights) farLights_ |= (l->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION)) != 0;
    if (set_.visS >= 0 && set_.matrixFile.empty()) {
        std::string f = film.filename();
        size_t dot = f.find_last_of('.'), slash = f.find_last_of('/');
        if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) f = f.substr(0, dot);
        set_.matrixFile = f + "_matrix_s" + std::to_string(set_.visS) + "_t" + std::to_string(set_.visT) + ".exr";
    }
}

void MBDPTIntegrator::RecordBuffer::reserve(size_t n) {
    if (n <= cap_) return;
    std::free(data_);
    // 2 MB aligned, huge pages asked for before the first touch: a connection
    // reads a random record of tens of MB, and with 4 KB pages each read was a
    // TLB miss (perf: the prefetches stalled on the page walks).
    constexpr size_t kHuge = size_t(2) << 20;
    const size_t bytes = (std::max<size_t>(n, 1) * sizeof(LightRecord) + kHuge - 1) / kHuge * kHuge;
    data_ = static_cast<LightRecord *>(std::aligned_alloc(kHuge, bytes));
    if (!data_) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
    madvise(data_, bytes, MADV_HUGEPAGE);  // a hint: without transparent huge pages, 4 KB pages
#endif
    cap_ = bytes / sizeof(LightRecord);
}

// Connection records of the matrix columns (common/connection_record.h), in
// column order: record k of strategy s is the endpoint of cols_[s][k].
void MBDPTIntegrator::buildRecords(PassContext &ctx) {
    const SubpathStore &light = paths_.light;
    const int maxLen = set_.maxDepth;
    colStart_.assign(size_t(maxLen) + 2, 0);
    for (int s = 2; s <= maxLen; ++s) colStart_[size_t(s) + 1] = colStart_[size_t(s)] + cols_[size_t(s)].size();
    for (int s = maxLen + 1; s < int(colStart_.size()); ++s) colStart_[size_t(s)] = colStart_[size_t(maxLen) + 1];
    colRecords_.reserve(colStart_.back());
    // Each eligible light vertex's place among its matrix's columns.
    colPos_.assign(light.v.size(), UINT32_MAX);
    for (int s = 2; s <= maxLen; ++s) {
        const std::vector<uint32_t> &cols = cols_[size_t(s)];
        for (size_t k = 0; k < cols.size(); ++k) colPos_[light.offset[cols[k]] + uint32_t(s - 1)] = uint32_t(k);
    }
    const int maxLight = maxLen + 1;
    ctx.parallelFor(int64_t(paths_.size()), 256, [&](int64_t i0, int64_t i1, Worker &) {
        std::vector<LightRecord> recs(static_cast<size_t>(maxLight), LightRecord());
        for (int64_t i = i0; i < i1; ++i) {
            const uint32_t o = light.offset[size_t(i)];
            const int n = light.count(size_t(i));
            BuildLightRecords(ctx_, SubpathView{light.path(size_t(i)), light.bsdfs(size_t(i)), n}, o, recs.data());
            for (int k = 1; k < n && k < maxLen; ++k)
                if (colPos_[o + uint32_t(k)] != UINT32_MAX)
                    new (colRecords_.data() + colStart_[size_t(k) + 1] + colPos_[o + uint32_t(k)])
                        LightRecord(recs[size_t(k)]);
        }
    });
}

// ---------------------------------------------------------------- stage 2: reordering
void MBDPTIntegrator::reorder(PassContext &ctx) {
    const size_t N = paths_.size();
    // Matrix strategies have s >= 2, t >= 2 and s + t - 2 <= maxDepth.
    const int maxLen = set_.maxDepth;
    // Rows: camera prefix lengths t <= maxDepth (+ 1 for s = 1 with nexteventmatrix).
    const int maxRow = maxLen + (set_.nextEventMatrix ? 1 : 0);
    rows_.resize(maxLen + 2);
    rank_.resize(maxLen + 2);
    cols_.resize(maxLen + 1);
    const Bounds3 &b = ctx.scene().bounds;
    // Sec. 4.2's d(y) of every prefix: running sums along each subpath, in
    // DistanceMetric's order (the same doubles), so a key costs one load.
    auto prefixDistances = [&](const SubpathStore &store, std::vector<double> &cum) {
        cum.resize(store.v.size());
        if (set_.reorder != Reorder::Distance) return;
        ctx.parallelFor(int64_t(N), 1024, [&](int64_t i0, int64_t i1, Worker &) {
            for (int64_t i = i0; i < i1; ++i) {
                const PathVertex *v = store.path(size_t(i));
                double *c = cum.data() + store.offset[size_t(i)];
                double d = 0;
                for (int k = 0; k < store.count(size_t(i)); ++k) {
                    if (k > 0) d += DistanceSquared(v[k - 1].p, v[k].p);
                    c[k] = d;
                }
            }
        });
    };
    // The eligible subpaths of every length in index order (one pass over the vertices).
    auto eligible = [&](const SubpathStore &store, std::vector<std::vector<uint32_t>> &lists, int maxL) {
        for (auto &l : lists) l.clear();
        for (size_t i = 0; i < N; ++i) {
            const int n = std::min(store.count(i), maxL);
            const uint8_t *c = store.connectible.data() + store.offset[i];
            for (int len = 2; len <= n; ++len)
                if (c[len - 1]) lists[size_t(len)].push_back(uint32_t(i));
        }
    };
    const bool rows = set_.sampling != MatrixSampling::Pixel;  // pixel: no stored camera subpaths
    prefixDistances(paths_.light, lightDist_);
    eligible(paths_.light, cols_, maxLen);
    if (set_.nextEventMatrix)  // M_{1,t}'s columns: the emitter vertices (ConnectLightOrigin)
        for (size_t i = 0; i < N; ++i)
            if (HasMatrixOrigin(paths_.light, i)) cols_[1].push_back(uint32_t(i));
    if (rows) {
        prefixDistances(paths_.camera, camDist_);
        eligible(paths_.camera, rows_, maxRow);
    }
    // One sort per matrix side and length, the sorts in parallel; ties broken
    // by index (the lists are in index order, the sort is stable): a total
    // order, so the result is thread-count independent.
    struct SortJob {
        const SubpathStore *store;
        const std::vector<double> *cum;
        int len;
        std::vector<uint32_t> *sorted;
    };
    std::vector<SortJob> jobs;
    for (int len = 1; len <= maxRow && set_.reorder != Reorder::None; ++len) {
        // (s = 1: d(y) = 0 for every emitter vertex, the distance order is the index order)
        const bool sortCols = len <= maxLen && (len >= 2 || set_.reorder == Reorder::Morton);
        if (sortCols && cols_[len].size() >= 2) jobs.push_back({&paths_.light, &lightDist_, len, &cols_[len]});
        if (rows && len >= 2 && rows_[len].size() >= 2) jobs.push_back({&paths_.camera, &camDist_, len, &rows_[len]});
    }
    if (sortBufs_.size() < jobs.size()) sortBufs_.resize(jobs.size());  // kept: no page faults per pass
    ctx.parallelFor(int64_t(jobs.size()), 1, [&](int64_t j0, int64_t j1, Worker &) {
        for (int64_t j = j0; j < j1; ++j) {
            const SortJob &job = jobs[size_t(j)];
            const SubpathStore &store = *job.store;
            std::vector<uint32_t> &sorted = *job.sorted;
            auto &keys = sortBufs_[size_t(j)].first;
            keys.resize(sorted.size());
            for (size_t k = 0; k < sorted.size(); ++k) {
                const size_t at = store.offset[sorted[k]] + size_t(job.len - 1);
                const uint64_t key = set_.reorder == Reorder::Distance ? DistanceKey((*job.cum)[at])
                                                                       : MortonKey(store.v[at].p, b);
                keys[k] = {key, sorted[k]};
            }
            RadixSortKeys(keys, sortBufs_[size_t(j)].second);
            for (size_t k = 0; k < keys.size(); ++k) sorted[k] = keys[k].second;
        }
    });
    maxColumnS_ = 0;
    for (int len = 1; len <= maxRow; ++len) {
        if (len <= maxLen && !cols_[len].empty()) maxColumnS_ = std::max(maxColumnS_, len);
        if (!rows || len < 2) continue;
        if (rows_[len].empty()) {  // no eligible camera subpath this long: rows skip it
            rank_[len].clear();
            continue;
        }
        rank_[len].assign(N, -1);
        const auto &r = rows_[len];
        for (size_t k = 0; k < r.size(); ++k) rank_[len][r[k]] = int32_t(k);
    }
}

// ---------------------------------------------------------------- stage 3: connection
namespace {
// What every tile of one connection pass shares.
struct ConnectPass {
    const Scene &scene;
    int iteration;
    uint64_t seed;
    size_t N;
    int maxDepth, m, maxCam, maxLight;
    bool pixelMode, diagonal;
    bool nextEventMatrix, diagonalNextEvent;  // M_{1,t}; s = 1 on the diagonal (all lights, or the far ones)
    // Column samplers of the matrices of this iteration (row-ordered modes),
    // indexed s * (maxDepth + 2) + t.
    std::vector<ColumnSampler> samplers;
};
}  // namespace

// Stage 3 for the camera subpaths (rows) of one tile: per row, the camera
// subpath, the choice of its matrix connections (prefetched), the diagonal
// strategies, then the matrix connections.
struct MBDPTIntegrator::TileConnector {
    // A chosen matrix connection: light subpath q for strategy (s, t).
    struct Pending {
        int s, t;
        const LightRecord *rec;    // s >= 2: the light endpoint q_{s-1}
        const PathVertex *origin;  // s = 1: the emitter vertex q_0 (in the store)
        Float scale;
        const void *address() const { return rec ? static_cast<const void *>(rec) : origin; }
    };
    // Row p's camera subpath: its film sample, vertices and BSDFs.
    struct CameraRow {
        Point2i pixel;
        Point2 pFilm;
        Float w;
        int nC;
        const PathVertex *cv;
        const BSDF *cb;
    };
    // One row's connections in progress.
    struct Row {
        uint32_t p;
        CameraRow c;
        SampleRecorder rec;
        RNG rng, mediaRng;
        SubpathView camView, ownLight;
        Spectrum L = Spectrum(0);
    };

    TileConnector(const MBDPTIntegrator &in, const ConnectPass &pass, int ti, const Bounds2i &tb, FilmTile &tile,
                  Worker &wk)
        : in(in), pass(pass), cam(in.paths_.camera), light(in.paths_.light), ti(ti), tb(tb), tile(tile), wk(wk),
          camB(pass.maxCam), lightB(pass.maxLight), colB(pass.maxLight), camV(pass.pixelMode ? pass.maxCam : 0),
          smp(*wk.sampler), tileW(tb.pMax.x - tb.pMin.x) {}

    void connectRow(uint32_t p) {
        const CameraRow c = pass.pixelMode ? generateCameraRow(p) : storedCameraRow(p);
        const uint64_t pix = uint64_t(c.pixel.x) << 32 | uint32_t(c.pixel.y);
        Row r{p, c, SampleRecorder(tile, c.pixel, c.pFilm), RNG(Hash(pass.seed ^ kConnectTag, pix, uint64_t(pass.iteration))),
              // Media: the row's transmittance estimates (its own stream; unused without media).
              RNG(Hash(pass.seed ^ kMediaTag, pix, uint64_t(pass.iteration))), {}, {}};
        const int nL = light.count(p);
        const PathVertex *lv = light.path(p);
        const BSDF *lb = light.bsdfs(p);  // kept from generation, or rebuilt here
        if (!lb) {
            for (int i = 0; i < nL; ++i) lightB[i] = RebuildBSDF(in.ctx_, lv[i], TransportMode::Importance, wk.arena);
            lb = lightB.data();
        }
        r.camView = SubpathView{c.cv, c.cb, c.nC};
        r.ownLight = SubpathView{lv, lb, nL};
        camSums.build(in.ctx_, r.camView);
        chooseConnections(r);
        for (size_t i = 0; i < kPrefetchAhead; ++i) prefetch(i);  // loaded while the diagonal runs
        runDiagonal(r);
        runMatrix(r);
        r.rec.addRadiance(r.L * c.w);
        tile.addCount(c.pixel, 1);
        bad += r.rec.nonFinite;
        wk.arena.reset();
    }

    // Pixel mode: the camera subpath of this pixel sample, generated here (its
    // BSDFs stay in the arena): as bdpt draws it.
    CameraRow generateCameraRow(uint32_t p) {
        CameraRow c;
        const uint32_t k = p - in.paths_.tileBegin(ti);
        c.pixel = Point2i{tb.pMin.x + int(k % uint32_t(tileW)), tb.pMin.y + int(k / uint32_t(tileW))};
        smp.startPixelSample(c.pixel, pass.iteration);
        CameraSample cs;
        Point2 u = smp.get2D();
        cs.pFilm = Point2(c.pixel.x + u.x, c.pixel.y + u.y);
        cs.pLens = smp.get2D();
        Ray ray;
        c.w = pass.scene.camera->generateRay(cs, &ray);
        RNG camRng;  // camB not reset: the walk assigns the BSDF of every vertex it creates
        RNG *crng = pass.scene.features.media ? &(camRng = CameraSampleMediaRNG(smp, cs)) : nullptr;
        c.nC = c.w > 0 ? GenerateCameraSubpath(in.ctx_, ray, smp, wk.arena, pass.maxCam, camV.data(), camB.data(), crng)
                       : 0;
        c.pFilm = cs.pFilm;
        c.cv = camV.data();
        c.cb = camB.data();
        return c;
    }

    // Row-ordered modes: the stored camera subpath, its BSDFs rebuilt.
    CameraRow storedCameraRow(uint32_t p) {
        CameraRow c;
        c.pFilm = in.paths_.pFilm[p];
        c.pixel = Point2i{int(std::floor(c.pFilm.x)), int(std::floor(c.pFilm.y))};
        c.w = in.paths_.camWeight[p];
        c.nC = cam.count(p);
        c.cv = cam.path(p);
        c.cb = cam.bsdfs(p);  // kept from generation
        if (!c.cb) {
            for (int i = 0; i < c.nC; ++i) camB[i] = RebuildBSDF(in.ctx_, c.cv[i], TransportMode::Radiance, wk.arena);
            c.cb = camB.data();
        }
        return c;
    }

    void record(Row &r, int s, int t, const ConnectResult &res, Float scale) {
        const int layer = in.strategyLayer(s, t);
        const Spectrum shown = in.set_.visWeights ? res.L : res.unweighted;
        if (res.splat) {  // t = 1: light tracing
            r.rec.splat(res.pRaster, res.L * (scale * in.splatScale_));
            if (layer >= 0) r.rec.splat(res.pRaster, shown * (scale * in.splatScale_), layer);
            return;
        }
        r.L += res.L * scale;
        if (layer >= 0) r.rec.addLayer(layer, shown * (scale * r.c.w));
    }

    // Strategy (s, t) of the row's camera subpath with `lightView`.
    void run(Row &r, SubpathView lightView, int s, int t, Float scale) {
        ConnectSamples u;
        u.rng = &r.mediaRng;
        // Next-event and lens samples: the pixel sample's next dimensions
        // (as bdpt) in pixel mode, else a per-row generator.
        const bool pixelMode = pass.pixelMode;
        if (s == 1) {
            u.uLightSelect = pixelMode ? smp.get1D() : r.rng.uniform();
            u.uLight = pixelMode ? smp.get2D() : Point2(r.rng.uniform(), r.rng.uniform());
            u.infiniteLightsOnly = pass.nextEventMatrix;  // the other lights: M_{1,t}
        }
        if (t == 1) u.uLens = pixelMode ? smp.get2D() : Point2(r.rng.uniform(), r.rng.uniform());
        ConnectResult res;
        ++conn;
        bool ok = ConnectBDPT(in.ctx_, lightView, r.camView, s, t, u, &res);
        if (res.shadowRayTraced) ++shadow;
        if (ok) record(r, s, t, res, scale);
    }

    // Matrix strategies s >= 2, t >= 2: first choose every connection of
    // this row (its light endpoint's record is a random place in the
    // image-wide store: each connection otherwise stalls on cache misses,
    // measured 1.45 s of 6.2 s at 4 spp on the Cornell box), then run the
    // diagonal strategies while the first records load, then the connections.
    // Pixel mode: one participation number per pixel sample,
    // B_p^{s,t} = [u < rho_s] (each B_p^{s,t} has probability rho_s, as
    // Eq. 4 needs; they are nested over s, as BDPT's own-subpath lengths
    // are), so a pixel touches only the strategies it takes part in.
    void chooseConnections(Row &r) {
        pending.clear();
        const CameraRow &c = r.c;
        Float uRow = 0;
        if (pass.pixelMode && c.w > 0) {
            smp.startPixelSample(c.pixel, pass.iteration, kMatrixDim);
            uRow = smp.get1D();
        }
        const int maxT = pass.maxDepth + (pass.nextEventMatrix ? 1 : 0);
        const int minS = pass.nextEventMatrix ? 1 : 2;
        if (c.w > 0)
            for (int t = 2; t <= std::min(c.nC, maxT); ++t) {
                int32_t rank = -1;
                if (pass.pixelMode) {
                    if (!c.cv[t - 1].scatters() || !IsConnectible(c.cv[t - 1], &c.cb[t - 1])) continue;
                } else if (in.rank_[t].empty() || (rank = in.rank_[t][r.p]) < 0) {
                    // (empty: no eligible camera subpath of this length; this one's
                    // vertex t - 1 cannot connect)
                    continue;
                }
                // Matrices without columns take no row (chooseColumns returns at once).
                for (int s = minS; s + t - 2 <= pass.maxDepth && s <= in.maxColumnS_; ++s)
                    chooseColumns(r, s, t, rank, uRow);
            }
    }

    // Column k of M_{s,t} (s = 1: the emitter vertex of light subpath cols_[1][k]).
    void choose(int s, int t, uint64_t k, Float scale) {
        if (s == 1)
            pending.push_back({s, t, nullptr, light.path(in.cols_[1][k]), scale});
        else
            pending.push_back({s, t, in.columns(s) + k, nullptr, scale});
    }

    // Records are loaded kPrefetchAhead connections ahead: issuing all of a
    // row's prefetches at once stalled on the full fill buffers (perf: the
    // prefetch instructions took 5% of veach-ajar's time).
    static constexpr size_t kPrefetchAhead = 6;
    void prefetch(size_t i) const {
        if (i >= pending.size()) return;
        const char *rec = static_cast<const char *>(pending[i].address());
        __builtin_prefetch(rec);
        __builtin_prefetch(rec + 64);
    }

    // The columns of row p in M_{s,t} (rank: the row's place in rows_[t]).
    void chooseColumns(Row &r, int s, int t, int32_t rank, Float uRow) {
        const uint64_t Ls = in.cols_[s].size();
        const size_t N = pass.N;
        const int m = pass.m, maxDepth = pass.maxDepth;
        if (Ls == 0) return;
        if (in.set_.combinatorial) {
            for (uint64_t k = 0; k < Ls; ++k) choose(s, t, k, Float(1) / Float(N));  // Eq. 6
            return;
        }
        if (pass.diagonal) {  // Eq. 7
            if (s == 1 && HasMatrixOrigin(light, r.p))
                pending.push_back({s, t, nullptr, light.path(r.p), 1});
            else if (s >= 2 && light.eligible(r.p, s))
                choose(s, t, in.colPos_[light.offset[r.p] + uint32_t(s - 1)], 1);
            return;
        }
        // Rows take part with probability rho (BDPT's rate L_s / L by
        // default); I_p^{s,t} = B_p / rho * L_s / (L m) * sum_c M^{p, q_c}.
        const Float rho = in.set_.allRows ? Float(1) : Float(Ls) / Float(N);
        const Float scale = Float(Ls) / (Float(N) * m * rho);
        if (pass.pixelMode) {
            // eps_c: dimensions of this pixel sample, the same ones in
            // every iteration (stratified over them).
            if (uRow >= rho) return;
            smp.startPixelSample(r.c.pixel, pass.iteration, kMatrixDim + 1 + (s * (maxDepth + 1) + t) * m);
            for (int c = 0; c < m; ++c) choose(s, t, ColumnSampler::Column(smp.get1D(), Ls), scale);
            return;
        }
        // A randomly shifted 1D lattice over the row ranks chooses the rows.
        const ColumnSampler &cs = pass.samplers[size_t(s) * (maxDepth + 2) + t];
        if (rho < 1 && !cs.participates(uint64_t(rank), rho)) return;
        for (int c = 0; c < m; ++c) {
            double y = cs.coordinate(uint64_t(rank), c, r.rng.uniform());
            choose(s, t, ColumnSampler::Column(y, Ls), scale);
        }
    }

    // Diagonal strategies (Sec. 5.1): s = 0, s = 1 with this pixel's camera
    // subpath; t = 1 with this pixel's light subpath (Eq. 7). Pixel mode:
    // their next-event and lens samples from kConnectDim on.
    void runDiagonal(Row &r) {
        const int maxDepth = pass.maxDepth;
        if (pass.pixelMode) smp.startPixelSample(r.c.pixel, pass.iteration, kConnectDim);
        if (r.c.w > 0)
            for (int t = 2; t <= r.c.nC && t - 2 <= maxDepth; ++t) {
                run(r, r.ownLight, 0, t, 1);
                if (t - 1 <= maxDepth && pass.diagonalNextEvent) run(r, r.ownLight, 1, t, 1);
            }
        for (int s = 2; s <= r.ownLight.n && s - 1 <= maxDepth; ++s) run(r, r.ownLight, s, 1, 1);
    }

    // The chosen matrix connections, from the light endpoints' records
    // (Stored records: the store's vertex and BSDF, rebuilt when not kept).
    void runMatrix(Row &r) {
        for (size_t i = 0; i < pending.size(); ++i) {
            prefetch(i + kPrefetchAhead);
            const Pending &c = pending[i];
            ConnectSamples u;
            u.rng = &r.mediaRng;
            ConnectResult res;
            ++conn;
            if (c.s == 1) {  // next-event estimation through the matrix
                ++origins;
                const bool ok = ConnectLightOrigin(in.ctx_, *c.origin, camSums, r.camView, c.t, u, &res);
                if (res.shadowRayTraced) ++shadow;
                if (ok) record(r, c.s, c.t, res, c.scale);
                continue;
            }
            const LightRecord &rec = *c.rec;
            const PathVertex *zv = nullptr;
            const BSDF *zb = nullptr;
            if (rec.kind == RecordKind::Stored) {
                const uint32_t k = rec.vertex;
                zv = &light.v[k];
                if (!light.b.empty()) {
                    zb = &light.b[k];
                } else {
                    colB[0] = RebuildBSDF(in.ctx_, *zv, TransportMode::Importance, wk.arena);
                    zb = &colB[0];
                }
            }
            const bool ok = ConnectRecord(in.ctx_, rec, zv, zb, camSums, r.camView, c.s, c.t, u, &res);
            if (res.shadowRayTraced) ++shadow;
            if (ok) record(r, c.s, c.t, res, c.scale);
        }
    }

    const MBDPTIntegrator &in;
    const ConnectPass &pass;
    const SubpathStore &cam, &light;
    const int ti;
    const Bounds2i &tb;
    FilmTile &tile;
    Worker &wk;
    std::vector<BSDF> camB, lightB, colB;
    std::vector<PathVertex> camV;
    std::vector<Pending> pending;
    CameraSums camSums;  // the row's camera side of the MIS sums
    Sampler &smp;
    const int tileW;
    uint64_t conn = 0, shadow = 0, bad = 0, origins = 0;
};

void MBDPTIntegrator::connect(PassContext &ctx) {
    const int maxDepth = set_.maxDepth;
    ConnectPass pass{ctx.scene(), ctx.firstSample(), ctx.seed(), paths_.size(), maxDepth, set_.connections,
                     maxDepth + 2, maxDepth + 1, set_.sampling == MatrixSampling::Pixel,
                     set_.sampling == MatrixSampling::Diagonal && !set_.combinatorial, set_.nextEventMatrix,
                     !ctx.scene().lights.empty() && (!set_.nextEventMatrix || farLights_),
                     std::vector<ColumnSampler>(size_t(maxDepth + 2) * (maxDepth + 2))};
    const int minS = set_.nextEventMatrix ? 1 : 2;
    if (!pass.pixelMode)
        for (int t = 2; t <= maxDepth + 1; ++t)
            for (int s = minS; s + t - 2 <= maxDepth; ++s) {
                uint64_t h = Hash(pass.seed ^ kMatrixTag, uint64_t(pass.iteration), uint64_t(s), uint64_t(t));
                pass.samplers[size_t(s) * (maxDepth + 2) + t] = ColumnSampler(
                    set_.sampling, rows_[t].size(), pass.m, BitsToUniform(MixBits(h)), h, BitsToUniform(MixBits(h ^ kRowTag)));
            }
    ctx.forEachTile([&](int ti, const Bounds2i &tb, FilmTile &tile, Worker &wk) {
        TileConnector tc(*this, pass, ti, tb, tile, wk);
        for (uint32_t p = paths_.tileBegin(ti); p < paths_.tileEnd(ti); ++p) tc.connectRow(p);
        nConnect_ += tc.conn;
        nShadow_ += tc.shadow;
        nOrigin_ += tc.origins;
        ctx.addNonFinite(tc.bad);
    });
}

// ---------------------------------------------------------------- Fig. 4: matrix image
void MBDPTIntegrator::visualizeMatrix(PassContext &ctx) {
    const int s = set_.visS, t = set_.visT;
    const uint64_t seed = ctx.seed();
    const size_t N = paths_.size();
    const SubpathStore &cam = paths_.camera, &light = paths_.light;
    const std::vector<float> &camWeight = paths_.camWeight;
    std::vector<uint32_t> rowsU, colsU;
    for (size_t i = 0; i < N; ++i) {
        if (cam.eligible(i, t) && camWeight[i] > 0) rowsU.push_back(uint32_t(i));
        if (light.eligible(i, s)) colsU.push_back(uint32_t(i));
    }
    // "Unordered" as in Fig. 4: a random permutation of the rows and of the columns
    // (the index order of the rows is the pixel order, itself spatially coherent).
    auto shuffle = [&](std::vector<uint32_t> &v, uint64_t tag) {
        RNG rng(Hash(seed ^ kMatrixTag, tag));
        for (size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[size_t(rng.uniform() * i)]);
    };
    shuffle(rowsU, 1);
    shuffle(colsU, 2);
    std::vector<uint32_t> rowsO;
    for (uint32_t i : rows_[t])
        if (camWeight[i] > 0) rowsO.push_back(i);
    const std::vector<uint32_t> &colsO = cols_[s];
    int R = int(std::min<size_t>(rowsU.size(), set_.matrixResolution));
    int C = int(std::min<size_t>(colsU.size(), set_.matrixResolution));
    if (R == 0 || C == 0) {
        matrixImage_ = Image::RGB(1, 1);
        return;
    }
    Image ordered = Image::RGB(C, R), unordered = Image::RGB(C, R);
    const int maxCam = set_.maxDepth + 2, maxLight = set_.maxDepth + 1;
    auto fill = [&](const std::vector<uint32_t> &rows, const std::vector<uint32_t> &cols, Image &img) {
        ctx.parallelFor(R, 1, [&](int64_t i0, int64_t i1, Worker &wk) {
            std::vector<BSDF> camB(maxCam), colB(maxLight);
            for (int64_t i = i0; i < i1; ++i) {
                uint32_t p = rows[size_t((i + 0.5) * rows.size() / R)];
                const PathVertex *cv = cam.path(p);
                for (int k = 0; k < t; ++k) camB[k] = RebuildBSDF(ctx_, cv[k], TransportMode::Radiance, wk.arena);
                SubpathView camView{cv, camB.data(), t};
                for (int j = 0; j < C; ++j) {
                    uint32_t q = cols[size_t((j + 0.5) * cols.size() / C)];
                    const PathVertex *zv = light.path(q);
                    colB[s - 1] = RebuildBSDF(ctx_, zv[s - 1], TransportMode::Importance, wk.arena);
                    ConnectResult r;
                    Spectrum v(0);
                    RNG mediaRng(Hash(seed ^ kMediaTag, uint64_t(i) << 32 | uint32_t(j), uint64_t(s) << 32 | uint32_t(t)));
                    ConnectSamples cu;
                    cu.rng = &mediaRng;
                    if (ConnectBDPT(ctx_, SubpathView{zv, colB.data(), s}, camView, s, t, cu, &r))
                        v = r.L * camWeight[p];
                    for (int c = 0; c < 3; ++c) img.at(int(j), int(i), c) = float(v[c]);
                }
                wk.arena.reset();
            }
        });
    };
    fill(rowsO, colsO, ordered);
    fill(rowsU, colsU, unordered);
    ordered.setLayerRGB("unordered", unordered);
    ordered.metadata["mbdpt_strategy"] = std::to_string(s) + "," + std::to_string(t);
    ordered.metadata["mbdpt_rows"] = std::to_string(rowsU.size());
    ordered.metadata["mbdpt_columns"] = std::to_string(colsU.size());
    matrixImage_ = std::move(ordered);
    if (!set_.matrixFile.empty()) WriteImage(set_.matrixFile, matrixImage_);
}

// ---------------------------------------------------------------- one iteration = one pass
void MBDPTIntegrator::runPass(PassContext &ctx) {
    // Once per session (a resumed or split render starts at a later pass).
    if (!pathsReady_) paths_.init(ctx.tiles()), pathsReady_ = true;
    double start = Seconds();
    const bool pixelMode = set_.sampling == MatrixSampling::Pixel;
    paths_.generate(ctx, ctx_, set_.maxDepth, !pixelMode, pixelMode ? kLightDim : -1, /*keepLightBSDFs=*/true,
                    /*keepCameraBSDFs=*/!pixelMode);
    nCamVerts_ += paths_.camera.v.size();
    nLightVerts_ += paths_.light.v.size();
    double a = Seconds();
    reorder(ctx);
    buildRecords(ctx);
    double b = Seconds();
    if (ctx.pass() == 0 && set_.visS >= 0) visualizeMatrix(ctx);
    double c = Seconds();
    connect(ctx);
    double d = Seconds();
    secGen_ += a - start;
    secSort_ += b - a;
    secConnect_ += d - c;
}

void MBDPTIntegrator::endPass(PassContext &ctx) {
    ++iterations_;
    // Stored subpaths and reordering tables of this iteration, per sampled pixel.
    size_t bytes = paths_.bytes() + colRecords_.capacity() * sizeof(LightRecord) + colPos_.capacity() * 4 +
                   (lightDist_.capacity() + camDist_.capacity()) * sizeof(double);
    for (const auto *lists : {&rows_, &cols_})
        for (const auto &l : *lists) bytes += l.capacity() * 4;
    for (const auto &l : rank_) bytes += l.capacity() * 4;
    bytesPerPixel_ = std::max(bytesPerPixel_, double(bytes) / std::max<size_t>(1, paths_.size()));
}

std::string MBDPTIntegrator::statistics() const {
    std::ostringstream o;
    const double N = double(paths_.size());
    const double it = std::max(1, iterations_);
    o << "M-BDPT:\n";
    o << "  iterations: " << iterations_ << ", subpaths per iteration: " << N << " camera + " << N << " light\n";
    o << "  mean stored vertices per subpath: camera ";
    if (set_.sampling == MatrixSampling::Pixel)
        o << "- (pixel mode: generated at connection time, not stored)";
    else
        o << nCamVerts_ / std::max(1.0, N * it);
    o << ", light " << nLightVerts_ / std::max(1.0, N * it) << " (" << sizeof(PathVertex) << " bytes each)\n";
    o << "  memory per pixel (stored subpaths + reordering tables): " << bytesPerPixel_ << " bytes\n";
    o << "  connections: " << nConnect_ << " (shadow rays " << nShadow_ << "; next-event through the matrix "
      << nOrigin_ << ")\n";
    o << "  seconds: generation " << secGen_ << ", reordering " << secSort_ << ", connection " << secConnect_ << "\n";
    return o.str();
}

}  // namespace gradus
