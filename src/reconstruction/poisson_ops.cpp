#include "reconstruction/poisson_ops.h"

#include "reconstruction/multigrid.h"

#include <algorithm>
#include <cmath>
#include <memory>

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

void Residual(const PoissonProblem &P, const float *x, float *r, bool unitWeights) {
    const int W = P.W, H = P.H;
    const size_t N = P.N;
    const float a2 = P.a2;
    const bool unit = unitWeights || P.wp.empty();
    // Unit weights as rows (0 on the missing last-column edge); a zero row
    // stands for the missing edges above the first and below the last row.
    std::vector<float> ones(W, 1.f), onesX(W, 1.f), zeros(W, 0.f);
    onesX[W - 1] = 0.f;
    ParallelRows(H, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const size_t row = size_t(y) * W;
            const bool up = y > 0, down = y + 1 < H;
            const float *__restrict wpr = unit ? ones.data() : P.wp.data() + row;
            const float *__restrict wxr = unit ? onesX.data() : P.wx.data() + row;
            const float *__restrict wyr = !down ? zeros.data() : unit ? ones.data() : P.wy.data() + row;
            const float *__restrict wyu = !up ? zeros.data() : unit ? ones.data() : P.wy.data() + row - W;
            for (int c = 0; c < P.C; ++c) {
                const float *__restrict xr = x + c * N + row;
                const float *__restrict xu = up ? xr - W : xr;
                const float *__restrict xd = down ? xr + W : xr;
                const float *__restrict pr = P.p.data() + c * N + row;
                const float *__restrict gxr = P.gx.data() + c * N + row;
                const float *__restrict gyr = down ? P.gy.data() + c * N + row : zeros.data();
                const float *__restrict gyu = up ? P.gy.data() + c * N + row - W : zeros.data();
                float *__restrict rr = r + c * N + row;
                // b - A x = a2 wp (p - x) + Dx^T Wx (gx - Dx x) + Dy^T Wy (gy - Dy x),
                // with (D^T e)_i = e_{i-1} - e_i.
                auto vert = [&](int i) {
                    return a2 * wpr[i] * (pr[i] - xr[i]) - wyr[i] * (gyr[i] - (xd[i] - xr[i])) +
                           wyu[i] * (gyu[i] - (xr[i] - xu[i]));
                };
                auto right = [&](int i) { return wxr[i] * (gxr[i] - (xr[i + 1] - xr[i])); };
                if (W == 1) {
                    rr[0] = vert(0);
                    continue;
                }
                rr[0] = vert(0) - right(0);
                rr[W - 1] = vert(W - 1) + right(W - 2);
#pragma omp simd
                for (int i = 1; i < W - 1; ++i) rr[i] = vert(i) - right(i) + right(i - 1);
            }
        }
    });
}

void IrlsWeights(PoissonProblem &P, const float *x, float alpha, float reg) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    ParallelRows(H, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int xi = 0; xi < W; ++xi) {
                const size_t i = size_t(y) * W + xi;
                float sp = 0, sx = 0, sy = 0;
                for (int c = 0; c < C; ++c) {
                    const float *xc = x + c * N;
                    const float d = xc[i] - P.p[c * N + i];
                    sp += d * d;
                    if (xi + 1 < W) {
                        const float e = (xc[i + 1] - xc[i]) - P.gx[c * N + i];
                        sx += e * e;
                    }
                    if (y + 1 < H) {
                        const float e = (xc[i + W] - xc[i]) - P.gy[c * N + i];
                        sy += e * e;
                    }
                }
                // The primal row's residual is alpha (x - p).
                P.wp[i] = 1.f / (alpha * std::sqrt(sp) + reg);
                P.wx[i] = xi + 1 < W ? 1.f / (std::sqrt(sx) + reg) : 0.f;
                P.wy[i] = y + 1 < H ? 1.f / (std::sqrt(sy) + reg) : 0.f;
            }
    });
}

ChannelSums ApplyA(const PoissonProblem &P, const float *p, float *Ap) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    const float a2 = P.a2;
    return ParallelRowSums(H, [&](int y0, int y1, ChannelSums &acc) {
        for (int y = y0; y < y1; ++y) {
            const size_t row = size_t(y) * W;
            const float *__restrict wpr = P.wp.data() + row;
            const float *__restrict wxr = P.wx.data() + row;
            const float *__restrict wyr = P.wy.data() + row;
            // Missing neighbours point at the row itself: their difference is 0.
            const float *__restrict wyu = y > 0 ? wyr - W : wyr;
            for (int c = 0; c < C; ++c) {
                const float *__restrict pr = p + c * N + row;
                const float *__restrict pu = y > 0 ? pr - W : pr;
                const float *__restrict pd = y + 1 < H ? pr + W : pr;
                float *__restrict out = Ap + c * N + row;
                auto vert = [&](int x) {
                    const float pi = pr[x];
                    return a2 * wpr[x] * pi + wyr[x] * (pi - pd[x]) + wyu[x] * (pi - pu[x]);
                };
                float s = 0;
                if (W == 1) {
                    out[0] = vert(0);
                    s = out[0] * pr[0];
                } else {
                    out[0] = vert(0) + wxr[0] * (pr[0] - pr[1]);
                    out[W - 1] = vert(W - 1) + wxr[W - 2] * (pr[W - 1] - pr[W - 2]);
                    s = out[0] * pr[0] + out[W - 1] * pr[W - 1];
                }
#pragma omp simd reduction(+ : s)
                for (int x = 1; x < W - 1; ++x) {
                    const float pi = pr[x];
                    const float v = a2 * wpr[x] * pi + wyr[x] * (pi - pd[x]) + wyu[x] * (pi - pu[x]) +
                                    wxr[x] * (pi - pr[x + 1]) + wxr[x - 1] * (pi - pr[x - 1]);
                    out[x] = v;
                    s += v * pi;
                }
                acc[c] += s;
            }
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
        for (int y = y0; y < y1; ++y)
            for (int c = 0; c < P.C; ++c) {
                const float *__restrict rc = r + c * N + size_t(y) * W;
                float b = 0;
#pragma omp simd reduction(+ : b)
                for (int x = 0; x < W; ++x) b += rc[x] * rc[x];
                acc[c] += b;
            }
    });
}

// Per-channel a.b
static ChannelSums Dot(const PoissonProblem &P, const float *a, const float *b) {
    const int C = P.C, W = P.W;
    const size_t N = P.N;
    return ParallelRowSums(P.H, [&](int y0, int y1, ChannelSums &acc) {
        for (int y = y0; y < y1; ++y)
            for (int c = 0; c < C; ++c) {
                const float *__restrict ac = a + c * N + size_t(y) * W;
                const float *__restrict bc = b + c * N + size_t(y) * W;
                float v = 0;
#pragma omp simd reduction(+ : v)
                for (int i = 0; i < W; ++i) v += ac[i] * bc[i];
                acc[c] += v;
            }
    });
}

// d = M^-1 r for the diagonal M^-1 mi; returns r.M^-1 r.
static ChannelSums DiagonalDirection(const PoissonProblem &P, const float *mi, const float *r, float *d) {
    const int C = P.C, W = P.W;
    const size_t N = P.N;
    return ParallelRowSums(P.H, [&](int y0, int y1, ChannelSums &acc) {
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
}

// On the active channels: x += step d; r -= step Ad. Returns the new r.M^-1 r
// for the diagonal M^-1 mi (zero when mi is null).
static ChannelSums StepSolution(const PoissonProblem &P, float *x, float *r, const float *d, const float *Ad,
                                const float *mi, const bool *active, const double *step) {
    const int C = P.C, W = P.W;
    const size_t N = P.N;
    return ParallelRowSums(P.H, [&](int y0, int y1, ChannelSums &acc) {
        for (int y = y0; y < y1; ++y) {
            const size_t row = size_t(y) * W;
            const float *__restrict m = mi ? mi + row : nullptr;
            for (int c = 0; c < C; ++c) {
                if (!active[c]) continue;
                const float s = float(step[c]);
                float *__restrict xc = x + c * N + row;
                float *__restrict rc = r + c * N + row;
                const float *__restrict dc = d + c * N + row;
                const float *__restrict adc = Ad + c * N + row;
                float a = 0;
                if (m) {
#pragma omp simd reduction(+ : a)
                    for (int i = 0; i < W; ++i) {
                        xc[i] += s * dc[i];
                        const float rv = rc[i] - s * adc[i];
                        rc[i] = rv;
                        a += rv * m[i] * rv;
                    }
                } else {
#pragma omp simd
                    for (int i = 0; i < W; ++i) {
                        xc[i] += s * dc[i];
                        rc[i] -= s * adc[i];
                    }
                }
                acc[c] += a;
            }
        }
    });
}

// On the active channels: d = z + beta d, z = M^-1 r given (multigrid) or
// mi r for the diagonal M^-1 mi (z null).
static void UpdateDirection(const PoissonProblem &P, float *d, const float *r, const float *z, const float *mi,
                            const bool *active, const double *beta) {
    const int C = P.C, W = P.W;
    const size_t N = P.N;
    ParallelRows(P.H, [&](int y0, int y1) {
        for (int c = 0; c < C; ++c) {
            if (!active[c]) continue;
            const float b = float(beta[c]);
            float *dc = d + c * N;
            const float *rc = r + c * N;
            if (z) {
                const float *zc = z + c * N;
                for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) dc[i] = zc[i] + b * dc[i];
            } else {
                for (size_t i = size_t(y0) * W; i < size_t(y1) * W; ++i) dc[i] = mi[i] * rc[i] + b * dc[i];
            }
        }
    });
}

// max_c ||r|| / ||r0|| from the squared norms.
static double RelativeResidual(const ChannelSums &rr, const ChannelSums &rr0, int C) {
    double m = 0;
    for (int c = 0; c < C; ++c)
        if (rr0[c] > 0) m = std::max(m, std::sqrt(rr[c] / rr0[c]));
    return m;
}

CGReport SolveCG(const PoissonProblem &P, float *x, int maxIter, double tol, CGPrecond precond,
                 CGWorkspace *ws) {
    const int C = P.C;
    const size_t N = P.N, CN = size_t(C) * N;
    CGWorkspace local;
    if (!ws) ws = &local;
    // Reused buffers (no fresh pages per IRLS step); every entry is overwritten.
    std::vector<float> &r = ws->r, &d = ws->d, &Ad = ws->Ad, &minv = ws->minv;
    r.resize(CN);
    d.resize(CN);
    Ad.resize(CN);
    if (precond == CGPrecond::Jacobi) InverseDiagonal(P, minv);
    else minv.assign(N, 1.f);
    const float *mi = minv.data();
    // Multigrid: z = M^-1 r kept in its own buffer (Jacobi/none fuse M^-1 = diag).
    std::unique_ptr<MultigridPreconditioner> mg;
    std::vector<float> z;

    Residual(P, x, r.data());
    if (maxIter > 0 && precond == CGPrecond::Multigrid) {
        mg = std::make_unique<MultigridPreconditioner>(P);
        z.resize(CN);
        mg->apply(r.data(), z.data());
        mi = nullptr;
    }
    // d = M^-1 r; rz = r.M^-1 r; rr0 = r.r
    const ChannelSums rz0 = mg ? (std::copy(z.begin(), z.end(), d.begin()), Dot(P, r.data(), z.data()))
                               : DiagonalDirection(P, mi, r.data(), d.data());
    ChannelSums rz = rz0;
    const ChannelSums rr0 = ResidualNorms(P, r.data());
    CGReport rep;
    ChannelSums rr = rr0;
    bool active[kMaxChannels];
    for (int c = 0; c < C; ++c) active[c] = rr0[c] > 0 && rz[c] > 0;
    for (int it = 0; it < maxIter; ++it) {
        bool any = false;
        for (int c = 0; c < C; ++c) any |= active[c];
        if (!any) break;
        if (tol > 0 && RelativeResidual(rr, rr0, C) <= tol) break;
        ChannelSums dAd = ApplyA(P, d.data(), Ad.data());
        double step[kMaxChannels];
        for (int c = 0; c < C; ++c) {
            if (active[c] && !(dAd[c] > 0)) active[c] = false;  // converged to rounding
            step[c] = active[c] ? rz[c] / dAd[c] : 0.0;
        }
        ChannelSums rzNew = StepSolution(P, x, r.data(), d.data(), Ad.data(), mi, active, step);
        if (tol > 0 || it + 1 == maxIter)
            rr = ResidualNorms(P, r.data());
        ++rep.iterations;
        if (it + 1 == maxIter) break;
        if (mg) {
            mg->apply(r.data(), z.data());
            rzNew = Dot(P, r.data(), z.data());
        }
        double beta[kMaxChannels];
        for (int c = 0; c < C; ++c) {
            beta[c] = active[c] ? rzNew[c] / rz[c] : 0.0;
            if (active[c] && !(rzNew[c] > 0)) active[c] = false;
            rz[c] = rzNew[c];
        }
        UpdateDirection(P, d.data(), r.data(), mg ? z.data() : nullptr, mi, active, beta);
    }
    rep.relResidual = RelativeResidual(rr, rr0, C);
    return rep;
}

}  // namespace recon
}  // namespace gradus
