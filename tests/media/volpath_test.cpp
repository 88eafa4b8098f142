// The path integrator in media (pbrt-v3's volpath) against closed forms, and
// the refusal of media by integrators that do not render them.
//
// z-tests are two-sided at |z| < 4.4 (false-positive rate 1e-5 per check) on
// pixel means of random-sampler renders with fixed seeds; each also checks
// that a 2% bias would have been detected.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "core/error.h"
#include "render_util.h"

using namespace gradus;
using namespace gradus::test;

namespace {

void ExpectMean(const Image &img, double expected, const std::string &what) {
    for (int c = 0; c < 3; ++c) {
        double mean, se;
        PixelMeanAndStdErr(img, c, &mean, &se);
        se = std::max(se, 1e-9);
        EXPECT_LT(std::abs(mean - expected) / se, 4.4)
            << what << " channel " << c << ": mean " << mean << " expected " << expected << " se " << se;
        EXPECT_GT(std::abs(mean - 1.02 * expected) / se, 4.4) << what << ": a 2% bias would go unseen";
    }
}

// The camera at the centre of a sphere (an interface, no surface) filled with
// a non-absorbing medium, under a uniform environment of radiance 1: in
// equilibrium the radiance is 1 in every direction at every point, whatever
// sigma_s and g (the medium only redistributes directions). Exercises distance
// and phase sampling, NEE with transmittance across the interface and the MIS
// with the environment.
std::string FurnaceInMedium(double sigmaS, double g, const std::string &mediumType) {
    std::ostringstream s;
    s << "LookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\" \"float fov\" [70]\n"
      << "Sampler \"random\" \"integer pixelsamples\" [4]\n"
      << "Film \"image\" \"integer xresolution\" [16] \"integer yresolution\" [16]\n"
      << "Integrator \"path\" \"integer maxdepth\" [1000]\n"
      << "MakeNamedMedium \"fog\" \"string type\" \"" << mediumType << "\"\n"
      << "  \"rgb sigma_a\" [0 0 0] \"rgb sigma_s\" [" << sigmaS << " " << sigmaS << " " << sigmaS << "] \"float g\" ["
      << g << "]\n";
    if (mediumType == "heterogeneous")
        s << "  \"point p0\" [-1 -1 -1] \"point p1\" [1 1 1] \"integer nx\" [2] \"integer ny\" [2] \"integer nz\" [2]"
             " \"float density\" [1 0.2 0.5 1 0.1 0.9 1 0.3]\n";
    s << "MediumInterface \"\" \"fog\"\n"  // the camera sits in the fog
      << "WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"
      << "AttributeBegin\nMediumInterface \"fog\" \"\"\nMaterial \"\"\nShape \"sphere\" \"float radius\" [1]\n"
      << "AttributeEnd\nWorldEnd\n";
    return s.str();
}

}  // namespace

TEST(VolPath, NonAbsorbingMediumInUniformLightIsInEquilibrium) {
    struct Case {
        double sigmaS, g;
        const char *type;
    };
    for (const Case &c : {Case{0.5, 0.0, "homogeneous"}, Case{2.0, 0.6, "homogeneous"}, Case{1.5, -0.4, "homogeneous"},
                          Case{3.0, 0.3, "heterogeneous"}}) {
        RenderResult r = RenderSceneText(FurnaceInMedium(c.sigmaS, c.g, c.type), 64, 3);
        ExpectMean(r.image, 1.0, std::string(c.type) + " sigma_s " + std::to_string(c.sigmaS) + " g " +
                                     std::to_string(c.g));
    }
}

// An emitting quad seen through a box of absorbing medium 1.5 units thick
// along a narrow view: L = Le exp(-sigma_a d) (1 - 1e-4 for the view's spread).
TEST(VolPath, AbsorbingSlabAttenuatesExponentially) {
    std::ostringstream s;
    s << "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [1]\n"
      << "Sampler \"random\" \"integer pixelsamples\" [4]\n"
      << "Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n"
      << "Integrator \"path\" \"integer maxdepth\" [5]\n"
      << "MakeNamedMedium \"ink\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.4 0.8 1.2] "
         "\"rgb sigma_s\" [0 0 0]\n"
      << "WorldBegin\n"
      << "AttributeBegin\nMediumInterface \"ink\" \"\"\nMaterial \"\"\nScale 2 2 0.75\n"
      << "Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2  4 5 6 4 6 7  0 1 5 0 5 4  2 3 7 2 7 6  1 2 6 1 6 5"
         "  0 4 7 0 7 3]\n  \"point P\" [-1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1]\n"
      << "AttributeEnd\n"
      << "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [2 2 2]\nMaterial \"matte\" \"rgb Kd\" [0 0 0]\n"
      << "Shape \"trianglemesh\" \"integer indices\" [0 2 1 0 3 2] \"point P\" [-3 -3 3  3 -3 3  3 3 3  -3 3 3]\n"
      << "AttributeEnd\nWorldEnd\n";
    RenderResult r = RenderSceneText(s.str(), 1024, 9);
    const double sa[3] = {0.4, 0.8, 1.2};
    for (int c = 0; c < 3; ++c) {
        double mean, se;
        PixelMeanAndStdErr(r.image, c, &mean, &se);
        const double expected = 2 * std::exp(-sa[c] * 1.5);
        EXPECT_LT(std::abs(mean - expected), 4.4 * se + 2e-4 * expected) << "channel " << c << " mean " << mean;
        EXPECT_GT(std::abs(mean - 1.02 * expected), 4.4 * se) << "channel " << c;
    }
}

// Integrators without media support refuse the scene at the Integrator
// directive, naming themselves and the medium; path (and pbrt-v3's volpath,
// which maps to it), mlt, gpt and gbdpt render it.
TEST(VolPath, OtherIntegratorsRefuseMediaWithALocatedError) {
    const std::string text = FurnaceInMedium(1.0, 0.0, "homogeneous");
    for (const char *name : {"gvcm", "pmlt", "gmlt"}) {
        std::string err;
        try {
            MakeTestJob(ParseString(text, "test.pbrt", "."), 1, 0, name);
        } catch (const Error &e) {
            err = e.what();
        }
        EXPECT_NE(err.find("test.pbrt:5:1"), std::string::npos) << name << ": " << err;
        EXPECT_NE(err.find(std::string("\"") + name + "\""), std::string::npos) << err;
        EXPECT_NE(err.find("\"fog\""), std::string::npos) << err;
    }
    std::string volpath = text;
    volpath.replace(volpath.find("\"path\""), 6, "\"volpath\"");
    EXPECT_NO_THROW(MakeTestJob(ParseString(volpath, "test.pbrt", "."), 1, 0));
    EXPECT_NO_THROW(MakeTestJob(ParseString(text, "test.pbrt", "."), 1, 0, "mlt"));
    EXPECT_NO_THROW(MakeTestJob(ParseString(text, "test.pbrt", "."), 1, 0, "gpt"));
    EXPECT_NO_THROW(MakeTestJob(ParseString(text, "test.pbrt", "."), 1, 0, "gbdpt"));
}
