// Internal: the weighted screened-Poisson operator on planar float images
// (channel c of pixel i at c*N + i, i = y*W + x) and its TBB kernels.
//
// Normal equations of  sum_i a2*wp_i*|x_i - p_i|^2 + sum_e w_e*|(D x)_e - g_e|^2:
//   A x = b,  A = a2*Wp + Dx^T Wx Dx + Dy^T Wy Dy,  b = a2*Wp p + Dx^T Wx gx + Dy^T Wy gy,
// with (Dx x)_i = x_{i+1} - x_i on interior edges only (wx = 0 on the last column,
// wy = 0 on the last row), so A carries the Neumann boundary of the DCT-II.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

namespace gradus {
namespace recon {

constexpr int kMaxChannels = 8;
using ChannelSums = std::array<double, kMaxChannels>;

struct PoissonProblem {
    int W = 0, H = 0, C = 0;
    size_t N = 0;
    std::vector<float> p, gx, gy;  // planar, C*N (unused boundary entries are 0)
    float a2 = 0.04f;              // alpha^2: scale of the primal rows
    std::vector<float> wp, wx, wy; // per-term weights shared by channels, N each
    void setUnitWeights();         // wp = 1, wx/wy = 1 on interior edges, 0 on the boundary
};

// Row blocks for deterministic parallel loops (results independent of thread count).
template <class F> void ParallelRows(int H, const F &f);
// Deterministic parallel sum over rows: f(y0, y1, ChannelSums&) accumulates.
template <class F> ChannelSums ParallelRowSums(int H, const F &f);

// r = b - A x (computed from the term residuals, so exact inputs give r ~ 0);
// unitWeights (or empty weight arrays) uses weight 1 on every term.
void Residual(const PoissonProblem &P, const float *x, float *r, bool unitWeights = false);
// Ap = A p; returns per-channel p.Ap.
ChannelSums ApplyA(const PoissonProblem &P, const float *p, float *Ap);
// Inverse of diag(A), N entries.
void InverseDiagonal(const PoissonProblem &P, std::vector<float> &minv);

// IRLS weights of the colour-length (L1) objective at x (G-MLT Sec. 6, L1):
// wp = 1 / (alpha ||x_i - p_i|| + reg), wx = 1 / (||(Dx x)_i - gx_i|| + reg),
// wy likewise; 0 on the missing boundary edges.
void IrlsWeights(PoissonProblem &P, const float *x, float alpha, float reg);

struct Energies { double primalL2 = 0, gradientL2 = 0, primalL1 = 0, gradientL1 = 0, weightedL2 = 0; };
// Unweighted residual sums at x (and sum of a2*wp*|.|^2 + w*|.|^2 with P's weights).
Energies ComputeEnergies(const PoissonProblem &P, const float *x);

// Preconditioned CG on A x = b from the given x (per-channel step sizes, as
// independent CGs that share the operator). Stops after maxIter iterations or
// when ||r_c|| <= tol * ||r0_c|| for all channels.
struct CGReport { int iterations = 0; double relResidual = 0; };
enum class CGPrecond { None, Jacobi, Multigrid };
// Buffers SolveCG can reuse across calls (e.g. IRLS steps).
struct CGWorkspace { std::vector<float> r, d, Ad, minv; };
CGReport SolveCG(const PoissonProblem &P, float *x, int maxIter, double tol, CGPrecond precond,
                 CGWorkspace *ws = nullptr);

}  // namespace recon
}  // namespace gradus
