// Screened-Poisson reconstruction of gradient-domain renders.
//
// Every gradient-domain integrator outputs a noisy primal image p and noisy
// forward differences gx(x,y) ~ I(x+1,y) - I(x,y), gy(x,y) ~ I(x,y+1) - I(x,y)
// (the last column of gx and the last row of gy are unused). The final image
// minimises (G-MLT Eq. 16, with alpha weighting the primal residual as in the
// frequency-domain form G-MLT Eq. 19, i.e. alpha^2 in the normal equations):
//
//   E(I) = sum_pixels  || alpha (I - p) ||  +  sum_edges || D I - g ||
//
// where ||.|| is squared (L2) or the Euclidean length over colour channels
// (L1, solved by IRLS; channels share the IRLS weights). alpha -> infinity
// returns p; alpha = 0 keeps the mean of p and otherwise integrates g.
//
// Hybrid: the L1 solution at fine scales with the primal's coarse scales,
//   I = I_L1 + G_sigma * (p - I_L1),
// G_sigma a Gaussian of standard deviation sigma pixels (lowpassSigma, 8;
// half-sample symmetric borders, so G preserves the image sum and I's sum
// is p's). p is unbiased, so E[I] equals the true image at every scale
// coarser than sigma; I_L1 is not unbiased (it trades outliers, which at
// short render times carry much of the light, for bias: -14% of the mean on
// veach-ajar at 10 s). Gradient outliers do not reach I through p, so I is
// as robust to them as L1; a primal outlier is spread over G's support at
// 1/(2 pi sigma^2) of its size. Chosen by bench/reconstruction/RESULTS.md
// over the L2 solution as the coarse source and over sigma 2, 4, 16.
//
// Weighted: the variance-weighted least-squares reading of the image-space
// control-variate reconstruction (Rousselle, Jarosz, Novak 2016): each term
// is weighted by the inverse of its estimated variance,
//   E(I) = sum_i (I_i - p_i)^2 / v^p_i + sum_e ((D I)_e - g_e)^2 / v^g_e,
// with v the per-term variance averaged over the colour channels plus a floor
// of 1e-3 times that layer's mean variance (zero-variance terms stay finite).
// alpha is not used (the variances set the primal/gradient balance).
//
// Separated light: `separated` (optional) is the part of the primal that
// takes no gradients (gradient_film.h: paths reaching an emitter through
// Dirac scatterings only). Every norm solves for primal - separated (so the
// gradients' image and the primal term agree) and adds separated to its
// result; the hybrid's coarse scales come from the full primal, which gives
// the hybrid of the unseparated solve plus separated. Residuals and the
// objective are those of the solve.
#pragma once
#include <string>
#include <vector>

namespace gradus {

class Image;

// Input buffers, interleaved per pixel: v(x,y,c) = data[(y*width+x)*channels+c].
struct GradientImages {
    int width = 0, height = 0, channels = 3;
    std::vector<float> primal, dx, dy;
    // Optional: light in the primal that takes no gradients (empty: none).
    std::vector<float> separated;
    // Optional per-term variances (same layout); required by Norm::Weighted.
    std::vector<float> primalVar, dxVar, dyVar;
    bool hasVariance() const { return !primalVar.empty(); }
};

enum class ReconstructionNorm { L2, L1, Weighted, Hybrid };
// L2 solve: Exact = direct DCT-II diagonalisation (FFTW REDFT10/REDFT01,
// float); CG = preconditioned CG. Both start from / correct the primal.
enum class L2Method { Exact, CG };
// CG preconditioner: Jacobi (diagonal), or a symmetric multigrid V-cycle
// (2x2 aggregation, Galerkin coarse operators, damped-Jacobi smoothing): far
// fewer iterations on smooth weights (L2, weighted), less robust on the
// strongly varying IRLS weights of L1.
enum class Preconditioner { None, Jacobi, Multigrid };

struct ReconstructionOptions {
    ReconstructionNorm norm = ReconstructionNorm::L1;
    double alpha = 0.2;  // the papers' value; must be >= 0 (inf returns the primal)
    L2Method l2Method = L2Method::Exact;
    // CG iterations per solve (L2 CG, weighted, and each IRLS step), and a
    // relative residual tolerance (||r|| / ||r0|| per channel) that stops early.
    int cgIterations = 8;
    double cgTolerance = 0.0;
    Preconditioner preconditioner = Preconditioner::Jacobi;
    // IRLS (L1 only): iteration 0 is the L2 solve, each further iteration
    // reweights by 1 / (|e| + reg), reg = irlsRegInit * irlsRegFactor^(k-1).
    int irlsIterations = 18;
    double irlsRegInit = 0.05, irlsRegFactor = 0.5;
    // Start L1 from the exact L2 solution (true) or from the primal (false).
    bool initFromL2 = true;
    // Hybrid: the scale (Gaussian sigma, pixels) above which the primal's energy is kept.
    double lowpassSigma = 8;

    // Presets. L1Default is the default above: 18 IRLS x 8 Jacobi-PCG from the
    // exact L2 solution. Its L1 objective is below the reference schedule's on
    // the tests' inputs and at 1280x720 (bench_reconstruction: 793.669k in
    // 0.86 s against 793.889k in 4.6 s; the former 20 x 10 took 1.11 s for
    // 793.486k; 16 x 8 was faster but above the reference on a test input).
    // L1Reference reproduces the reference implementation's schedule (20 IRLS
    // x 50 plain CG from the primal) for comparisons. L2CG: multigrid PCG to
    // 1e-6; Weighted: multigrid PCG to 1e-5 from the L2 solution with alpha^2 =
    // mean primal weight / mean gradient weight.
    static ReconstructionOptions L1Default();
    static ReconstructionOptions L1Reference();
    static ReconstructionOptions L2Exact(double alpha = 0.2);
    static ReconstructionOptions L2CG(double alpha = 0.2);
    static ReconstructionOptions Weighted();
    // L1Default's IRLS with the primal's coarse scales (sigma 8 px).
    static ReconstructionOptions Hybrid(double alpha = 0.2);
    // By name: hybrid, l1, l1-reference, l2, l2-cg, weighted (else gradus::Error).
    static ReconstructionOptions Preset(const std::string &name);
};

struct ReconstructionStats {
    std::string method;      // e.g. "l2-exact", "l1-irls", "weighted-cg"
    double seconds = 0;      // wall-clock time of Reconstruct
    int irlsIterations = 18;  // IRLS iterations done (L1)
    int cgIterations = 0;    // total CG iterations
    // Residuals of the result, summed over pixels/edges and channels:
    double primalL2 = 0, gradientL2 = 0;  // sum (I-p)^2, sum (DI-g)^2
    double primalL1 = 0, gradientL1 = 0;  // sum ||I-p||, sum ||DI-g|| (colour length)
    // The minimised objective: L2 alpha^2*primalL2 + gradientL2; L1
    // alpha*primalL1 + gradientL1; Weighted its inverse-variance sum.
    double objective = 0;
    double finalRelativeResidual = 0;  // last CG solve: max_c ||r|| / ||r0|| (0 if exact)
};

struct ReconstructionResult {
    int width = 0, height = 0, channels = 0;
    std::vector<float> image;  // interleaved like GradientImages
    ReconstructionStats stats;
    float at(int x, int y, int c) const { return image[(size_t(y) * width + x) * channels + c]; }
};

// Solves the reconstruction. Throws gradus::Error on bad input (sizes, NaN/Inf
// values, negative variances, missing variances for Weighted, bad options).
ReconstructionResult Reconstruct(const GradientImages &in, const ReconstructionOptions &opt);

// Hybrid from two images of the same size: fine + G_sigma * (coarse - fine).
std::vector<float> CombineScales(const std::vector<float> &fine, const std::vector<float> &coarse, int width,
                                 int height, int channels, double sigma);

// Parses "l2" | "l1" | "weighted" | "hybrid" (throws gradus::Error otherwise).
ReconstructionNorm ParseReconstructionNorm(const std::string &name);
const char *ReconstructionNormName(ReconstructionNorm norm);

// ---- gradus::Image bridge (layers primal, dx, dy, optional separated, primal_var, dx_var, dy_var) ----

// Extracts RGB layers "primal", "dx", "dy", "separated" when present (images
// written before the separation have none: nothing is added) and variances
// when all three are present. Throws gradus::Error naming a missing layer.
GradientImages GradientImagesFromImage(const Image &img);
// Same, from three separate images (their unprefixed R,G,B or Y).
GradientImages GradientImagesFromImages(const Image &primal, const Image &dx, const Image &dy);
// Converts a result to an RGB image (channels R, G, B).
Image ResultToImage(const ReconstructionResult &r);
// One-call helper: reconstructs the primal/dx/dy layers of `img` as RGB.
Image ReconstructImage(const Image &img, const ReconstructionOptions &opt,
                       ReconstructionStats *stats = nullptr);
// For integrators: adds layers "reconstructed_l1" and "reconstructed_l2"
// (default presets with the given alpha) to a film holding primal/dx/dy.
void AddReconstructionLayers(Image &film, double alpha = 0.2);

}  // namespace gradus
