#include "lights/light_sampler.h"

#include <atomic>

#include "core/error.h"
#include "samplers/rng.h"

namespace gradus {

namespace {
// Points at which a voxel's distribution is estimated (see light_sampler.h): the first kVoxelSamples
// Halton points in 5 dimensions (3 for the position in the voxel, 2 for the
// light sample), the same for every voxel, so computed once.
constexpr int kVoxelSamples = 32;
struct HaltonTable {
    Float v[kVoxelSamples][5];
    HaltonTable() {
        static const int primes[] = {2, 3, 5, 7, 11};
        for (int s = 0; s < kVoxelSamples; ++s)
            for (int d = 0; d < 5; ++d) {
                const int base = primes[d];
                Float inv = Float(1) / base, f = inv, r = 0;
                for (uint64_t a = uint64_t(s); a; a /= base, f *= inv) r += Float(a % base) * f;
                v[s][d] = r;
            }
    }
};
const HaltonTable &VoxelPoints() {
    static const HaltonTable table;
    return table;
}
}  // namespace

// Voxel distributions in a flat array of atomic pointers: lookups are one
// load; a missing voxel is built by whichever thread needs it first and
// published with a compare-and-swap (a losing builder discards its copy).
// A voxel's distribution is one block of n + 1 cumulative values (cdf[0] = 0,
// cdf[n] = 1): sampling and the pmf read that block alone, so a lookup costs
// two dependent loads (the voxel's pointer, its block), not four
// (pointer, Distribution1D, its cdf and its func arrays).
struct LightSampler::Grid {
    Bounds3 bounds;
    int res[3] = {1, 1, 1};
    std::unique_ptr<std::atomic<const Float *>[]> voxels;
    size_t count = 0;
    std::atomic<int64_t> built{0};
    ~Grid() {
        for (size_t i = 0; i < count; ++i) delete[] voxels[i].load();
    }
};

namespace {
// Index i with cdf[i] <= u < cdf[i + 1], over buckets of positive width.
int SampleCdf(const Float *cdf, int n, Float u, Float *pmf) {
    u = Clamp<Float>(u, 0, OneMinusEpsilon);
    int lo = 0, hi = n;  // invariant: cdf[lo] <= u < cdf[hi]
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    if (pmf) *pmf = cdf[lo + 1] - cdf[lo];
    return lo;
}
}  // namespace

LightSampler::LightSampler() = default;
LightSampler::~LightSampler() = default;
LightSampler::LightSampler(LightSampler &&) noexcept = default;
LightSampler &LightSampler::operator=(LightSampler &&) noexcept = default;

LightSampler::LightSampler(const std::vector<std::shared_ptr<Light>> &lights, const std::string &strategy,
                           const FileLoc &loc, const Bounds3 &bounds)
    : strategy_(strategy) {
    if (strategy != "uniform" && strategy != "power" && strategy != "spatial")
        throw Error(loc, "unknown light sample strategy \"" + strategy + "\" (valid: uniform, power, spatial)");
    std::vector<Float> w;
    size_t nSlots = 1;
    int bits = 0;
    while (nSlots < 2 * lights.size()) nSlots <<= 1, ++bits;
    slots_.assign(nSlots, {nullptr, -1});
    slotShift_ = 64 - bits;
    for (const auto &l : lights) {
        size_t h = bits ? size_t((uint64_t(uintptr_t(l.get())) * 0x9e3779b97f4a7c15ULL) >> slotShift_) : 0;
        while (slots_[h].first && slots_[h].first != l.get()) h = (h + 1) & (nSlots - 1);
        slots_[h] = {l.get(), int(lights_.size())};
        lights_.push_back(l.get());
        w.push_back(strategy == "uniform" ? 1 : std::max<Float>(0, l->power().y()));
    }
    if (!w.empty()) distrib_ = Distribution1D(w.data(), int(w.size()));
    if (strategy == "spatial" && lights_.size() > 1 && !bounds.empty()) {
        grid_ = std::make_unique<Grid>();
        grid_->bounds = bounds;
        Vec3 d = bounds.diagonal();
        Float maxExtent = MaxComponent(d);
        for (int i = 0; i < 3; ++i)
            grid_->res[i] = maxExtent > 0 ? std::max(1, int(std::round(64 * d[i] / maxExtent))) : 1;
        grid_->count = size_t(grid_->res[0]) * grid_->res[1] * grid_->res[2];
        grid_->voxels.reset(new std::atomic<const Float *>[grid_->count]);
        for (size_t i = 0; i < grid_->count; ++i) grid_->voxels[i].store(nullptr, std::memory_order_relaxed);
    }
}

int64_t LightSampler::voxelsBuilt() const { return grid_ ? grid_->built.load() : 0; }

const Float *LightSampler::lookup(const Point3 &p) const {
    const Grid &g = *grid_;
    int vi[3];
    for (int i = 0; i < 3; ++i) {
        Float ext = g.bounds.pMax[i] - g.bounds.pMin[i];
        Float t = ext > 0 ? (p[i] - g.bounds.pMin[i]) / ext : 0;
        // Clamped before the integer conversion: points far outside the bounds
        // (t = 1e73 in a fuzzed scene) made it undefined; NaN goes to voxel 0.
        t = t > 0 ? std::min<Float>(t, 1) : 0;
        vi[i] = Clamp(int(t * g.res[i]), 0, g.res[i] - 1);
    }
    size_t key = (size_t(vi[2]) * g.res[1] + vi[1]) * g.res[0] + vi[0];
    if (const Float *d = g.voxels[key].load(std::memory_order_acquire)) return d;
    // Estimate each light's contribution at kVoxelSamples low-discrepancy points of the voxel.
    Bounds3 vb;
    for (int i = 0; i < 3; ++i) {
        Float ext = g.bounds.pMax[i] - g.bounds.pMin[i];
        vb.pMin[i] = g.bounds.pMin[i] + ext * vi[i] / g.res[i];
        vb.pMax[i] = g.bounds.pMin[i] + ext * (vi[i] + 1) / g.res[i];
    }
    const HaltonTable &h = VoxelPoints();
    std::vector<Float> contrib(lights_.size(), 0);
    for (int s = 0; s < kVoxelSamples; ++s) {
        const Float *x = h.v[s];
        Point3 po(Lerp(x[0], vb.pMin.x, vb.pMax.x), Lerp(x[1], vb.pMin.y, vb.pMax.y), Lerp(x[2], vb.pMin.z, vb.pMax.z));
        Interaction ref(po, Normal3(0, 0, 0), Vec3(0, 0, 0));
        Point2 u(x[3], x[4]);
        for (size_t j = 0; j < lights_.size(); ++j) {
            LightLiSample ls;
            if (lights_[j]->sampleLi(ref, u, &ls) && ls.pdf > 0) contrib[j] += ls.L.y() / ls.pdf;
        }
    }
    Float sum = 0;
    for (Float c : contrib) sum += c;
    Float avg = sum / (kVoxelSamples * Float(contrib.size()));
    Float floorC = avg > 0 ? 1e-3 * avg : 1;
    for (Float &c : contrib) c = std::max(c, floorC);
    Float total = 0;
    for (Float c : contrib) total += c;
    const int n = int(contrib.size());
    Float *cdf = new Float[size_t(n) + 1];
    cdf[0] = 0;
    for (int j = 0; j < n; ++j) cdf[j + 1] = cdf[j] + contrib[j] / total;
    cdf[n] = 1;
    const Float *expected = nullptr;
    if (g.voxels[key].compare_exchange_strong(expected, cdf, std::memory_order_acq_rel)) {
        ++grid_->built;
        return cdf;
    }
    delete[] cdf;
    return expected;
}

const Light *LightSampler::sample(Float u, Float *pmf) const {
    if (lights_.empty()) { *pmf = 0; return nullptr; }
    int i = distrib_.sampleDiscrete(u, pmf);
    return lights_[i];
}

int LightSampler::indexOf(const Light *light) const {
    const size_t mask = slots_.size() - 1;
    if (slots_.empty() || !light) return -1;
    size_t h = slotShift_ < 64 ? size_t((uint64_t(uintptr_t(light)) * 0x9e3779b97f4a7c15ULL) >> slotShift_) : 0;
    for (;; h = (h + 1) & mask) {
        if (slots_[h].first == light) return slots_[h].second;
        if (!slots_[h].first) return -1;
    }
}

Float LightSampler::pmf(const Light *light) const {
    int i = indexOf(light);
    return i < 0 ? 0 : distrib_.discretePmf(i);
}

const Light *LightSampler::sample(const Point3 &p, Float u, Float *pmf) const {
    if (!grid_) return sample(u, pmf);
    int i = SampleCdf(lookup(p), int(lights_.size()), u, pmf);
    return lights_[i];
}

Float LightSampler::pmf(const Point3 &p, const Light *light) const {
    if (!grid_) return pmf(light);
    int i = indexOf(light);
    if (i < 0) return 0;
    const Float *cdf = lookup(p);
    return cdf[i + 1] - cdf[i];
}

}  // namespace gradus
