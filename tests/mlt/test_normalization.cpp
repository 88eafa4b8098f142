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

// largestepmis: the chain's part scales with the running b, the large
// steps' part (their own film layer, added to the main image) does not.
TEST(MetropolisNormalisation, FurnaceMeanMLTLargeStepMIS) {
    const std::string scene = Furnace("Integrator \"mlt\" " + kDepthParam +
                                          "\"integer bootstrapsamples\" [50] \"integer chains\" [256] "
                                          "\"bool largestepmis\" [true]",
                                      64);
    ExpectConverges("mlt furnace, largestepmis", Ratios(scene, FurnaceMean(), 16, 551));
}

// normalizationsamples: every strategy of the chain's depth on one pair of
// subpaths per sample (mlt.h), pooled with the large steps.
TEST(MetropolisNormalisation, FurnaceMeanMLTAllStrategySamples) {
    const std::string scene = Furnace("Integrator \"mlt\" " + kDepthParam +
                                          "\"integer bootstrapsamples\" [20] \"integer chains\" [256] "
                                          "\"float normalizationsamples\" [1]",
                                      32);
    ExpectConverges("mlt furnace, normalizationsamples", Ratios(scene, FurnaceMean(), 16, 581));
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

// directsamples: the direct light (paths of at most one scattering vertex,
// Le + rho Le here) comes from the path tracer's filtered samples, which do
// not scale with b; the chains render the rest, scaled by the current b. A
// direct pass scaled by b (~0.3 of the image here), or chains without it, is
// far off the closed form.
TEST(MetropolisNormalisation, FurnaceMeanWithDirectSamples) {
    for (const char *integ : {"pmlt", "gmlt"}) {
        const std::string scene =
            Furnace("Integrator \"" + std::string(integ) + "\" " + kDepthParam +
                        "\"integer bootstrapsamples\" [20] \"integer chains\" [256] \"float normalizationsamples\" [1] "
                        "\"integer directsamples\" [4]" + (integ == std::string("gmlt") ? " \"float alpha\" [8]" : ""),
                    32);
        ExpectConverges(std::string(integ) + " furnace, directsamples 4", Ratios(scene, FurnaceMean(), 16, 801));
    }
}

// gmlt: the output's primal, dx and dy are the film's unnormalised splat
// sums times one and the same current b (not the bootstrap's; a stale b on
// the gradients would bend the reconstruction without moving its mean).
TEST(MetropolisNormalisation, GMLTGradientsAndPrimalCarryTheCurrentB) {
    BuildOptions bo;
    bo.sppOverride = 4;
    bo.seed = 5;
    bo.quiet = true;
    RenderJob job = BuildRenderJob(
        ParseString(BoxScene("Integrator \"gmlt\" \"integer maxdepth\" [3] \"integer bootstrapsamples\" [50] "
                             "\"integer chains\" [64] \"float normalizationsamples\" [1]",
                             16)),
        bo);
    RenderOptions ro;
    ro.spp = 4;
    ro.nthreads = 2;
    ro.quiet = true;
    const RenderResult res = RenderJobImage(job, ro);
    const double b = res.image.metadata.at("gmlt_b").number(), b0 = res.image.metadata.at("gmlt_b_bootstrap").number();
    ASSERT_GT(std::abs(b / b0 - 1), 1e-3) << "the test needs a running b that differs from the bootstrap's";
    const Film &film = *job.film;
    auto layer = [&](const std::string &name) {
        for (int l = 0; l < film.numLayers(); ++l)
            if (film.layerName(l) == name) return film.layerImage(l);
        ADD_FAILURE() << "no film layer " << name;
        return Image();
    };
    const Image primal = layer("gd.lt.primal"), dxf = layer("gd.lt.dxf"), dxb = layer("gd.lt.dxb"),
                dyf = layer("gd.lt.dyf"), dyb = layer("gd.lt.dyb");
    const Image outP = res.image.layerRGB("primal"), outX = res.image.layerRGB("dx"), outY = res.image.layerRGB("dy");
    // Errors relative to the value plus a floor of 1e-3 of the largest primal
    // (gradients sum two float layers: cancellation).
    double floor = 0;
    for (float v : primal.data()) floor = std::max(floor, 1e-3 * b * std::abs(double(v)));
    double maxP = 0, maxG = 0;
    int64_t nonzero = 0;
    for (int y = 0; y < primal.height(); ++y)
        for (int x = 0; x < primal.width(); ++x)
            for (int c = 0; c < 3; ++c) {
                auto rel = [&](double got, double want) { return std::abs(got - want) / (std::abs(want) + floor); };
                const double p = primal.at(x, y, c), gx = double(dxf.at(x, y, c)) + dxb.at(x, y, c),
                             gy = double(dyf.at(x, y, c)) + dyb.at(x, y, c);
                nonzero += gx != 0;
                maxP = std::max(maxP, rel(outP.at(x, y, c), b * p));
                maxG = std::max({maxG, rel(outX.at(x, y, c), b * gx), rel(outY.at(x, y, c), b * gy)});
            }
    EXPECT_GT(nonzero, 0);
    EXPECT_LT(maxP, 1e-5) << "primal not the film's sums times b = " << b << " (bootstrap's " << b0 << ")";
    EXPECT_LT(maxG, 1e-5) << "gradients not the film's sums times b = " << b << " (bootstrap's " << b0 << ")";
}

}  // namespace
}  // namespace gradus::mlt_test
