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

#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <chrono>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "core/stats.h"
#include "integrators/factories.h"

namespace gradus {

using namespace mbdpt;

std::unique_ptr<Integrator> CreateMBDPTIntegrator(const EntityDesc &d) { return std::make_unique<MBDPTIntegrator>(d); }

namespace {

constexpr uint64_t kConnectTag = 0x6d62647074000001ULL;
constexpr uint64_t kMatrixTag = 0x6d62647074000002ULL;
constexpr uint64_t kRowTag = 0x6d62647074000003ULL;
constexpr int kTileSize = 16;

// Per-thread scratch of generation and connection.
struct ThreadScratch {
    std::unique_ptr<Sampler> sampler;
    Arena arena;
    std::vector<PathVertex> camV, lightV;
    std::vector<BSDF> camB, lightB, colB;
};

}  // namespace

MBDPTIntegrator::MBDPTIntegrator(const EntityDesc &desc) : loc_(desc.loc) {
    const ParamSet &ps = desc.params;
    set_.maxDepth = ps.getInt("maxdepth", 5);
    set_.rrDepth = ps.getInt("rrdepth", 3);
    set_.lightStrategy = ps.getString("lightsamplestrategy", "power");
    set_.visStrategies = ps.getBool("visualizestrategies", false);
    set_.visWeights = ps.getBool("visualizeweights", false);
    ps.getInts("pixelbounds");
    if (set_.maxDepth < 0) throw Error(ps.locOf("maxdepth", desc.loc), "\"maxdepth\" must be >= 0");
    std::string h = ps.getString("misheuristic", "balance");
    if (h == "balance")
        set_.heuristic = MISHeuristic::Balance;
    else if (h == "power")
        set_.heuristic = MISHeuristic::Power;
    else
        throw Error(ps.locOf("misheuristic", desc.loc), "unknown \"misheuristic\" \"" + h + "\" (valid: balance, power)");
    std::string r = ps.getString("reorder", "distance");
    if (r == "distance")
        set_.reorder = Reorder::Distance;
    else if (r == "morton")
        set_.reorder = Reorder::Morton;
    else if (r == "none")
        set_.reorder = Reorder::None;
    else
        throw Error(ps.locOf("reorder", desc.loc), "unknown \"reorder\" \"" + r + "\" (valid: distance, morton, none)");
    std::string ms = ps.getString("matrixsampler", "lattice");
    if (ms == "lattice")
        set_.sampling = MatrixSampling::Lattice;
    else if (ms == "lhs")
        set_.sampling = MatrixSampling::LHS;
    else if (ms == "random")
        set_.sampling = MatrixSampling::Random;
    else if (ms == "diagonal")
        set_.sampling = MatrixSampling::Diagonal;
    else
        throw Error(ps.locOf("matrixsampler", desc.loc),
                    "unknown \"matrixsampler\" \"" + ms + "\" (valid: lattice, lhs, random, diagonal)");
    set_.connections = ps.getInt("connections", 1);
    if (set_.connections < 1 || set_.connections > 1024)
        throw Error(ps.locOf("connections", desc.loc), "\"connections\" must be in [1, 1024]");
    set_.combinatorial = ps.getBool("combinatorial", false);
    std::string mr = ps.getString("matrixrows", "matched");
    if (mr == "matched" || mr == "all")
        set_.allRows = mr == "all";
    else
        throw Error(ps.locOf("matrixrows", desc.loc), "unknown \"matrixrows\" \"" + mr + "\" (valid: matched, all)");
    std::string vm = ps.getString("visualizematrix", "");
    if (!vm.empty()) {
        int s = -1, t = -1;
        char extra;
        if (std::sscanf(vm.c_str(), "%d , %d %c", &s, &t, &extra) != 2 || s < 2 || t < 2 || s + t - 2 > set_.maxDepth)
            throw Error(ps.locOf("visualizematrix", desc.loc),
                        "\"visualizematrix\" must be \"s,t\" with s >= 2, t >= 2 and s + t - 2 <= maxdepth");
        set_.visS = s;
        set_.visT = t;
    }
    set_.matrixResolution = ps.getInt("matrixresolution", 256);
    if (set_.matrixResolution < 1) throw Error(ps.locOf("matrixresolution", desc.loc), "\"matrixresolution\" must be >= 1");
    set_.matrixFile = ps.getString("matrixfile", "");
}

std::string MBDPTIntegrator::LayerName(int s, int t) { return "mbdpt_s" + std::to_string(s) + "_t" + std::to_string(t); }

int MBDPTIntegrator::strategyLayer(int s, int t) const {
    if (layers_.empty() || s < 0 || t < 0 || s > set_.maxDepth + 2 || t > set_.maxDepth + 2) return -1;
    return layers_[size_t(s) * (set_.maxDepth + 3) + t];
}

void MBDPTIntegrator::preprocess(const Scene &scene, Film &film) {
    lightSampler_ = LightSampler(scene.lights, set_.lightStrategy, loc_);
    ctx_.init(scene, lightSampler_, set_.heuristic);
    ctx_.rrDepth = set_.rrDepth;
    Point2i full = film.fullResolution();
    int64_t sampled = film.sampleBounds().area();
    // One light subpath per sampled pixel: light tracing estimates the full image (see bdpt.cpp).
    splatScale_ = sampled > 0 ? Float(int64_t(full.x) * full.y) / Float(sampled) : 1;
    layers_.clear();
    if (set_.visStrategies || set_.visWeights) {
        layers_.assign(size_t(set_.maxDepth + 3) * (set_.maxDepth + 3), -1);
        for (int depth = 0; depth <= set_.maxDepth; ++depth)
            for (int t = 2; t <= depth + 2; ++t) {
                int s = depth + 2 - t;
                layers_[size_t(s) * (set_.maxDepth + 3) + t] = film.addLayer(LayerName(s, t));
            }
    }
    if (set_.visS >= 0 && set_.matrixFile.empty()) {
        std::string f = film.filename();
        size_t dot = f.find_last_of('.'), slash = f.find_last_of('/');
        if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) f = f.substr(0, dot);
        set_.matrixFile = f + "_matrix_s" + std::to_string(set_.visS) + "_t" + std::to_string(set_.visT) + ".exr";
    }
    // Tiles of sampled pixels; subpaths are numbered tile by tile.
    Bounds2i sb = film.sampleBounds();
    tileMin_.clear();
    tileMax_.clear();
    tileStart_.assign(1, 0);
    for (int y = sb.pMin.y; y < sb.pMax.y; y += kTileSize)
        for (int x = sb.pMin.x; x < sb.pMax.x; x += kTileSize) {
            Point2i a{x, y}, b{std::min(x + kTileSize, sb.pMax.x), std::min(y + kTileSize, sb.pMax.y)};
            tileMin_.push_back(a);
            tileMax_.push_back(b);
            tileStart_.push_back(tileStart_.back() + uint32_t((b.x - a.x) * (b.y - a.y)));
        }
}

// ---------------------------------------------------------------- stage 1: generation
void MBDPTIntegrator::generate(const Scene &scene, const Film &film, const Sampler &proto, int iteration) {
    const int ntiles = int(tileMin_.size());
    const size_t N = tileStart_.back();
    const int maxCam = set_.maxDepth + 2, maxLight = set_.maxDepth + 1;
    struct TileOut {
        std::vector<PathVertex> cv, lv;
        std::vector<uint8_t> cc, lc;
        std::vector<uint32_t> nc, nl;
    };
    std::vector<TileOut> out(ntiles);
    pFilm_.resize(N);
    camWeight_.resize(N);
    tbb::enumerable_thread_specific<ThreadScratch> scratch;
    tbb::parallel_for(0, ntiles, [&](int ti) {
        ThreadScratch &st = scratch.local();
        if (!st.sampler) {
            st.sampler = proto.clone();
            st.camV.resize(maxCam);
            st.lightV.resize(maxLight);
            st.camB.resize(maxCam);
            st.lightB.resize(maxLight);
        }
        TileOut &o = out[ti];
        uint32_t p = tileStart_[ti];
        for (int y = tileMin_[ti].y; y < tileMax_[ti].y; ++y)
            for (int x = tileMin_[ti].x; x < tileMax_[ti].x; ++x, ++p) {
                Point2i pixel{x, y};
                Sampler &smp = *st.sampler;
                smp.startPixelSample(pixel, iteration);
                CameraSample cs;
                Point2 u = smp.get2D();
                cs.pFilm = Point2(x + u.x, y + u.y);
                cs.pLens = smp.get2D();
                Ray ray;
                Float w = scene.camera->generateRay(cs, &ray);
                int nC = 0, nL = 0;
                for (auto &b : st.camB) b = BSDF();
                for (auto &b : st.lightB) b = BSDF();
                if (w > 0) nC = GenerateCameraSubpath(ctx_, ray, smp, st.arena, maxCam, st.camV.data(), st.camB.data());
                if (!scene.lights.empty())
                    nL = GenerateLightSubpath(ctx_, smp, st.arena, maxLight, st.lightV.data(), st.lightB.data());
                pFilm_[p] = cs.pFilm;
                camWeight_[p] = float(w);
                for (int i = 0; i < nC; ++i) {
                    o.cv.push_back(st.camV[i]);
                    o.cc.push_back(st.camV[i].type == VertexType::Surface && IsConnectible(st.camV[i], &st.camB[i]));
                }
                for (int i = 0; i < nL; ++i) {
                    o.lv.push_back(st.lightV[i]);
                    o.lc.push_back(st.lightV[i].type == VertexType::Surface && IsConnectible(st.lightV[i], &st.lightB[i]));
                }
                o.nc.push_back(uint32_t(nC));
                o.nl.push_back(uint32_t(nL));
                st.arena.reset();
            }
    });
    // Deterministic concatenation in tile order.
    auto concat = [&](SubpathStore &store, bool camera) {
        std::vector<size_t> vstart(ntiles + 1, 0);
        for (int ti = 0; ti < ntiles; ++ti) vstart[ti + 1] = vstart[ti] + (camera ? out[ti].cv.size() : out[ti].lv.size());
        store.v.resize(vstart[ntiles]);
        store.connectible.resize(vstart[ntiles]);
        store.offset.resize(N + 1);
        store.offset[N] = uint32_t(vstart[ntiles]);
        tbb::parallel_for(0, ntiles, [&](int ti) {
            const TileOut &o = out[ti];
            const auto &vs = camera ? o.cv : o.lv;
            const auto &cs = camera ? o.cc : o.lc;
            const auto &ns = camera ? o.nc : o.nl;
            std::copy(vs.begin(), vs.end(), store.v.begin() + vstart[ti]);
            std::copy(cs.begin(), cs.end(), store.connectible.begin() + vstart[ti]);
            uint32_t off = uint32_t(vstart[ti]);
            for (size_t j = 0; j < ns.size(); ++j) {
                store.offset[tileStart_[ti] + j] = off;
                off += ns[j];
            }
        });
    };
    concat(cam_, true);
    concat(light_, false);
    nCamVerts_ += cam_.v.size();
    nLightVerts_ += light_.v.size();
}

// ---------------------------------------------------------------- stage 2: reordering
void MBDPTIntegrator::reorder(const Scene &scene) {
    const size_t N = tileStart_.back();
    // Matrix strategies have s >= 2, t >= 2 and s + t - 2 <= maxDepth.
    const int maxLen = set_.maxDepth;
    rows_.resize(maxLen + 1);
    rank_.resize(maxLen + 1);
    cols_.resize(maxLen + 1);
    const Bounds3 &b = scene.bounds;
    auto build = [&](const SubpathStore &store, int len, std::vector<uint32_t> &sorted) {
        sorted.clear();
        for (size_t i = 0; i < N; ++i)
            if (store.eligible(i, len)) sorted.push_back(uint32_t(i));
        if (set_.reorder == Reorder::None || sorted.size() < 2) return;
        std::vector<std::pair<uint64_t, uint32_t>> keys(sorted.size());
        tbb::parallel_for(size_t(0), sorted.size(), [&](size_t k) {
            const PathVertex *v = store.path(sorted[k]);
            uint64_t key = set_.reorder == Reorder::Distance ? DistanceKey(DistanceMetric(v, len))
                                                              : MortonKey(v[len - 1].p, b);
            keys[k] = {key, sorted[k]};
        });
        // Ties broken by index: a total order, so the result is thread-count independent.
        tbb::parallel_sort(keys.begin(), keys.end());
        for (size_t k = 0; k < keys.size(); ++k) sorted[k] = keys[k].second;
    };
    for (int len = 2; len <= maxLen; ++len) {
        build(cam_, len, rows_[len]);
        build(light_, len, cols_[len]);
        rank_[len].assign(N, -1);
        const auto &r = rows_[len];
        tbb::parallel_for(size_t(0), r.size(), [&](size_t k) { rank_[len][r[k]] = int32_t(k); });
    }
}

// ---------------------------------------------------------------- stage 3: connection
void MBDPTIntegrator::connect(const Scene &scene, Film &film, int iteration, uint64_t seed) {
    const int ntiles = int(tileMin_.size());
    const size_t N = tileStart_.back();
    const int maxDepth = set_.maxDepth, m = set_.connections;
    const int maxCam = maxDepth + 2, maxLight = maxDepth + 1;
    const bool diagonal = set_.sampling == MatrixSampling::Diagonal && !set_.combinatorial;
    // Column samplers of the matrices of this iteration.
    std::vector<ColumnSampler> samplers(size_t(maxDepth + 1) * (maxDepth + 1));
    for (int t = 2; t <= maxDepth; ++t)
        for (int s = 2; s + t - 2 <= maxDepth; ++s) {
            uint64_t h = Hash(seed ^ kMatrixTag, uint64_t(iteration), uint64_t(s), uint64_t(t));
            samplers[size_t(s) * (maxDepth + 1) + t] = ColumnSampler(set_.sampling, rows_[t].size(), m,
                                                                     BitsToUniform(MixBits(h)), h,
                                                                     BitsToUniform(MixBits(h ^ kRowTag)));
        }
    std::vector<std::unique_ptr<FilmTile>> tiles(ntiles);
    tbb::enumerable_thread_specific<ThreadScratch> scratch;
    std::atomic<uint64_t> nConn{0}, nShadow{0};
    tbb::parallel_for(0, ntiles, [&](int ti) {
        if (InterruptRequested()) return;
        ThreadScratch &st = scratch.local();
        if (st.camB.empty()) {
            st.camB.resize(maxCam);
            st.lightB.resize(maxLight);
            st.colB.resize(maxLight);
        }
        Bounds2i tb{tileMin_[ti], tileMax_[ti]};
        auto tile = film.makeTile(tb);
        uint64_t conn = 0, shadow = 0;
        for (uint32_t p = tileStart_[ti]; p < tileStart_[ti + 1]; ++p) {
            Point2i pixel{int(std::floor(pFilm_[p].x)), int(std::floor(pFilm_[p].y))};
            SampleRecorder rec(*tile, pixel, pFilm_[p]);
            RNG rng(Hash(seed ^ kConnectTag, uint64_t(pixel.x) << 32 | uint32_t(pixel.y), uint64_t(iteration)));
            const int nC = cam_.count(p), nL = light_.count(p);
            const PathVertex *cv = cam_.path(p), *lv = light_.path(p);
            for (int i = 0; i < nC; ++i) st.camB[i] = RebuildBSDF(ctx_, cv[i], TransportMode::Radiance, st.arena);
            for (int i = 0; i < nL; ++i) st.lightB[i] = RebuildBSDF(ctx_, lv[i], TransportMode::Importance, st.arena);
            SubpathView camView{cv, st.camB.data(), nC}, ownLight{lv, st.lightB.data(), nL};
            const Float w = camWeight_[p];
            Spectrum L(0);
            auto record = [&](int s, int t, const ConnectResult &r, Float scale) {
                if (r.splat) {
                    rec.splat(r.pRaster, r.L * (scale * splatScale_));
                    return;
                }
                L += r.L * scale;
                int layer = strategyLayer(s, t);
                if (layer >= 0) rec.addLayer(layer, (set_.visWeights ? r.L : r.unweighted) * (scale * w));
            };
            auto run = [&](SubpathView light, int s, int t, Float scale) {
                ConnectSamples u;
                if (s == 1) {
                    u.uLightSelect = rng.uniform();
                    u.uLight = Point2(rng.uniform(), rng.uniform());
                }
                if (t == 1) u.uLens = Point2(rng.uniform(), rng.uniform());
                ConnectResult r;
                ++conn;
                bool ok = ConnectBDPT(ctx_, light, camView, s, t, u, &r);
                if (r.shadowRayTraced) ++shadow;
                if (ok) record(s, t, r, scale);
            };
            // Diagonal strategies (Sec. 5.1): s = 0, s = 1 with this pixel's camera
            // subpath; t = 1 with this pixel's light subpath (Eq. 7).
            if (w > 0)
                for (int t = 2; t <= nC && t - 2 <= maxDepth; ++t) {
                    run(ownLight, 0, t, 1);
                    if (t - 1 <= maxDepth && !scene.lights.empty()) run(ownLight, 1, t, 1);
                }
            for (int s = 2; s <= nL && s - 1 <= maxDepth; ++s) run(ownLight, s, 1, 1);
            // Matrix strategies s >= 2, t >= 2.
            if (w > 0)
                for (int t = 2; t <= std::min(nC, maxDepth); ++t) {
                    int32_t rank = rank_[t][p];
                    if (rank < 0) continue;
                    for (int s = 2; s + t - 2 <= maxDepth; ++s) {
                        const std::vector<uint32_t> &cols = cols_[s];
                        const uint64_t Ls = cols.size();
                        if (Ls == 0) continue;
                        auto connectTo = [&](uint32_t q, Float scale) {
                            const PathVertex *zv = light_.path(q);
                            SubpathView lview = ownLight;
                            if (q != p) {
                                st.colB[s - 1] = RebuildBSDF(ctx_, zv[s - 1], TransportMode::Importance, st.arena);
                                lview = SubpathView{zv, st.colB.data(), light_.count(q)};
                            }
                            run(lview, s, t, scale);
                            st.colB[s - 1] = BSDF();
                        };
                        if (set_.combinatorial) {
                            for (uint32_t q : cols) connectTo(q, Float(1) / Float(N));  // Eq. 6
                        } else if (diagonal) {
                            if (light_.eligible(p, s)) connectTo(p, 1);  // Eq. 7
                        } else {
                            const ColumnSampler &cs = samplers[size_t(s) * (maxDepth + 1) + t];
                            // Rows take part with probability rho (BDPT's rate L_s / L by
                            // default), chosen by a randomly shifted 1D lattice over the ranks.
                            Float rho = set_.allRows ? Float(1) : Float(Ls) / Float(N);
                            if (rho < 1 && !cs.participates(uint64_t(rank), rho)) continue;
                            const Float scale = Float(Ls) / (Float(N) * m * rho);
                            for (int c = 0; c < m; ++c) {
                                double y = cs.coordinate(uint64_t(rank), c, rng.uniform());
                                connectTo(cols[ColumnSampler::Column(y, Ls)], scale);
                            }
                        }
                    }
                }
            rec.addRadiance(L * w);
            tile->addCount(pixel, 1);
            st.arena.reset();
        }
        nConn += conn;
        nShadow += shadow;
        tiles[ti] = std::move(tile);
    });
    for (auto &t : tiles)
        if (t) film.mergeTile(*t);
    nConnect_ += nConn;
    nShadow_ += nShadow;
}

// ---------------------------------------------------------------- Fig. 4: matrix image
void MBDPTIntegrator::visualizeMatrix(const Scene &scene, uint64_t seed) {
    const int s = set_.visS, t = set_.visT;
    const size_t N = tileStart_.back();
    std::vector<uint32_t> rowsU, colsU;
    for (size_t i = 0; i < N; ++i) {
        if (cam_.eligible(i, t) && camWeight_[i] > 0) rowsU.push_back(uint32_t(i));
        if (light_.eligible(i, s)) colsU.push_back(uint32_t(i));
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
        if (camWeight_[i] > 0) rowsO.push_back(i);
    const std::vector<uint32_t> &colsO = cols_[s];
    int R = int(std::min<size_t>(rowsU.size(), set_.matrixResolution));
    int C = int(std::min<size_t>(colsU.size(), set_.matrixResolution));
    if (R == 0 || C == 0) {
        matrixImage_ = Image::RGB(1, 1);
        return;
    }
    Image ordered = Image::RGB(C, R), unordered = Image::RGB(C, R);
    const int maxCam = set_.maxDepth + 2, maxLight = set_.maxDepth + 1;
    tbb::enumerable_thread_specific<ThreadScratch> scratch;
    auto fill = [&](const std::vector<uint32_t> &rows, const std::vector<uint32_t> &cols, Image &img) {
        tbb::parallel_for(0, R, [&](int i) {
            ThreadScratch &st = scratch.local();
            if (st.camB.empty()) {
                st.camB.resize(maxCam);
                st.colB.resize(maxLight);
            }
            uint32_t p = rows[size_t((i + 0.5) * rows.size() / R)];
            const PathVertex *cv = cam_.path(p);
            for (int k = 0; k < t; ++k) st.camB[k] = RebuildBSDF(ctx_, cv[k], TransportMode::Radiance, st.arena);
            SubpathView camView{cv, st.camB.data(), t};
            for (int j = 0; j < C; ++j) {
                uint32_t q = cols[size_t((j + 0.5) * cols.size() / C)];
                const PathVertex *zv = light_.path(q);
                st.colB[s - 1] = RebuildBSDF(ctx_, zv[s - 1], TransportMode::Importance, st.arena);
                ConnectResult r;
                Spectrum v(0);
                if (ConnectBDPT(ctx_, SubpathView{zv, st.colB.data(), s}, camView, s, t, ConnectSamples(), &r))
                    v = r.L * camWeight_[p];
                for (int c = 0; c < 3; ++c) img.at(j, i, c) = float(v[c]);
            }
            st.arena.reset();
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
    (void)scene;
}

// ---------------------------------------------------------------- the iteration loop
RenderStats MBDPTIntegrator::render(const Scene &scene, Film &film, const Sampler &sampler, const RenderOptions &opts) {
    using Clock = std::chrono::steady_clock;
    auto t0 = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
    std::unique_ptr<tbb::global_control> gc;
    if (opts.nthreads > 0)
        gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, opts.nthreads);
    const int spp = opts.spp > 0 ? opts.spp : sampler.samplesPerPixel();
    const bool unlimited = opts.timeLimit > 0 && opts.spp <= 0;
    RenderStats stats;
    Progress progress("Rendering", unlimited ? 0 : spp, opts.quiet);
    double lastIter = 0;
    int done = 0;
    while (unlimited || done < spp) {
        if (InterruptRequested()) {
            stats.interrupted = true;
            break;
        }
        if (opts.timeLimit > 0 && done > 0 && elapsed() + lastIter > opts.timeLimit) {
            stats.timeLimited = true;
            break;
        }
        double start = elapsed();
        generate(scene, film, sampler, done);
        double a = elapsed();
        reorder(scene);
        double b = elapsed();
        if (done == 0 && set_.visS >= 0) visualizeMatrix(scene, opts.seed);
        double c = elapsed();
        connect(scene, film, done, opts.seed);
        double d = elapsed();
        if (InterruptRequested()) {  // as the driver: the partial iteration's merged tiles stay
            stats.interrupted = true;
            ++done;
            break;
        }
        secGen_ += a - start;
        secSort_ += b - a;
        secConnect_ += d - c;
        ++done;
        film.setSplatSamples(done);
        // Stored subpaths and reordering tables of this iteration, per sampled pixel.
        size_t bytes = cam_.bytes() + light_.bytes() + pFilm_.capacity() * sizeof(Point2) +
                       camWeight_.capacity() * sizeof(float);
        for (size_t k = 0; k < rows_.size(); ++k)
            bytes += rows_[k].capacity() * 4 + rank_[k].capacity() * 4 + cols_[k].capacity() * 4;
        bytesPerPixel_ = std::max(bytesPerPixel_, double(bytes) / std::max<size_t>(1, tileStart_.back()));
        lastIter = elapsed() - start;
        progress.update(done, elapsed(), opts.timeLimit);
    }
    progress.done(elapsed());
    film.setSplatSamples(done);
    iterations_ = done;
    stats.passes = done;
    stats.cameraSamples = int64_t(done) * int64_t(tileStart_.back());
    stats.seconds = elapsed();
    return stats;
}

std::string MBDPTIntegrator::statistics() const {
    std::ostringstream o;
    const double N = double(tileStart_.empty() ? 0 : tileStart_.back());
    const double it = std::max(1, iterations_);
    o << "M-BDPT:\n";
    o << "  iterations: " << iterations_ << ", subpaths per iteration: " << N << " camera + " << N << " light\n";
    o << "  mean stored vertices per subpath: camera " << nCamVerts_ / std::max(1.0, N * it) << ", light "
      << nLightVerts_ / std::max(1.0, N * it) << " (" << sizeof(PathVertex) << " bytes each)\n";
    o << "  memory per pixel (stored subpaths + reordering tables): " << bytesPerPixel_ << " bytes\n";
    o << "  connections: " << nConnect_ << " (shadow rays " << nShadow_ << ")\n";
    o << "  seconds: generation " << secGen_ << ", reordering " << secSort_ << ", connection " << secConnect_ << "\n";
    return o.str();
}

}  // namespace gradus
