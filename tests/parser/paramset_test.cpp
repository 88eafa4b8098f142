// Typed parameter lookups, used-tracking and spectrum -> RGB conversion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "parser/paramset.h"
#include "parser/scene_desc.h"
#include "parser/spectrum_convert.h"

using namespace gradus;

namespace {

const std::string kData = GRADUS_PARSER_TEST_DATA;

// Parameters of one Shape directive written on line 2 of "p.pbrt".
ParamSet P(const std::string &params) {
    SceneDesc s = ParseString("WorldBegin\nShape \"x\" " + params + "\nWorldEnd\n", "p.pbrt", kData);
    return s.shapes.at(0).params;
}

template <typename F>
std::string ErrorOf(F &&f) {
    try {
        f();
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(ParamSet, DefaultsWhenAbsent) {
    ParamSet p = P("");
    EXPECT_EQ(p.getInt("n", 7), 7);
    EXPECT_EQ(p.getFloat("f", 2.5), 2.5);
    EXPECT_TRUE(p.getBool("b", true));
    EXPECT_EQ(p.getString("s", "d"), "d");
    EXPECT_EQ(p.getSpectrum("c", Spectrum(0.25)), Spectrum(0.25));
    EXPECT_EQ(p.getTexture("t"), "");
    EXPECT_TRUE(p.getFloats("v").empty());
    EXPECT_FALSE(p.has("n"));
}

TEST(ParamSet, IntegerConvertsToFloatButNotBack) {
    ParamSet p = P("\"integer n\" 3 \"float f\" 1.5");
    EXPECT_EQ(p.getFloat("n", 0), 3.0);
    EXPECT_EQ(p.getFloats("n"), std::vector<Float>{3.0});
    EXPECT_EQ(ErrorOf([&] { p.getInt("f", 0); }),
              "p.pbrt:2:25: parameter \"float f\" has type float, expected integer");
}

TEST(ParamSet, StringForFloatIsAnError) {
    ParamSet p = P("\"string fov\" \"wide\"");
    EXPECT_EQ(ErrorOf([&] { p.getFloat("fov", 0); }),
              "p.pbrt:2:11: parameter \"string fov\" has type string, expected float");
}

TEST(ParamSet, TypeSynonyms) {
    ParamSet p = P("\"point a\" [1 2 3] \"point3 b\" [4 5 6] \"vector c\" [1 0 0] \"vector3 d\" [0 1 0]"
                   " \"normal e\" [0 0 1] \"normal3 f\" [1 1 1] \"color g\" [.1 .2 .3] \"rgb h\" [.4 .5 .6]");
    EXPECT_EQ(p.getPoint3("a", {}), Point3(1, 2, 3));
    EXPECT_EQ(p.getPoint3("b", {}), Point3(4, 5, 6));
    EXPECT_EQ(p.getVector3("c", {}), Vec3(1, 0, 0));
    EXPECT_EQ(p.getVector3("d", {}), Vec3(0, 1, 0));
    EXPECT_EQ(p.getNormal("e", {}), Normal3(0, 0, 1));
    EXPECT_EQ(p.getNormal("f", {}), Normal3(1, 1, 1));
    EXPECT_EQ(p.getSpectrum("g", {}), Spectrum(.1, .2, .3));
    EXPECT_EQ(p.getSpectrum("h", {}), Spectrum(.4, .5, .6));
    // point is not a vector.
    EXPECT_THROW(p.getVector3("a", {}), Error);
    EXPECT_THROW(p.getNormal("c", {}), Error);
}

TEST(ParamSet, Bools) {
    ParamSet p = P("\"bool a\" true \"bool b\" \"false\" \"bool c\" [\"true\"] \"bool d\" [false]");
    EXPECT_TRUE(p.getBool("a", false));
    EXPECT_FALSE(p.getBool("b", true));
    EXPECT_TRUE(p.getBool("c", false));
    EXPECT_FALSE(p.getBool("d", true));
}

TEST(ParamSet, SingleValueLookupsCheckCount) {
    ParamSet p = P("\"float f\" [1 2]");
    EXPECT_EQ(ErrorOf([&] { p.getFloat("f", 0); }), "p.pbrt:2:11: parameter \"float f\" needs 1 value, got 2 values");
    EXPECT_EQ(p.getFloats("f"), (std::vector<Float>{1, 2}));
}

TEST(ParamSet, ArrayLookups) {
    ParamSet p = P("\"point P\" [0 0 0 1 0 0 0 1 0] \"normal N\" [0 0 1 0 0 1 0 0 1] \"float uv\" [0 0 1 0 0 1]"
                   " \"integer indices\" [0 1 2] \"point2 st\" [0 0 1 1] \"vector3 dirs\" [1 0 0 0 1 0]");
    EXPECT_EQ(p.getPoint3s("P").size(), 3u);
    EXPECT_EQ(p.getPoint3s("P")[1], Point3(1, 0, 0));
    EXPECT_EQ(p.getNormals("N").size(), 3u);
    ASSERT_EQ(p.getPoint2s("uv").size(), 3u);  // float pairs accepted
    EXPECT_EQ(p.getPoint2s("uv")[2], Point2(0, 1));
    EXPECT_EQ(p.getPoint2s("st").size(), 2u);
    EXPECT_EQ(p.getInts("indices"), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(p.getVector3s("dirs").size(), 2u);
}

TEST(ParamSet, TextureLookupIgnoresOtherTypes) {
    ParamSet p = P("\"texture Kd\" \"wood\" \"rgb Ks\" [1 1 1]");
    EXPECT_EQ(p.getTexture("Kd"), "wood");
    EXPECT_EQ(p.getTexture("Ks"), "");  // an rgb is not a texture reference...
    EXPECT_EQ(ErrorOf([&] { p.checkUnused("Material \"plastic\""); }),
              "p.pbrt:2:31: parameter \"rgb Ks\" is not used by Material \"plastic\" (misspelt or unsupported)");
    EXPECT_EQ(p.getSpectrum("Ks", {}), Spectrum(1.0));  // ...and stays for the typed lookup
    EXPECT_NO_THROW(p.checkUnused("Material \"plastic\""));
    EXPECT_THROW(p.getSpectrum("Kd", {}), Error);  // a texture is not a spectrum
}

TEST(ParamSet, CheckUnusedReportsFirstUnusedWithLocation) {
    SceneDesc s = ParseString("Camera \"perspective\"\n  \"float fvo\" [45] \"float lensradius\" 0\nWorldBegin\nWorldEnd",
                              "c.pbrt", ".");
    const ParamSet &p = s.camera.params;
    EXPECT_EQ(p.getFloat("fov", 90), 90);  // misspelt: default
    EXPECT_EQ(ErrorOf([&] { p.checkUnused("Camera \"perspective\""); }),
              "c.pbrt:2:3: parameter \"float fvo\" is not used by Camera \"perspective\" (misspelt or unsupported)");
    p.getFloat("fvo", 0);
    EXPECT_EQ(ErrorOf([&] { p.checkUnused("Camera \"perspective\""); }),
              "c.pbrt:2:20: parameter \"float lensradius\" is not used by Camera \"perspective\" (misspelt or "
              "unsupported)");
    p.getFloat("lensradius", 0);
    EXPECT_NO_THROW(p.checkUnused("Camera \"perspective\""));
}

TEST(ParamSet, FindMarksUsedAndLaterDuplicateWins) {
    ParamSet p = P("\"float a\" 1 \"float a\" 2");
    EXPECT_EQ(p.all().size(), 1u);
    EXPECT_EQ(p.getFloat("a", 0), 2);
    ParamSet q = P("\"float z\" 1");
    ASSERT_NE(q.find("z"), nullptr);
    EXPECT_NO_THROW(q.checkUnused("x"));
    EXPECT_EQ(q.locOf("z", FileLoc()).str(), "p.pbrt:2:11");
    EXPECT_EQ(q.locOf("nope", FileLoc()).line, 1);
}

// ------------------------------------------------------------ spectra

TEST(Spectra, CieFitMatchesTabulatedValues) {
    // CIE 1931 2-degree values (published table); the multi-lobe fit of
    // Wyman et al. 2013 is accurate to a few hundredths near the lobes.
    EXPECT_NEAR(CieY(555), 1.0000, 0.02);
    EXPECT_NEAR(CieY(500), 0.3230, 0.03);
    EXPECT_NEAR(CieY(650), 0.1070, 0.03);
    EXPECT_NEAR(CieX(600), 1.0622, 0.03);
    EXPECT_NEAR(CieX(650), 0.2835, 0.03);
    EXPECT_NEAR(CieX(500), 0.0049, 0.03);
    EXPECT_NEAR(CieZ(450), 1.7721, 0.05);
    EXPECT_NEAR(CieZ(600), 0.0008, 0.01);
}

TEST(Spectra, ConstantReflectanceIsGrey) {
    ParamSet p = P("\"spectrum Kd\" [400 0.5 500 0.5 600 0.5 700 0.5]");
    Spectrum s = p.getSpectrum("Kd", {});
    EXPECT_NEAR(s.r, 0.5, 1e-6);
    EXPECT_NEAR(s.g, 0.5, 1e-6);
    EXPECT_NEAR(s.b, 0.5, 1e-6);
}

TEST(Spectra, ConstantIlluminantHasUnitLuminance) {
    // pbrt-v3 normalisation: XYZ divided by the integral of ybar, so an
    // equal-energy spectrum of value 1 has Y = 1.
    ParamSet p = P("\"spectrum L\" [300 1 900 1]");
    Spectrum s = p.getSpectrum("L", {}, SpectrumKind::Illuminant);
    EXPECT_NEAR(s.y(), 1.0, 2e-3);
    // Equal energy is pinkish in sRGB (white point E vs D65).
    EXPECT_GT(s.r, s.g);
    EXPECT_GT(s.g, s.b);
}

TEST(Spectra, NarrowBandsHaveTheExpectedHue) {
    auto rgbOfBand = [](double center) {
        return SampledToRGB({center - 15, center - 10, center + 10, center + 15}, {0, 1, 1, 0},
                            SpectrumKind::Illuminant);
    };
    Spectrum blue = rgbOfBand(450), green = rgbOfBand(530), red = rgbOfBand(620);
    EXPECT_GT(blue.b, std::max(blue.r, blue.g));
    EXPECT_GT(green.g, std::max(green.r, green.b));
    EXPECT_GT(red.r, std::max(red.g, red.b));
}

TEST(Spectra, UnsortedSamplesAreSorted) {
    Spectrum a = SampledToRGB({400, 500, 600, 700}, {0.1, 0.4, 0.8, 0.3}, SpectrumKind::Reflectance);
    Spectrum b = SampledToRGB({600, 400, 700, 500}, {0.8, 0.1, 0.3, 0.4}, SpectrumKind::Reflectance);
    EXPECT_NEAR(a.r, b.r, 1e-12);
    EXPECT_NEAR(a.g, b.g, 1e-12);
    EXPECT_NEAR(a.b, b.b, 1e-12);
}

TEST(Spectra, Blackbody6500IsNearWhite) {
    ParamSet p = P("\"blackbody L\" [6500 1]");
    Spectrum s = p.getSpectrum("L", {});
    double mx = s.maxComponent(), mn = std::min(s.r, std::min(s.g, s.b));
    EXPECT_GT(mn, 0);
    EXPECT_LT(mx / mn, 1.08) << s.r << " " << s.g << " " << s.b;
}

TEST(Spectra, BlackbodyHueAndScale) {
    Spectrum warm = BlackbodyToRGB(2700, 1), cool = BlackbodyToRGB(12000, 1);
    EXPECT_GT(warm.r, warm.g);
    EXPECT_GT(warm.g, warm.b);
    EXPECT_GT(cool.b, cool.r);
    Spectrum s1 = BlackbodyToRGB(4000, 1), s3 = BlackbodyToRGB(4000, 3);
    EXPECT_NEAR(s3.g, 3 * s1.g, 1e-12);
    // Peak-normalised: the spectrum is at most 1, so Y stays below 1.
    EXPECT_LT(s1.y(), 1.0);
    EXPECT_GT(s1.y(), 0.5);
}

TEST(Spectra, SpdFileResolvedAgainstSceneDirectory) {
    ParamSet p = P("\"spectrum Kd\" \"half.spd\"");
    Spectrum s = p.getSpectrum("Kd", {});
    EXPECT_NEAR(s.r, 0.5, 1e-6);
    EXPECT_NEAR(s.g, 0.5, 1e-6);
    EXPECT_NEAR(s.b, 0.5, 1e-6);
}

TEST(Spectra, MissingSpdFileIsALocatedError) {
    std::string e = ErrorOf([] { P("\"spectrum Kd\" \"nothere.spd\""); });
    EXPECT_EQ(e.rfind("p.pbrt:2:11: spectrum file \"nothere.spd\": ", 0), 0u) << e;
}

TEST(Spectra, NamedMetalSpectraAreUnsupported) {
    ParamSet p = P("\"spectrum eta\" \"metal-Cu-eta\"");
    try {
        p.getSpectrum("eta", {});
        FAIL() << "expected UnsupportedError";
    } catch (const UnsupportedError &e) {
        std::string m = e.what();
        EXPECT_EQ(m.rfind("p.pbrt:2:11: ", 0), 0u);
        EXPECT_NE(m.find("metal-Cu-eta"), std::string::npos);
    }
}

TEST(Spectra, SpectrumArity) {
    std::string e = ErrorOf([] { P("\"spectrum Kd\" [400 0.5 500]"); });
    EXPECT_EQ(e, "p.pbrt:2:11: parameter \"spectrum Kd\" needs (wavelength value) pairs, got 3 values");
}
