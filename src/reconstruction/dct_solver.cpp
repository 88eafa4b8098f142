#include "reconstruction/dct_solver.h"

#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include <fftw3.h>
#include <tbb/parallel_for.h>

namespace gradus {
namespace recon {

namespace {

struct FloatBuffer {
    float *data = nullptr;
    explicit FloatBuffer(size_t n) : data(fftwf_alloc_real(n)) {}
    ~FloatBuffer() { fftwf_free(data); }
    FloatBuffer(const FloatBuffer &) = delete;
    FloatBuffer &operator=(const FloatBuffer &) = delete;
};

// In-place 2-D DCT-II / DCT-III plans for one size, created once and reused
// (execution with fftwf_execute_r2r on other fftwf_alloc'd buffers is thread-safe).
struct DctPlans {
    fftwf_plan forward = nullptr, inverse = nullptr;
};

std::mutex gPlanMutex;  // the FFTW planner is not thread-safe

DctPlans GetPlans(int W, int H) {
    // Never destroyed: the plans live as long as the process (no leak at exit).
    static auto &cache = *new std::map<std::pair<int, int>, DctPlans>;
    std::lock_guard<std::mutex> lock(gPlanMutex);
    auto it = cache.find({W, H});
    if (it != cache.end()) return it->second;
    FloatBuffer buf(size_t(W) * H);
    DctPlans plans;
    // Row-major H x W: the last dimension (x) is contiguous.
    plans.forward = fftwf_plan_r2r_2d(H, W, buf.data, buf.data, FFTW_REDFT10, FFTW_REDFT10,
                                      FFTW_ESTIMATE);
    plans.inverse = fftwf_plan_r2r_2d(H, W, buf.data, buf.data, FFTW_REDFT01, FFTW_REDFT01,
                                      FFTW_ESTIMATE);
    cache[{W, H}] = plans;
    return plans;
}

}  // namespace

void SolveL2Exact(const PoissonProblem &P, float *x) {
    const int W = P.W, H = P.H, C = P.C;
    const size_t N = P.N;
    const float *p = P.p.data();
    if (std::isinf(P.a2)) {  // alpha -> infinity: the primal term dominates
        std::copy(p, p + size_t(C) * N, x);
        return;
    }
    // Residual b - A0 p with unit weights.
    std::vector<float> r(size_t(C) * N);
    Residual(P, p, r.data(), /*unitWeights=*/true);
    // Eigenvalues of the two 1-D Neumann Laplacians.
    std::vector<double> lx(W), ly(H);
    for (int k = 0; k < W; ++k) {
        double s = std::sin(M_PI * k / (2.0 * W));
        lx[k] = 4 * s * s;
    }
    for (int l = 0; l < H; ++l) {
        double s = std::sin(M_PI * l / (2.0 * H));
        ly[l] = 4 * s * s;
    }
    const DctPlans plans = GetPlans(W, H);
    // FFTW's REDFT10 followed by REDFT01 multiplies by 2W * 2H.
    const double norm = 1.0 / (4.0 * double(W) * double(H));
    const double a2 = P.a2;
    tbb::parallel_for(0, C, [&](int c) {
        FloatBuffer buf(N);
        std::copy(r.begin() + c * N, r.begin() + (c + 1) * N, buf.data);
        fftwf_execute_r2r(plans.forward, buf.data, buf.data);
        for (int l = 0; l < H; ++l)
            for (int k = 0; k < W; ++k) {
                double denom = a2 + lx[k] + ly[l];
                // a2 = 0: the constant mode is free; keep the primal's mean.
                size_t i = size_t(l) * W + k;
                buf.data[i] = denom > 0 ? float(buf.data[i] * (norm / denom)) : 0.f;
            }
        fftwf_execute_r2r(plans.inverse, buf.data, buf.data);
        const float *pc = p + c * N;
        float *xc = x + c * N;
        for (size_t i = 0; i < N; ++i) xc[i] = pc[i] + buf.data[i];
    });
}

}  // namespace recon
}  // namespace gradus
