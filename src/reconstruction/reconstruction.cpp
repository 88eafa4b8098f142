#include "reconstruction/reconstruction.h"

#include <atomic>
#include <chrono>
#include <limits>
#include <algorithm>
#include <cmath>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "reconstruction/dct_solver.h"
#include "reconstruction/poisson_ops.h"

namespace gradus {

using recon::PoissonProblem;

ReconstructionOptions ReconstructionOptions::L1Default() { return ReconstructionOptions(); }

ReconstructionOptions ReconstructionOptions::L1Reference() {
    ReconstructionOptions o;
    o.norm = ReconstructionNorm::L1;
    o.irlsIterations = 20;
    o.cgIterations = 50;
    o.cgTolerance = 0;
    o.preconditioner = Preconditioner::None;
    o.initFromL2 = false;
    return o;
}

ReconstructionOptions ReconstructionOptions::L2Exact(double alpha) {
    ReconstructionOptions o;
    o.norm = ReconstructionNorm::L2;
    o.l2Method = L2Method::Exact;
    o.alpha = alpha;
    return o;
}

ReconstructionOptions ReconstructionOptions::L2CG(double alpha) {
    ReconstructionOptions o;
    o.norm = ReconstructionNorm::L2;
    o.l2Method = L2Method::CG;
    o.alpha = alpha;
    o.cgIterations = 2000;
    o.cgTolerance = 1e-6;
    o.preconditioner = Preconditioner::Multigrid;
    return o;
}

ReconstructionOptions ReconstructionOptions::Weighted() {
    ReconstructionOptions o;
    o.norm = ReconstructionNorm::Weighted;
    o.cgIterations = 500;
    o.cgTolerance = 1e-5;
    o.preconditioner = Preconditioner::Multigrid;
    return o;
}

ReconstructionOptions ReconstructionOptions::Hybrid(double alpha) {
    ReconstructionOptions o;
    o.norm = ReconstructionNorm::Hybrid;
    o.alpha = alpha;
    return o;
}

ReconstructionOptions ReconstructionOptions::Preset(const std::string &name) {
    if (name == "hybrid") return Hybrid();
    if (name == "l1") return L1Default();
    if (name == "l1-reference") return L1Reference();
    if (name == "l2") return L2Exact();
    if (name == "l2-cg") return L2CG();
    if (name == "weighted") return Weighted();
    throw Error("unknown preset '" + name + "' (valid: hybrid, l1, l1-reference, l2, l2-cg, weighted)");
}

ReconstructionNorm ParseReconstructionNorm(const std::string &name) {
    if (name == "l2" || name == "L2") return ReconstructionNorm::L2;
    if (name == "l1" || name == "L1") return ReconstructionNorm::L1;
    if (name == "weighted") return ReconstructionNorm::Weighted;
    if (name == "hybrid") return ReconstructionNorm::Hybrid;
    throw Error("unknown reconstruction norm '" + name + "' (valid: l2, l1, weighted, hybrid)");
}

std::vector<float> CombineScales(const std::vector<float> &fine, const std::vector<float> &coarse, int W, int H,
                                 int C, double sigma) {
    const size_t N = size_t(W) * H, rowLen = size_t(W) * C;
    if (fine.size() != N * C || coarse.size() != N * C) throw Error("reconstruction: CombineScales: size mismatch");
    if (!(sigma >= 0) || !std::isfinite(sigma)) throw Error("reconstruction: lowpass sigma must be finite and >= 0");
    // In double: with values near the float limit (clamped film sums of extreme
    // scenes, +-3.4e38) coarse - fine overflows float and the blur turned the
    // infinities into NaN; the result is clamped back into the float range.
    std::vector<double> d(N * C);
    for (size_t i = 0; i < N * C; ++i) d[i] = double(coarse[i]) - double(fine[i]);
    if (sigma > 0) {
        // Normalised Gaussian taps to 3 sigma.
        const int R = std::max(1, int(std::ceil(3 * sigma)));
        std::vector<double> k(2 * R + 1);
        double ks = 0;
        for (int j = -R; j <= R; ++j) ks += std::exp(-0.5 * j * j / (sigma * sigma));
        for (int j = -R; j <= R; ++j) k[j + R] = std::exp(-0.5 * j * j / (sigma * sigma)) / ks;
        // Half-sample symmetric extension (x[-1] = x[0], x[n] = x[n-1]): the
        // blur matrix is then symmetric with unit row sums, so it keeps the sum.
        auto mirror = [](int i, int n) {
            const int p = 2 * n;
            i %= p;
            if (i < 0) i += p;
            return i < n ? i : p - 1 - i;
        };
        std::vector<double> tmp(N * C);
        // Horizontal: each row padded by R mirrored pixels, then contiguous sums.
        tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int> &rows) {
            std::vector<double> pad(size_t(W + 2 * R) * C);
            for (int y = rows.begin(); y < rows.end(); ++y) {
                const double *src = &d[size_t(y) * rowLen];
                for (int x = -R; x < W + R; ++x)
                    for (int c = 0; c < C; ++c) pad[size_t(x + R) * C + c] = src[size_t(mirror(x, W)) * C + c];
                double *out = &tmp[size_t(y) * rowLen];
                std::fill(out, out + rowLen, 0.0);
                for (int j = 0; j <= 2 * R; ++j) {
                    const double kj = k[j];
                    const double *in = &pad[size_t(j) * C];
                    for (size_t i = 0; i < rowLen; ++i) out[i] += kj * in[i];
                }
            }
        });
        // Vertical: each output row is a weighted sum of whole (mirrored) rows.
        tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int> &rows) {
            for (int y = rows.begin(); y < rows.end(); ++y) {
                double *out = &d[size_t(y) * rowLen];
                std::fill(out, out + rowLen, 0.0);
                for (int j = -R; j <= R; ++j) {
                    const double kj = k[j + R];
                    const double *in = &tmp[size_t(mirror(y + j, H)) * rowLen];
                    for (size_t i = 0; i < rowLen; ++i) out[i] += kj * in[i];
                }
            }
        });
    }
    constexpr double big = std::numeric_limits<float>::max();
    std::vector<float> out(N * C);
    for (size_t i = 0; i < N * C; ++i) out[i] = float(std::clamp(double(fine[i]) + d[i], -big, big));
    return out;
}

const char *ReconstructionNormName(ReconstructionNorm norm) {
    switch (norm) {
    case ReconstructionNorm::L2: return "l2";
    case ReconstructionNorm::L1: return "l1";
    case ReconstructionNorm::Weighted: return "weighted";
    case ReconstructionNorm::Hybrid: return "hybrid";
    }
    return "?";
}

namespace {

// Checks one interleaved buffer and copies it to planar storage. Entries of
// missing edges (last column of dx, last row of dy) are ignored and zeroed.
void ToPlanar(const GradientImages &in, const std::vector<float> &src, const char *layer,
              int skipLastCol, int skipLastRow, bool nonNegative, std::vector<float> &dst) {
    const int W = in.width, H = in.height, C = in.channels;
    const size_t N = size_t(W) * H;
    if (src.size() != N * C) {
        std::ostringstream m;
        m << "reconstruction: layer '" << layer << "' has " << src.size() << " values, expected "
          << W << "x" << H << "x" << C << " = " << N * C;
        throw Error(m.str());
    }
    dst.assign(N * C, 0.f);
    auto bad = [&](float v) { return !std::isfinite(v) || (nonNegative && v < 0); };
    std::atomic<bool> anyBad{false};
    tbb::parallel_for(tbb::blocked_range<int>(0, H - skipLastRow), [&](const tbb::blocked_range<int> &rows) {
        bool b = false;
        for (int y = rows.begin(); y < rows.end(); ++y)
            for (int x = 0; x < W - skipLastCol; ++x)
                for (int c = 0; c < C; ++c) {
                    const size_t i = size_t(y) * W + x;
                    const float v = src[i * C + c];
                    b |= bad(v);
                    dst[c * N + i] = v;
                }
        if (b) anyBad = true;
    });
    if (!anyBad) return;
    // Report the first bad value in scan order (deterministic message).
    for (int y = 0; y < H - skipLastRow; ++y)
        for (int x = 0; x < W - skipLastCol; ++x)
            for (int c = 0; c < C; ++c) {
                const float v = src[(size_t(y) * W + x) * C + c];
                if (!bad(v)) continue;
                std::ostringstream m;
                m << "reconstruction: layer '" << layer << "' has "
                  << (std::isnan(v) ? "a NaN" : std::isinf(v) ? "an infinite" : "a negative")
                  << " value at pixel (" << x << ", " << y << "), channel " << c;
                throw Error(m.str());
            }
}

// Per-term weights 1 / (channel-mean variance + floor), see reconstruction.h.
void InverseVarianceWeights(const PoissonProblem &P, const std::vector<float> &var, bool edgeX,
                            bool edgeY, std::vector<float> &w, double *meanVar) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    w.assign(N, 0.f);
    double sum = 0;
    size_t count = 0;
    for (int y = 0; y < H - (edgeY ? 1 : 0); ++y)
        for (int x = 0; x < W - (edgeX ? 1 : 0); ++x) {
            size_t i = size_t(y) * W + x;
            double v = 0;
            for (int c = 0; c < C; ++c) v += var[c * N + i];
            w[i] = float(v / C);  // temporarily the mean variance
            sum += v / C;
            ++count;
        }
    double mean = count ? sum / count : 0;
    *meanVar = mean;
    double floor = mean > 0 ? 1e-3 * mean : 1.0;
    for (int y = 0; y < H - (edgeY ? 1 : 0); ++y)
        for (int x = 0; x < W - (edgeX ? 1 : 0); ++x) {
            size_t i = size_t(y) * W + x;
            w[i] = float(1.0 / (w[i] + floor));
        }
}

std::vector<float> ToInterleaved(const std::vector<float> &planar, int C, size_t N) {
    std::vector<float> out(planar.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, N, 4096), [&](const tbb::blocked_range<size_t> &r) {
        for (size_t i = r.begin(); i < r.end(); ++i)
            for (int c = 0; c < C; ++c) out[i * C + c] = planar[c * N + i];
    });
    return out;
}

// Hybrid: L1 at fine scales, the primal's coarse scales (reconstruction.h).
ReconstructionResult ReconstructHybrid(const GradientImages &in, const ReconstructionOptions &opt) {
    const auto h0 = std::chrono::steady_clock::now();
    ReconstructionOptions o1 = opt;
    o1.norm = ReconstructionNorm::L1;
    ReconstructionResult r = Reconstruct(in, o1);
    r.image = CombineScales(r.image, in.primal, r.width, r.height, r.channels, opt.lowpassSigma);
    r.stats.method = "hybrid (l1-irls + lowpass of primal - l1)";
    r.stats.objective = 0;  // neither norm's minimiser
    r.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - h0).count();
    return r;
}

void CheckSizeAndOptions(const GradientImages &in, const ReconstructionOptions &opt) {
    if (in.width <= 0 || in.height <= 0)
        throw Error("reconstruction: image size " + std::to_string(in.width) + "x" +
                    std::to_string(in.height) + " is empty");
    if (in.channels < 1 || in.channels > recon::kMaxChannels)
        throw Error("reconstruction: " + std::to_string(in.channels) +
                    " channels (supported: 1 to " + std::to_string(recon::kMaxChannels) + ")");
    if (std::isnan(opt.alpha) || opt.alpha < 0)
        throw Error("reconstruction: alpha must be >= 0 (got " + std::to_string(opt.alpha) + ")");
    if (opt.cgIterations < 0 || opt.irlsIterations < 1)
        throw Error("reconstruction: CG iterations must be >= 0 and IRLS iterations >= 1");
    if (!(opt.irlsRegInit > 0) || !(opt.irlsRegFactor > 0) || !(opt.cgTolerance >= 0))
        throw Error("reconstruction: IRLS regularisation and CG tolerance must be positive");
}

// Fills P's size and planar p, gx, gy; returns the range shift applied to them.
int LoadProblem(const GradientImages &in, PoissonProblem &P) {
    P.W = in.width;
    P.H = in.height;
    P.C = in.channels;
    P.N = size_t(P.W) * P.H;
    ToPlanar(in, in.primal, "primal", 0, 0, false, P.p);
    if (!in.separated.empty()) {  // the solve's primal: primal - separated (header comment)
        std::vector<float> s;
        ToPlanar(in, in.separated, "separated", 0, 0, false, s);
        // In double, clamped: primal and separated near the float limit with
        // opposite signs would otherwise make +-inf (then NaN in the solvers).
        const double big = std::numeric_limits<float>::max();
        for (size_t i = 0; i < s.size(); ++i)
            if (s[i] != 0) P.p[i] = float(std::clamp(double(P.p[i]) - double(s[i]), -big, big));
    }
    ToPlanar(in, in.dx, "dx", 1, 0, false, P.gx);
    ToPlanar(in, in.dy, "dy", 0, 1, false, P.gy);
    // Range safety: inputs near the float limit (up to FLT_MAX after the film's
    // output clamp) would overflow squares and dot products in the float
    // solvers. Such inputs are scaled by a power of two (exact, so the
    // solution scales back exactly for L2) to a maximum in [0.5, 1); inputs
    // below 2^50 are untouched.
    float maxAbs = 0;
    for (const std::vector<float> *v : {&P.p, &P.gx, &P.gy})
        for (float f : *v) maxAbs = std::max(maxAbs, std::abs(f));
    const int rangeShift = maxAbs > 0x1p50f ? std::ilogb(maxAbs) + 1 : 0;
    if (rangeShift)
        for (std::vector<float> *v : {&P.p, &P.gx, &P.gy})
            for (float &f : *v) f = std::ldexp(f, -rangeShift);
    return rangeShift;
}

recon::CGPrecond ToCGPrecond(Preconditioner p) {
    return p == Preconditioner::Jacobi      ? recon::CGPrecond::Jacobi
           : p == Preconditioner::Multigrid ? recon::CGPrecond::Multigrid
                                            : recon::CGPrecond::None;
}

void SolveL2(PoissonProblem &P, const ReconstructionOptions &opt, recon::CGPrecond pc, std::vector<float> &x,
             ReconstructionStats &st) {
    if (opt.l2Method == L2Method::Exact) {
        st.method = "l2-exact-dct";
        recon::SolveL2Exact(P, x.data());
        return;
    }
    st.method = pc == recon::CGPrecond::Jacobi ? "l2-pcg-jacobi" : pc == recon::CGPrecond::Multigrid ? "l2-pcg-multigrid" : "l2-cg";
    P.setUnitWeights();
    x = P.p;
    recon::CGReport rep = recon::SolveCG(P, x.data(), opt.cgIterations, opt.cgTolerance, pc);
    st.cgIterations = rep.iterations;
    st.finalRelativeResidual = rep.relResidual;
}

void SolveL1(PoissonProblem &P, const ReconstructionOptions &opt, recon::CGPrecond pc, std::vector<float> &x,
             ReconstructionStats &st) {
    st.method = "l1-irls";
    P.setUnitWeights();
    // IRLS iteration 0: the L2 solution (exact, or CG from the primal).
    if (opt.initFromL2) {
        recon::SolveL2Exact(P, x.data());
    } else {
        x = P.p;
        recon::CGReport rep = recon::SolveCG(P, x.data(), opt.cgIterations, opt.cgTolerance, pc);
        st.cgIterations += rep.iterations;
        st.finalRelativeResidual = rep.relResidual;
    }
    st.irlsIterations = 1;
    recon::CGWorkspace ws;
    for (int k = 1; k < opt.irlsIterations; ++k) {
        // With a range shift the regularisation applies in the normalised
        // range (in the input's units it would underflow the float weights).
        double reg = opt.irlsRegInit * std::pow(opt.irlsRegFactor, k - 1);
        recon::IrlsWeights(P, x.data(), float(opt.alpha), float(reg));
        recon::CGReport rep = recon::SolveCG(P, x.data(), opt.cgIterations, opt.cgTolerance, pc, &ws);
        st.cgIterations += rep.iterations;
        st.finalRelativeResidual = rep.relResidual;
        ++st.irlsIterations;
    }
}

// Sets P.wp, P.wx, P.wy to the inverse variances of `in` (range-shifted like P).
void LoadVarianceWeights(const GradientImages &in, int rangeShift, PoissonProblem &P) {
    std::vector<float> vp, vx, vy;
    ToPlanar(in, in.primalVar, "primal_var", 0, 0, true, vp);
    ToPlanar(in, in.dxVar, "dx_var", 1, 0, true, vx);
    ToPlanar(in, in.dyVar, "dy_var", 0, 1, true, vy);
    if (rangeShift)  // variances scale with the square
        for (std::vector<float> *v : {&vp, &vx, &vy})
            for (float &f : *v) f = std::ldexp(f, -2 * rangeShift);
    double mp, mx, my;
    InverseVarianceWeights(P, vp, false, false, P.wp, &mp);
    InverseVarianceWeights(P, vx, true, false, P.wx, &mx);
    InverseVarianceWeights(P, vy, false, true, P.wy, &my);
}

void SolveWeighted(const GradientImages &in, int rangeShift, PoissonProblem &P, const ReconstructionOptions &opt,
                   recon::CGPrecond pc, std::vector<float> &x, ReconstructionStats &st) {
    st.method = "weighted-pcg";
    LoadVarianceWeights(in, rangeShift, P);
    // Start from the unweighted L2 solution whose alpha^2 is the ratio of
    // mean primal to mean gradient weight (cheap and usually close).
    double sp = 0, sg = 0;
    size_t ng = 0;
    for (size_t i = 0; i < P.N; ++i) {
        sp += P.wp[i];
        if (P.wx[i] > 0) sg += P.wx[i], ++ng;
        if (P.wy[i] > 0) sg += P.wy[i], ++ng;
    }
    P.a2 = ng > 0 && sg > 0 ? float((sp / P.N) / (sg / ng)) : 1.f;
    recon::SolveL2Exact(P, x.data());
    // Normalise the weights to a mean of about one (scale-free solution).
    const double s = ng > 0 && sg > 0 ? double(ng) / sg : 1.0;
    for (size_t i = 0; i < P.N; ++i) {
        P.wp[i] = float(P.wp[i] * s);
        P.wx[i] = float(P.wx[i] * s);
        P.wy[i] = float(P.wy[i] * s);
    }
    P.a2 = 1.f;
    recon::CGReport rep = recon::SolveCG(P, x.data(), opt.cgIterations, opt.cgTolerance, pc);
    st.cgIterations = rep.iterations;
    st.finalRelativeResidual = rep.relResidual;
}

// The residuals of x and the objective its norm minimises (range-shifted units).
void SetEnergies(const PoissonProblem &P, const std::vector<float> &x, const ReconstructionOptions &opt,
                 ReconstructionStats &st) {
    const double alpha = opt.alpha;
    recon::Energies e = recon::ComputeEnergies(P, x.data());
    st.primalL2 = e.primalL2;
    st.gradientL2 = e.gradientL2;
    st.primalL1 = e.primalL1;
    st.gradientL1 = e.gradientL1;
    if (opt.norm == ReconstructionNorm::Weighted) st.objective = e.weightedL2;
    else if (std::isinf(alpha)) st.objective = 0;
    else if (opt.norm == ReconstructionNorm::L2) st.objective = alpha * alpha * e.primalL2 + e.gradientL2;
    else st.objective = alpha * e.primalL1 + e.gradientL1;
}

// Interleaves x and undoes the range shift on it and on the statistics.
ReconstructionResult MakeResult(const PoissonProblem &P, const std::vector<float> &x, int rangeShift,
                                const ReconstructionOptions &opt, ReconstructionStats &st) {
    ReconstructionResult res;
    res.width = P.W;
    res.height = P.H;
    res.channels = P.C;
    res.image = ToInterleaved(x, P.C, P.N);
    if (rangeShift) {
        const float big = std::numeric_limits<float>::max();
        for (float &f : res.image) f = std::clamp(float(std::ldexp(double(f), rangeShift)), -big, big);
        const double s = std::ldexp(1.0, rangeShift);
        st.primalL2 *= s * s, st.gradientL2 *= s * s, st.primalL1 *= s, st.gradientL1 *= s;
        st.objective *= opt.norm == ReconstructionNorm::L1 ? s : s * s;
    }
    return res;
}

}  // namespace

ReconstructionResult Reconstruct(const GradientImages &in, const ReconstructionOptions &opt) {
    if (opt.norm == ReconstructionNorm::Hybrid) return ReconstructHybrid(in, opt);
    const auto t0 = std::chrono::steady_clock::now();
    CheckSizeAndOptions(in, opt);
    PoissonProblem P;
    const int rangeShift = LoadProblem(in, P);
    const bool weighted = opt.norm == ReconstructionNorm::Weighted;
    if (weighted && !in.hasVariance())
        throw Error("reconstruction: the weighted norm needs variance layers primal_var, dx_var "
                    "and dy_var");

    ReconstructionStats st;
    std::vector<float> x(P.p.size());
    P.a2 = float(opt.alpha * opt.alpha);
    const recon::CGPrecond pc = ToCGPrecond(opt.preconditioner);
    if (std::isinf(opt.alpha) && !weighted) {
        st.method = "primal (alpha = inf)";
        x = P.p;
        P.a2 = 1.f;
    } else if (opt.norm == ReconstructionNorm::L2) {
        SolveL2(P, opt, pc, x, st);
    } else if (opt.norm == ReconstructionNorm::L1) {
        SolveL1(P, opt, pc, x, st);
    } else {
        SolveWeighted(in, rangeShift, P, opt, pc, x, st);
    }
    SetEnergies(P, x, opt, st);
    ReconstructionResult res = MakeResult(P, x, rangeShift, opt, st);
    if (!in.separated.empty()) {  // checked by LoadProblem: same size, finite
        const float big = std::numeric_limits<float>::max();
        for (size_t i = 0; i < res.image.size(); ++i)
            if (in.separated[i] != 0) res.image[i] = std::clamp(res.image[i] + in.separated[i], -big, big);
    }
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    res.stats = st;
    return res;
}

}  // namespace gradus
