// The running normalisation on a furnace whose mean is known in closed form
// (statistic and power check: normalization_util.h); gmlt's gradients and
// coarse primal scaled by the same b.
#include "normalization_util.h"

namespace gradus::mlt_test {
namespace {

// A closed cube around the camera whose every face emits Le (two-sided) and
// reflects diffusely with albedo rho: the radiance is the same everywhere and
// in every direction, L = Le sum_{k=0}^{D} rho^k at maxdepth D (each bounce
// adds the emission once more times rho). Grey, so the luminance is L.
constexpr double kLe = 0.5, kRho = 0.5;
constexpr int kDepth = 3;

std::string Furnace(const std::string &integratorLine, int res) {
    std::ostringstream s;
    s << integratorLine << "\nSampler \"random\" \"integer pixelsamples\" [4]\nPixelFilter \"box\"\n"
      << "Film \"image\" \"integer xresolution\" [" << res << "] \"integer yresolution\" [" << res
      << "] \"string filename\" [\"unused.exr\"]\n"
      << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [60]\nWorldBegin\nAttributeBegin\n"
      << "AreaLightSource \"diffuse\" \"rgb L\" [" << kLe << " " << kLe << " " << kLe << "] \"bool twosided\" [true]\n"
      << "Material \"matte\" \"rgb Kd\" [" << kRho << " " << kRho << " " << kRho << "]\n"
      << "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 6 5 4 7 6  0 4 5 0 5 1  1 5 6 1 6 2  2 6 7 2 7 3  "
         "3 7 4 3 4 0] \"point P\" [-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1]\n"
      << "AttributeEnd\nWorldEnd\n";
    return s.str();
}

double FurnaceMean() {
    double L = 0, w = kLe;
    for (int k = 0; k <= kDepth; ++k, w *= kRho) L += w;
    return L;
}

// A bootstrap far too small for its b alone to meet the statistic (spread of
// the bootstrap's b from seed to seed here: mlt 4.4%, pmlt 2-4%, gmlt ~15%; its
// image mean 1.4%), so that only a b refined by the render passes. mlt: 64 x 64 pixels, 16 mutations per pixel,
// ~20000 large steps; pmlt and gmlt: one independent sample per mutation.
const std::string kDepthParam = "\"integer maxdepth\" [" + std::to_string(kDepth) + "] ";

TEST(MetropolisNormalisation, FurnaceMeanMLT) {
    const std::string scene =
        Furnace("Integrator \"mlt\" " + kDepthParam + "\"integer bootstrapsamples\" [50] \"integer chains\" [256]", 64);
    ExpectConverges("mlt furnace", Ratios(scene, FurnaceMean(), 16, 501));
}

TEST(MetropolisNormalisation, FurnaceMeanPMLT) {
    const std::string scene = Furnace("Integrator \"pmlt\" " + kDepthParam +
                                          "\"integer bootstrapsamples\" [20] \"integer chains\" [256] "
                                          "\"float normalizationsamples\" [1]",
                                      32);
    ExpectConverges("pmlt furnace", Ratios(scene, FurnaceMean(), 16, 601));
}

// gmlt's coarse primal carries the chains' noise in its mean besides b's:
// (1/4) F / f with f = |f*| + alpha (1/4) I (Eq. 11) varies with the
// gradient's magnitude (at the default alpha 0.2 the image mean's sd here is
// ~4% at 16 mutations per pixel, b's ~0.8%). alpha 8 makes f ~ 2 I, so the
// image mean resolves b to the statistic's 1%.
TEST(MetropolisNormalisation, FurnaceMeanGMLT) {
    const std::string scene = Furnace("Integrator \"gmlt\" " + kDepthParam +
                                          "\"integer bootstrapsamples\" [200] \"integer chains\" [256] "
                                          "\"float normalizationsamples\" [1] \"float alpha\" [8]",
                                      32);
    ExpectConverges("gmlt furnace", Ratios(scene, FurnaceMean(), 16, 701));
}

}  // namespace
}  // namespace gradus::mlt_test
