#include "reconstruction/poisson_ops.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/partitioner.h>

namespace gradus {
namespace recon {

namespace {
// Rows per task: fixed so that reductions are summed in the same order for any
// thread count.
int RowGrain(int H) { return std::max(1, std::min(16, H / 64 + 1)); }
}  // namespace

template <class F> void ParallelRows(int H, const F &f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, H, RowGrain(H)),
                      [&](const tbb::blocked_range<int> &r) { f(r.begin(), r.end()); },
                      tbb::simple_partitioner());
}

template <class F> ChannelSums ParallelRowSums(int H, const F &f) {
    ChannelSums zero{};
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<int>(0, H, RowGrain(H)), zero,
        [&](const tbb::blocked_range<int> &r, ChannelSums acc) {
            f(r.begin(), r.end(), acc);
            return acc;
        },
        [](ChannelSums a, const ChannelSums &b) {
            for (int c = 0; c < kMaxChannels; ++c) a[c] += b[c];
            return a;
        },
        tbb::simple_partitioner());
}

void PoissonProblem::setUnitWeights() {
    wp.assign(N, 1.f);
    wx.assign(N, 1.f);
    wy.assign(N, 1.f);
    for (int y = 0; y < H; ++y) wx[size_t(y) * W + W - 1] = 0.f;
    for (int x = 0; x < W; ++x) wy[size_t(H - 1) * W + x] = 0.f;
}

namespace {
template <bool Unit>
void ResidualImpl(const PoissonProblem &P, const float *x, float *r) {
    const int W = P.W, H = P.H;
    const size_t N = P.N;
    const float a2 = P.a2;
    // Unit weights: 1 on every term (boundary edges are skipped by the index tests).
    auto wp = [&](size_t i) { return Unit ? 1.f : P.wp[i]; };
    auto wx = [&](size_t i) { return Unit ? 1.f : P.wx[i]; };
    auto wy = [&](size_t i) { return Unit ? 1.f : P.wy[i]; };
    ParallelRows(H, [&](int y0, int y1) {
        for (int c = 0; c < P.C; ++c) {
            const float *xc = x + c * N, *pc = P.p.data() + c * N;
            const float *gxc = P.gx.data() + c * N, *gyc = P.gy.data() + c * N;
            float *rc = r + c * N;
            for (int y = y0; y < y1; ++y) {
                for (int xi = 0; xi < W; ++xi) {
                    size_t i = size_t(y) * W + xi;
                    // b - A x = a2 wp (p - x) + Dx^T Wx (gx - Dx x) + Dy^T Wy (gy - Dy x),
                    // (Dx^T e)_i = e_{i-1} - e_i.
                    float v = a2 * wp(i) * (pc[i] - xc[i]);
                    if (xi + 1 < W) v -= wx(i) * (gxc[i] - (xc[i + 1] - xc[i]));
                    if (xi > 0) v += wx(i - 1) * (gxc[i - 1] - (xc[i] - xc[i - 1]));
                    if (y + 1 < H) v -= wy(i) * (gyc[i] - (xc[i + W] - xc[i]));
                    if (y > 0) v += wy(i - W) * (gyc[i - W] - (xc[i] - xc[i - W]));
                    rc[i] = v;
                }
            }
        }
    });
}
}  // namespace

void Residual(const PoissonProblem &P, const float *x, float *r, bool unitWeights) {
    if (unitWeights || P.wp.empty()) ResidualImpl<true>(P, x, r);
    else ResidualImpl<false>(P, x, r);
}

ChannelSums ApplyA(const PoissonProblem &P, const float *p, float *Ap) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    const float a2 = P.a2;
    const float *wp = P.wp.data(), *wx = P.wx.data(), *wy = P.wy.data();
    return ParallelRowSums(H, [&](int y0, int y1, ChannelSums &acc) {
        for (int c = 0; c < C; ++c) {
            const float *pc = p + c * N;
            float *out = Ap + c * N;
            double sum = 0;
            for (int y = y0; y < y1; ++y) {
                const size_t row = size_t(y) * W;
                const bool up = y > 0, down = y + 1 < H;
                float rowSum = 0;
                for (int xi = 0; xi < W; ++xi) {
                    const size_t i = row + xi;
                    const float pi = pc[i];
                    float v = a2 * wp[i] * pi;
                    if (xi + 1 < W) v += wx[i] * (pi - pc[i + 1]);
                    if (xi > 0) v += wx[i - 1] * (pi - pc[i - 1]);
                    if (down) v += wy[i] * (pi - pc[i + W]);
                    if (up) v += wy[i - W] * (pi - pc[i - W]);
                    out[i] = v;
                    rowSum += v * pi;
                }
                sum += rowSum;
            }
            acc[c] += sum;
        }
    });
}

void InverseDiagonal(const PoissonProblem &P, std::vector<float> &minv) {
    const int W = P.W, H = P.H;
    minv.resize(P.N);
    ParallelRows(H, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int xi = 0; xi < W; ++xi) {
                size_t i = size_t(y) * W + xi;
                float d = P.a2 * P.wp[i] + P.wx[i] + P.wy[i];
                if (xi > 0) d += P.wx[i - 1];
                if (y > 0) d += P.wy[i - W];
                minv[i] = d > 0 ? 1.f / d : 0.f;
            }
    });
}

void TermResidualLengths(const PoissonProblem &P, const float *x, float *ep, float *ex,
                         float *ey) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    ParallelRows(H, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int xi = 0; xi < W; ++xi) {
                size_t i = size_t(y) * W + xi;
                float sp = 0, sx = 0, sy = 0;
                for (int c = 0; c < C; ++c) {
                    const float *xc = x + c * N;
                    float d = xc[i] - P.p[c * N + i];
                    sp += d * d;
                    if (xi + 1 < W) {
                        float e = (xc[i + 1] - xc[i]) - P.gx[c * N + i];
                        sx += e * e;
                    }
                    if (y + 1 < H) {
                        float e = (xc[i + W] - xc[i]) - P.gy[c * N + i];
                        sy += e * e;
                    }
                }
                ep[i] = std::sqrt(sp);
                ex[i] = std::sqrt(sx);
                ey[i] = std::sqrt(sy);
            }
    });
}

Energies ComputeEnergies(const PoissonProblem &P, const float *x) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    // Slots: 0 primalL2, 1 gradientL2, 2 primalL1, 3 gradientL1, 4 weighted.
    ChannelSums s = ParallelRowSums(H, [&](int y0, int y1, ChannelSums &acc) {
        for (int y = y0; y < y1; ++y)
            for (int xi = 0; xi < W; ++xi) {
                size_t i = size_t(y) * W + xi;
                double sp = 0, sx = 0, sy = 0;
                for (int c = 0; c < C; ++c) {
                    const float *xc = x + c * N;
                    double d = double(xc[i]) - P.p[c * N + i];
                    sp += d * d;
                    if (xi + 1 < W) {
                        double e = (double(xc[i + 1]) - xc[i]) - P.gx[c * N + i];
                        sx += e * e;
                    }
                    if (y + 1 < H) {
                        double e = (double(xc[i + W]) - xc[i]) - P.gy[c * N + i];
                        sy += e * e;
                    }
                }
                acc[0] += sp;
                acc[1] += sx + sy;
                acc[2] += std::sqrt(sp);
                acc[3] += std::sqrt(sx) + std::sqrt(sy);
                const bool unit = P.wp.empty();
                acc[4] += double(P.a2) * (unit ? 1.f : P.wp[i]) * sp + (unit ? 1.f : P.wx[i]) * sx +
                          (unit ? 1.f : P.wy[i]) * sy;
            }
    });
    Energies e;
    e.primalL2 = s[0];
    e.gradientL2 = s[1];
    e.primalL1 = s[2];
    e.gradientL1 = s[3];
    e.weightedL2 = s[4];
    return e;
}

// Per-channel r.r
static ChannelSums ResidualNorms(const PoissonProblem &P, const float *r) {
    const size_t N = P.N;
    const int W = P.W;
    return ParallelRowSums(P.H, [&](int y0, int y1, ChannelSums &acc) {
        for (int c = 0; c < P.C; ++c) {
            double b = 0;
            const float *rc = r + c * N;
            for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) b += double(rc[i]) * rc[i];
            acc[c] += b;
        }
    });
}

CGReport SolveCG(const PoissonProblem &P, float *x, int maxIter, double tol, bool jacobi) {
    const int C = P.C, H = P.H;
    const size_t N = P.N, CN = size_t(C) * N;
    const int W = P.W;
    std::vector<float> r(CN), d(CN), Ad(CN), minv;
    if (jacobi) InverseDiagonal(P, minv);
    else minv.assign(N, 1.f);
    const float *mi = minv.data();

    Residual(P, x, r.data());
    // d = M^-1 r; rz = r.M^-1 r; rr0 = r.r
    const ChannelSums rz0 = ParallelRowSums(H, [&](int y0, int y1, ChannelSums &acc) {
        for (int c = 0; c < C; ++c) {
            double a = 0;
            for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) {
                float rv = r[c * N + i], z = mi[i] * rv;
                d[c * N + i] = z;
                a += double(rv) * z;
            }
            acc[c] += a;
        }
    });
    ChannelSums rz = rz0;
    const ChannelSums rr0 = ResidualNorms(P, r.data());
    CGReport rep;
    auto relRes = [&](const ChannelSums &rr) {
        double m = 0;
        for (int c = 0; c < C; ++c)
            if (rr0[c] > 0) m = std::max(m, std::sqrt(rr[c] / rr0[c]));
        return m;
    };
    ChannelSums rr = rr0;
    bool active[kMaxChannels];
    for (int c = 0; c < C; ++c) active[c] = rr0[c] > 0 && rz[c] > 0;
    for (int it = 0; it < maxIter; ++it) {
        bool any = false;
        for (int c = 0; c < C; ++c) any |= active[c];
        if (!any) break;
        if (tol > 0 && relRes(rr) <= tol) break;
        ChannelSums dAd = ApplyA(P, d.data(), Ad.data());
        double step[kMaxChannels];
        for (int c = 0; c < C; ++c) {
            if (active[c] && !(dAd[c] > 0)) active[c] = false;  // converged to rounding
            step[c] = active[c] ? rz[c] / dAd[c] : 0.0;
        }
        // x += step d; r -= step Ad; new rz = r.M^-1 r
        ChannelSums rzNew = ParallelRowSums(H, [&](int y0, int y1, ChannelSums &acc) {
            for (int c = 0; c < C; ++c) {
                if (!active[c]) continue;
                const float s = float(step[c]);
                float *xc = x + c * N, *rc = r.data() + c * N;
                const float *dc = d.data() + c * N, *adc = Ad.data() + c * N;
                double a = 0;
                for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) {
                    xc[i] += s * dc[i];
                    float rv = rc[i] - s * adc[i];
                    rc[i] = rv;
                    a += double(rv) * mi[i] * rv;
                }
                acc[c] += a;
            }
        });
        if (tol > 0 || it + 1 == maxIter)
            rr = ResidualNorms(P, r.data());
        ++rep.iterations;
        if (it + 1 == maxIter) break;
        double beta[kMaxChannels];
        for (int c = 0; c < C; ++c) {
            beta[c] = active[c] ? rzNew[c] / rz[c] : 0.0;
            if (active[c] && !(rzNew[c] > 0)) active[c] = false;
            rz[c] = rzNew[c];
        }
        ParallelRows(H, [&](int y0, int y1) {
            for (int c = 0; c < C; ++c) {
                if (!active[c]) continue;
                const float b = float(beta[c]);
                float *dc = d.data() + c * N;
                const float *rc = r.data() + c * N;
                for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) dc[i] = mi[i] * rc[i] + b * dc[i];
            }
        });
    }
    rep.relResidual = relRes(rr);
    return rep;
}

}  // namespace recon
}  // namespace gradus
