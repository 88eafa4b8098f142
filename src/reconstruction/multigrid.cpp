#include "reconstruction/multigrid.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace gradus {
namespace recon {

namespace {

constexpr float kOmega = 0.8f;  // damped Jacobi; < 2 / lambda_max(D^-1 A) since lambda_max <= 2

template <class F> void Rows(int H, int W, const F &f) {
    const int grain = std::max(1, 16384 / std::max(1, W));
    tbb::parallel_for(tbb::blocked_range<int>(0, H, grain),
                      [&](const tbb::blocked_range<int> &r) { f(r.begin(), r.end()); });
}

// out = A x on row y of one channel plane.
template <class L>
inline void StencilRow(const L &lv, const float *__restrict x, int y, float *__restrict out) {
    const int W = lv.W, H = lv.H;
    const size_t row = size_t(y) * W;
    const float *__restrict xr = x + row;
    const float *__restrict xu = y > 0 ? xr - W : xr;
    const float *__restrict xd = y + 1 < H ? xr + W : xr;
    const float *__restrict s = lv.s.data() + row;
    const float *__restrict wx = lv.wx.data() + row;
    const float *__restrict wy = lv.wy.data() + row;
    const float *__restrict wyu = y > 0 ? wy - W : wy;
    for (int i = 0; i < W; ++i) out[i] = s[i] * xr[i] + wy[i] * (xr[i] - xd[i]) + wyu[i] * (xr[i] - xu[i]);
    for (int i = 0; i + 1 < W; ++i) {
        const float f = wx[i] * (xr[i] - xr[i + 1]);
        out[i] += f;
        out[i + 1] -= f;
    }
}

}  // namespace

MultigridPreconditioner::MultigridPreconditioner(const PoissonProblem &P) : C_(P.C) {
    Level l0;
    l0.W = P.W;
    l0.H = P.H;
    l0.N = P.N;
    l0.s.resize(P.N);
    for (size_t i = 0; i < P.N; ++i) l0.s[i] = P.a2 * P.wp[i];
    l0.wx = P.wx;
    l0.wy = P.wy;
    levels_.push_back(std::move(l0));
    // Coarsen until the level is tiny.
    while (levels_.back().N > 64) {
        const Level &f = levels_.back();
        Level c;
        c.W = (f.W + 1) / 2;
        c.H = (f.H + 1) / 2;
        c.N = size_t(c.W) * c.H;
        c.s.assign(c.N, 0.f);
        c.wx.assign(c.N, 0.f);
        c.wy.assign(c.N, 0.f);
        for (int y = 0; y < f.H; ++y)
            for (int x = 0; x < f.W; ++x) {
                const size_t i = size_t(y) * f.W + x, ci = size_t(y / 2) * c.W + x / 2;
                c.s[ci] += f.s[i];
                if (x % 2 == 1) c.wx[ci] += f.wx[i];  // edge (x, x+1) crosses aggregates
                if (y % 2 == 1) c.wy[ci] += f.wy[i];
            }
        levels_.push_back(std::move(c));
    }
    for (Level &l : levels_) {
        l.minv.resize(l.N);
        for (int y = 0; y < l.H; ++y)
            for (int x = 0; x < l.W; ++x) {
                const size_t i = size_t(y) * l.W + x;
                float d = l.s[i] + l.wx[i] + l.wy[i];
                if (x > 0) d += l.wx[i - 1];
                if (y > 0) d += l.wy[i - l.W];
                l.minv[i] = d > 0 ? 1.f / d : 0.f;
            }
        l.b.resize(size_t(C_) * l.N);
        l.x.resize(size_t(C_) * l.N);
        l.t.resize(size_t(C_) * l.N);
    }
}

void MultigridPreconditioner::apply(const float *r, float *z) {
    Level &l0 = levels_[0];
    std::copy(r, r + size_t(C_) * l0.N, l0.b.begin());
    vcycle(0);
    std::copy(l0.x.begin(), l0.x.end(), z);
}

void MultigridPreconditioner::vcycle(size_t li) {
    Level &L = levels_[li];
    const int W = L.W, C = C_;
    const size_t N = L.N;
    const bool coarsest = li + 1 == levels_.size();
    // Pre-smoothing from zero: x = omega D^-1 b.
    for (int c = 0; c < C; ++c)
        for (size_t i = 0; i < N; ++i) L.x[c * N + i] = kOmega * L.minv[i] * L.b[c * N + i];
    // Jacobi steps x += omega D^-1 (b - A x) into t, then swap.
    auto jacobi = [&]() {
        Rows(L.H, W, [&](int y0, int y1) {
            std::vector<float> ax(W);
            for (int c = 0; c < C; ++c)
                for (int y = y0; y < y1; ++y) {
                    StencilRow(L, L.x.data() + c * N, y, ax.data());
                    const size_t row = size_t(y) * W;
                    const float *__restrict b = L.b.data() + c * N + row, *__restrict x = L.x.data() + c * N + row;
                    const float *__restrict m = L.minv.data() + row;
                    float *__restrict t = L.t.data() + c * N + row;
                    for (int i = 0; i < W; ++i) t[i] = x[i] + kOmega * m[i] * (b[i] - ax[i]);
                }
        });
        std::swap(L.x, L.t);
    };
    if (coarsest) {
        // A fixed polynomial in D^-1 A: still symmetric positive definite.
        for (int k = 0; k < 16; ++k) jacobi();
        return;
    }
    Level &Lc = levels_[li + 1];
    const int Wc = Lc.W;
    const size_t Nc = Lc.N;
    // Residual t = b - A x, restricted by summing 2x2 aggregates into Lc.b.
    Rows(L.H, W, [&](int y0, int y1) {
        std::vector<float> ax(W);
        for (int c = 0; c < C; ++c)
            for (int y = y0; y < y1; ++y) {
                StencilRow(L, L.x.data() + c * N, y, ax.data());
                const size_t row = size_t(y) * W;
                for (int i = 0; i < W; ++i) L.t[c * N + row + i] = L.b[c * N + row + i] - ax[i];
            }
    });
    Rows(Lc.H, Wc, [&](int y0, int y1) {
        for (int c = 0; c < C; ++c)
            for (int yc = y0; yc < y1; ++yc)
                for (int xc = 0; xc < Wc; ++xc) {
                    float s = 0;
                    for (int dy = 0; dy < 2; ++dy)
                        for (int dx = 0; dx < 2; ++dx) {
                            const int x = 2 * xc + dx, y = 2 * yc + dy;
                            if (x < W && y < L.H) s += L.t[c * N + size_t(y) * W + x];
                        }
                    Lc.b[c * Nc + size_t(yc) * Wc + xc] = s;
                }
    });
    vcycle(li + 1);
    // Prolongation: x += P x_c.
    Rows(L.H, W, [&](int y0, int y1) {
        for (int c = 0; c < C; ++c)
            for (int y = y0; y < y1; ++y) {
                const float *xc = Lc.x.data() + c * Nc + size_t(y / 2) * Wc;
                float *x = L.x.data() + c * N + size_t(y) * W;
                for (int i = 0; i < W; ++i) x[i] += xc[i / 2];
            }
    });
    jacobi();  // post-smoothing (adjoint of the pre-smoothing step)
}

}  // namespace recon
}  // namespace gradus
