#include "integrators/gradient/gradient_family.h"

#include <algorithm>
#include <chrono>
#include <memory>

#include "core/error.h"
#include "integrators/gradient/subpath_shift.h"

namespace gradus {

namespace {
// Seconds per byte of memory the process touches for the first time (page
// faults): 0.1-0.4 s per GB on most machines, 4.2 s per GB on some virtual
// machines. Timed once on 32 MB.
double FreshMemorySecondsPerByte() {
    static const double perByte = [] {
        constexpr size_t n = size_t(32) << 20;
        const auto t0 = std::chrono::steady_clock::now();
        std::unique_ptr<char[]> p(new char[n]);
        volatile char *q = p.get();
        for (size_t i = 0; i < n; i += 4096) q[i] = 1;  // one write per page: the faults
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / double(n);
    }();
    return perByte;
}
// Fresh bytes finishGradients allocates per pixel: the film's layer images,
// the gradient arrays, the solvers' buffers and the output image (a 512x512
// gpt finish spent 0.6 of its 0.7 s there at 4.2 s per GB: ~550 bytes/pixel).
constexpr double kFinishFreshBytesPerPixel = 600;
}  // namespace

void GradientFamily::initGradients(Film &film, bool useFilmFilter, bool lightTracing, bool samples) {
    gfilm_.init(film, useFilmFilter, lightTracing, samples);
    filmBounds_ = film.pixelBounds();
}

double GradientFamily::reconstructionEstimate(ReconstructionNorm norm, Float alpha) const {
    if (reconEstimate_ >= 0) return reconEstimate_;
    // Timed on n x n problems of 64 and 128 pixels: a fixed cost (thread
    // dispatch, FFT plans) and a cost per pixel, so that neither is scaled by
    // the other.
    auto timeAt = [&](int n) {
        GradientImages g;
        g.width = g.height = n;
        g.channels = 3;
        const size_t values = size_t(n) * n * 3;
        g.primal.resize(values);
        g.dx.resize(values);
        g.dy.resize(values);
        g.primalVar.assign(values, 0.01f);
        g.dxVar.assign(values, 0.01f);
        g.dyVar.assign(values, 0.01f);
        uint32_t h = 12345;  // deterministic noise: a realistic IRLS workload
        for (size_t i = 0; i < values; ++i) {
            h = h * 1664525u + 1013904223u;
            g.primal[i] = float(h >> 8) / float(1 << 24);
            g.dx[i] = 0.1f * (float(h & 0xffff) / 65536.f - 0.5f);
            g.dy[i] = -g.dx[i];
        }
        Image scratch;
        std::string report;
        const auto t0 = std::chrono::steady_clock::now();
        WriteGradientOutput(g, norm, alpha, &scratch, &report);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    timeAt(64);  // warm-up (first FFT plans, thread pool)
    const double t64 = timeAt(64), t128 = timeAt(128);
    const double perPixel = std::max(0.0, (t128 - t64) / (128.0 * 128 - 64.0 * 64));
    const double fixed = std::max(0.0, t64 - perPixel * 64 * 64);
    const double pixels = double(filmBounds_.area());
    reconEstimate_ = 1.5 * (fixed + perPixel * pixels) + kFinishFreshBytesPerPixel * pixels * FreshMemorySecondsPerByte();
    return reconEstimate_;
}

void GradientFamily::finishGradients(const Film &film, const RenderStats &stats, ReconstructionNorm norm,
                                     Float alpha, Image *out, double scale, const GradientImages *add) {
    GradientImages g = gfilm_.images(film, stats.spp);
    if (scale != 1) {
        for (auto *v : {&g.primal, &g.separated, &g.dx, &g.dy})
            for (float &x : *v) x = float(x * scale);
        for (auto *v : {&g.primalVar, &g.dxVar, &g.dyVar})
            for (float &x : *v) x = float(x * scale * scale);
    }
    if (add) {
        GRADUS_CHECK(add->width == g.width && add->height == g.height);
        auto sum = [](std::vector<float> &to, const std::vector<float> &from) {
            if (from.empty()) return;
            if (to.empty()) to.assign(from.size(), 0.f);
            for (size_t i = 0; i < to.size(); ++i) to[i] += from[i];
        };
        sum(g.primal, add->primal);
        sum(g.separated, add->separated);
        sum(g.dx, add->dx);
        sum(g.dy, add->dy);
        sum(g.primalVar, add->primalVar);
        sum(g.dxVar, add->dxVar);
        sum(g.dyVar, add->dyVar);
    }
    WriteGradientOutput(g, norm, alpha, out, &reconReport_);
}

// Separated light, K more samples of it (issue 59, item 2). Its paths are the
// s = 0 paths whose camera vertices x_1 .. x_{t-2} all scattered by a Dirac
// lobe (DiracCameraChain); every integrator that separates them gives them
// MIS weight 1, so the plain walks of DiracCameraWalk estimate the same
// integral and the K + 1 estimates are averaged with equal weights:
// - bdpt/gbdpt (MISWeight, bidir.cpp): a strategy (s', t') with t' >= 2 and
//   s' >= 1 connects at camera vertex x_{t'-1}, and one with t' = 1 connects
//   light vertex x_1 to the lens; either needs a non-delta endpoint and a
//   non-delta neighbour (the light vertex x_k is the emitter, reached from the
//   delta x_{k-1}), so every term of OtherStrategies is skipped and the weight is
//   1 / (1 + 0). The directly seen emitter, (0, 2), has only (1, 1) as its
//   alternative, which bdpt does not evaluate (MISWeight returns 1 for
//   s + t = 2, as pbrt-v3's bdpt).
// - gvcm: merges are tried and weighted only at MergeableIn vertices, which
//   with mergeRoughOnly (G-VCM's weights) excludes delta vertices, and never at
//   the light origin (the emitter x_k when s = 0); no merge term remains.
// - G-PM (gvcm mergeonly, chainEmission): s = 0 through a specular chain is
//   the only strategy of its path, weight 1 by construction.
// - gpt (gpt_terms.cpp emissionTerms): emission after a Dirac bounce (or
//   seen directly) takes the BSDF technique's weight 1; next-event
//   estimation cannot reach it (no light sample connects through a delta
//   vertex).
// Walk k's film position is uniform in the sample's pixel (as the sampler's
// film samples), its lens position uniform; numbers from an RNG keyed by the
// sampler's seed and the sample's film and lens position, so the main
// sample's numbers (and with K = 0 the images) do not change.
void GradientFamily::shareSeparated(GradientSample *s, int K) {
    if (K <= 0 || s->separated.isBlack()) return;
    const Float keep = Float(1) / Float(K + 1);
    s->primal = s->primal - s->separated * (1 - keep);
    s->separated *= keep;
}

void GradientFamily::separatedWalks(const BidirContext &ctx, int K, int maxDepth, const CameraSample &cs,
                                    const Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    const Float scale = Float(1) / Float(K + 1);
    const Point2i p = rec.pixel();
    RNG rng(Hash(sampler.seed() ^ 0x5e9a2a7edd1ac0ffULL, FloatBits(cs.pFilm.x), FloatBits(cs.pFilm.y),
                 FloatBits(cs.pLens.x) ^ (FloatBits(cs.pLens.y) << 1)));
    for (int k = 0; k < K; ++k) {
        CameraSample cw;
        cw.pFilm = Point2(p.x + Float(rng.uniform()), p.y + Float(rng.uniform()));
        cw.pLens = Point2(Float(rng.uniform()), Float(rng.uniform()));
        Ray ray;
        const Float w = ctx.camera->generateRay(cw, &ray);
        if (w == 0) continue;
        const Spectrum L = DiracCameraWalk(ctx, ray, maxDepth, rng, arena);
        gfilm_.recordSeparated(rec, cw.pFilm, L * (w * scale));
    }
}

}  // namespace gradus
