// Photon lookup for vertex merging: the hash grid (integrators/common/photon_grid.h)
// against a kd-tree (nanoflann, Debian's libnanoflann-dev) on the light vertices
// of real VCM iterations: one light subpath per pixel stored as vcm stores them,
// queried at the first mergeable vertex of one camera subpath per pixel with the
// iteration-1 footprint radius (VCMFootprintRadius), single thread. Scenes: the
// own glass-cube and, when ../shared is present, water-caustic (its reference
// variant, 256x256). Reported per scene: build time per iteration, time per
// query, points found per query (equal for both structures: checked).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>
#include <nanoflann.hpp>

#include "integrators/common/bidir.h"
#include "integrators/common/photon_grid.h"
#include "integrators/vcm/vcm.h"
#include "lights/light_sampler.h"
#include "parser/scene_desc.h"
#include "job/job.h"
#include "samplers/rng_sampler.h"

using namespace gradus;

namespace {

struct Data {
    std::vector<Point3> points, queries;
    Float radius = 0;
};

// The light vertices and camera query points of one iteration of `file`.
const Data *Load(const std::string &file) {
    static std::map<std::string, std::unique_ptr<Data>> cache;
    auto it = cache.find(file);
    if (it != cache.end()) return it->second.get();
    auto d = std::make_unique<Data>();
    BuildOptions bo;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(ParseFile(file), bo);
    const Scene &scene = *job.scene;
    LightSampler ls(scene.lights, "power", FileLoc());
    BidirContext ctx;
    ctx.init(scene, ls, MISHeuristic::Balance);
    const Bounds2i bounds = job.film->sampleBounds();
    d->radius = VCMFootprintRadius(scene, bounds, 1);
    MergeKernel k;
    k.piN = 1;
    k.r2 = d->radius * d->radius;
    const VCMWeights w{&k, true, true, false};
    const int maxDepth = 10;
    RNG rng(7);
    RNGSampler smp(rng);
    Arena arena;
    std::vector<LightVertex> lv;
    for (int y = bounds.pMin.y; y < bounds.pMax.y; ++y)
        for (int x = bounds.pMin.x; x < bounds.pMax.x; ++x) {
            arena.reset();
            PathVertex *v;
            BSDF *b;
            AllocSubpath(arena, maxDepth + 2, &v, &b);
            const int n = GenerateLightSubpath(ctx, smp, arena, maxDepth + 1, v, b);
            VCMLightVertices(ctx, v, b, n, w, &lv);
            CameraSample cs;
            cs.pFilm = Point2(x + smp.get1D(), y + smp.get1D());
            cs.pLens = smp.get2D();
            Ray ray;
            if (scene.camera->generateRay(cs, &ray) == 0) continue;
            const int nc = GenerateCameraSubpath(ctx, ray, smp, arena, maxDepth + 2, v, b);
            for (int u = 1; u < nc; ++u)
                if (w.mergeable(v[u], &b[u])) {
                    d->queries.push_back(v[u].p);
                    break;
                }
        }
    for (const LightVertex &l : lv) d->points.push_back(l.p);
    return (cache[file] = std::move(d)).get();
}

PhotonGrid::ParallelFor Serial() {
    return [](int64_t n, int64_t grain, const std::function<void(int64_t, int64_t)> &fn) {
        for (int64_t b = 0; b < n; b += grain) fn(b, std::min(n, b + grain));
    };
}

struct Cloud {
    const std::vector<Point3> *p;
    size_t kdtree_get_point_count() const { return p->size(); }
    double kdtree_get_pt(size_t i, size_t dim) const { return dim == 0 ? (*p)[i].x : dim == 1 ? (*p)[i].y : (*p)[i].z; }
    template <class BBox>
    bool kdtree_get_bbox(BBox &) const {
        return false;
    }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 3, uint32_t>;

// Counts the points within the radius (as the grid's callback does), no storage.
struct CountResult {
    double r2;
    size_t n = 0;
    void init() { n = 0; }
    size_t size() const { return n; }
    bool full() const { return true; }
    bool addPoint(double d2, uint32_t) {
        if (d2 < r2) ++n;
        return true;
    }
    double worstDist() const { return r2; }
};

size_t GridCount(const PhotonGrid &g, const std::vector<Point3> &q) {
    size_t n = 0;
    for (const Point3 &p : q) g.query(p, [&](uint32_t, Float) { ++n; });
    return n;
}

size_t KdCount(const KdTree &t, const std::vector<Point3> &q, double r2) {
    size_t n = 0;
    nanoflann::SearchParams sp(32, 0, false);
    for (const Point3 &p : q) {
        const double pt[3] = {p.x, p.y, p.z};
        CountResult res{r2};
        t.radiusSearchCustomCallback(pt, res, sp);
        n += res.n;
    }
    return n;
}

void Report(benchmark::State &st, const Data &d, size_t found) {
    st.counters["points"] = double(d.points.size());
    st.counters["queries"] = double(d.queries.size());
    st.counters["found/query"] = double(found) / std::max<size_t>(d.queries.size(), 1);
}

void GridBuild(benchmark::State &st, const std::string &file) {
    const Data &d = *Load(file);
    for (auto _ : st) {
        PhotonGrid g;
        g.build(d.points.size(), [&](size_t i) { return d.points[i]; }, d.radius, Serial());
        benchmark::DoNotOptimize(g.size());
    }
    st.counters["points"] = double(d.points.size());
}

void GridQuery(benchmark::State &st, const std::string &file) {
    const Data &d = *Load(file);
    PhotonGrid g;
    g.build(d.points.size(), [&](size_t i) { return d.points[i]; }, d.radius, Serial());
    size_t found = 0;
    for (auto _ : st) {
        found = GridCount(g, d.queries);
        benchmark::DoNotOptimize(found);
    }
    Report(st, d, found);
    st.SetItemsProcessed(int64_t(st.iterations() * d.queries.size()));
}

void KdBuild(benchmark::State &st, const std::string &file) {
    const Data &d = *Load(file);
    Cloud c{&d.points};
    for (auto _ : st) {
        KdTree t(3, c, nanoflann::KDTreeSingleIndexAdaptorParams(int(st.range(0))));
        t.buildIndex();
        benchmark::DoNotOptimize(t.size(t));
    }
    st.counters["points"] = double(d.points.size());
}

void KdQuery(benchmark::State &st, const std::string &file) {
    const Data &d = *Load(file);
    Cloud c{&d.points};
    KdTree t(3, c, nanoflann::KDTreeSingleIndexAdaptorParams(int(st.range(0))));
    t.buildIndex();
    size_t found = 0;
    for (auto _ : st) {
        found = KdCount(t, d.queries, d.radius * d.radius);
        benchmark::DoNotOptimize(found);
    }
    Report(st, d, found);
    PhotonGrid g;
    g.build(d.points.size(), [&](size_t i) { return d.points[i]; }, d.radius, Serial());
    if (found != GridCount(g, d.queries)) st.SkipWithError("kd-tree and grid disagree");
    st.SetItemsProcessed(int64_t(st.iterations() * d.queries.size()));
}

void Register(const std::string &name, const std::string &file) {
    if (!std::filesystem::exists(file)) return;
    benchmark::RegisterBenchmark(("GridBuild/" + name).c_str(), GridBuild, file)->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("GridQuery/" + name).c_str(), GridQuery, file)->Unit(benchmark::kMillisecond);
    for (int leaf : {4, 16})
        benchmark::RegisterBenchmark(("KdBuild/" + name).c_str(), KdBuild, file)->Arg(leaf)->Unit(benchmark::kMillisecond);
    for (int leaf : {4, 16})
        benchmark::RegisterBenchmark(("KdQuery/" + name).c_str(), KdQuery, file)->Arg(leaf)->Unit(benchmark::kMillisecond);
}

}  // namespace

int main(int argc, char **argv) {
    Register("glass-cube", GRADUS_SOURCE_DIR "/scenes/glass-cube.pbrt");
    Register("water-caustic", GRADUS_SOURCE_DIR "/../shared/references/water-caustic/ref.pbrt");
    benchmark::Initialize(&argc, argv);
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
