// Internal: exact screened-Poisson solve by the discrete cosine transform.
//
// With gradients on interior edges only, A0 = a2*I + Dx^T Dx + Dy^T Dy is the
// Neumann Laplacian plus a2, diagonalised by the 2-D DCT-II (FFTW REDFT10,
// inverse REDFT01) with eigenvalues
//   a2 + 4 sin^2(pi k / 2W) + 4 sin^2(pi l / 2H)
// (the discrete form of G-MLT Eq. 19).
#pragma once
#include "reconstruction/poisson_ops.h"

namespace gradus {
namespace recon {

// x = p + A0^-1 (b - A0 p) for P's data (P's weights are ignored: unit weights
// are used). Solving for the correction to the primal keeps float rounding
// proportional to the gradient mismatch. a2 = 0 keeps the mean of p;
// a2 = inf returns p.
void SolveL2Exact(const PoissonProblem &P, float *x);

}  // namespace recon
}  // namespace gradus
