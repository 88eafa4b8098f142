// Internal: a symmetric multigrid V-cycle used as a CG preconditioner for the
// weighted screened-Poisson operator (IRLS steps of the L1 reconstruction).
//
// Coarsening aggregates 2x2 pixels with piecewise-constant prolongation P; the
// coarse operator is the Galerkin product P^T A P, which for this operator is
// again a weighted screened Laplacian: coarse screening = sum of the 4 fine
// screening coefficients, coarse edge weight = sum of the fine edge weights
// crossing between the two aggregates. Smoother: one damped-Jacobi step before
// and after the coarse correction (from zero), so the V-cycle is a symmetric
// positive-definite operator as CG requires.
#pragma once
#include <vector>

#include "reconstruction/poisson_ops.h"

namespace gradus {
namespace recon {

class MultigridPreconditioner {
  public:
    // Builds the hierarchy from P's operator (a2*wp screening, wx, wy weights).
    explicit MultigridPreconditioner(const PoissonProblem &P);
    // z = M^-1 r for all channels (planar, C*N).
    void apply(const float *r, float *z);
    int levels() const { return int(levels_.size()); }

  private:
    struct Level {
        int W = 0, H = 0;
        size_t N = 0;
        std::vector<float> s, wx, wy, minv;  // screening, edge weights, 1/diag
        std::vector<float> b, x, t;          // C*N work buffers
    };
    void vcycle(size_t l);
    int C_;
    std::vector<Level> levels_;
};

}  // namespace recon
}  // namespace gradus
