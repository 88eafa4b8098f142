// Texture lookups against hand-computed values, image texture filtering and
// wrap modes (on images written to a temporary directory), noise properties
// and error handling of the Texture directive.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "image/image.h"
#include "materials/material.h"
#include "samplers/rng.h"
#include "textures/textures.h"

using namespace gradus;

namespace {

class TempDir {
  public:
    TempDir() {
        std::string t = ::testing::TempDir() + "gradus_tex_XXXXXX";
        path_.assign(t.begin(), t.end());
        path_.push_back('\0');
        if (!mkdtemp(path_.data())) throw std::runtime_error("mkdtemp failed");
    }
    ~TempDir() { std::system(("rm -rf '" + dir() + "'").c_str()); }
    std::string dir() const { return std::string(path_.data()); }

  private:
    std::vector<char> path_;
};

SurfaceInteraction At(Float u, Float v, Point3 p = Point3(0, 0, 0)) {
    SurfaceInteraction si;
    si.p = p;
    si.n = si.shading.n = Normal3(0, 0, 1);
    si.uv = Point2(u, v);
    si.dpdu = si.shading.dpdu = Vec3(1, 0, 0);
    si.dpdv = si.shading.dpdv = Vec3(0, 1, 0);
    return si;
}

// Builds every Texture directive of `text` (inside WorldBegin) into named textures.
NamedTextures Build(const std::string &text, const std::string &dir = ".") {
    SceneDesc s = ParseString("WorldBegin\n" + text + "\nWorldEnd\n", "tex.pbrt", dir);
    NamedTextures t;
    for (const TextureDesc &d : s.textures) {
        CreateTexture(d, s, &t);
        d.params.checkUnused("Texture");
    }
    return t;
}

}  // namespace

TEST(Texture, ConstantScaleMix) {
    NamedTextures t = Build(R"(
        Texture "three" "float" "constant" "float value" [3]
        Texture "six" "float" "scale" "texture tex1" "three" "float tex2" [2]
        Texture "quarter" "float" "mix" "float tex1" [0] "float tex2" [1] "float amount" [0.25]
        Texture "red" "spectrum" "constant" "rgb value" [1 0 0]
        Texture "blend" "spectrum" "mix" "texture tex1" "red" "rgb tex2" [0 0 1] "texture amount" "quarter"
    )");
    SurfaceInteraction si = At(0.3, 0.4);
    EXPECT_EQ(t.floats.at("three")->evaluate(si), 3);
    EXPECT_TRUE(t.floats.at("three")->isConstant());
    EXPECT_EQ(t.floats.at("six")->evaluate(si), 6);
    EXPECT_NEAR(t.floats.at("quarter")->evaluate(si), 0.25, 1e-15);
    Spectrum b = t.spectra.at("blend")->evaluate(si);
    EXPECT_NEAR(b.r, 0.75, 1e-15);
    EXPECT_NEAR(b.b, 0.25, 1e-15);
}

TEST(Texture, CheckerboardBilerpUV) {
    NamedTextures t = Build(R"(
        Texture "c" "float" "checkerboard" "float uscale" [2] "float vscale" [2] "float tex1" [1] "float tex2" [0]
        Texture "c3" "float" "checkerboard" "integer dimension" [3]
        Texture "b" "float" "bilerp" "float v00" [0] "float v01" [1] "float v10" [2] "float v11" [3]
        Texture "uv" "spectrum" "uv" "float udelta" [1] "float uscale" [0.5]
    )");
    EXPECT_EQ(t.floats.at("c")->evaluate(At(0.1, 0.1)), 1);  // cell (0,0)
    EXPECT_EQ(t.floats.at("c")->evaluate(At(0.6, 0.1)), 0);  // cell (1,0)
    EXPECT_EQ(t.floats.at("c")->evaluate(At(0.6, 0.6)), 1);  // cell (1,1)
    EXPECT_EQ(t.floats.at("c3")->evaluate(At(0, 0, Point3(0.5, 0.5, 0.5))), 1);
    EXPECT_EQ(t.floats.at("c3")->evaluate(At(0, 0, Point3(1.5, 0.5, 0.5))), 0);
    // (1-s)(1-t) v00 + (1-s) t v01 + s (1-t) v10 + s t v11 at (0.25, 0.5).
    EXPECT_NEAR(t.floats.at("b")->evaluate(At(0.25, 0.5)), 0.375 + 0.25 + 0.375, 1e-15);
    // s = 0.5 u + 1 = 1.6 -> fractional part 0.6.
    Spectrum uv = t.spectra.at("uv")->evaluate(At(1.2, 0.3));
    EXPECT_NEAR(uv.r, 0.6, 1e-12);
    EXPECT_NEAR(uv.g, 0.3, 1e-12);
    EXPECT_EQ(uv.b, 0);
}

TEST(Texture, ImageMapBilinearAndWrap) {
    TempDir tmp;
    // 2x2 image, row 0 at the top of the file: R = [1 2; 3 4], G = 10 R, B = 0.5.
    Image img = Image::RGB(2, 2);
    float vals[2][2] = {{1, 2}, {3, 4}};
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 2; ++x) {
            img.at(x, y, 0) = vals[y][x];
            img.at(x, y, 1) = 10 * vals[y][x];
            img.at(x, y, 2) = 0.5f;
        }
    WriteImage(tmp.dir() + "/img.pfm", img);
    NamedTextures t = Build(R"(
        Texture "rep" "spectrum" "imagemap" "string filename" "img.pfm" "bool trilinear" [ "true" ]
        Texture "blk" "spectrum" "imagemap" "string filename" "img.pfm" "string wrap" "black"
        Texture "clp" "spectrum" "imagemap" "string filename" "img.pfm" "string wrap" "clamp"
        Texture "scl" "spectrum" "imagemap" "string filename" "img.pfm" "float scale" [0.1] "bool invert" [ "true" ]
        Texture "shift" "spectrum" "imagemap" "string filename" "img.pfm" "float uscale" [0.5] "float udelta" [0.5]
        Texture "f" "float" "imagemap" "string filename" "img.pfm"
    )", tmp.dir());
    auto &rep = *t.spectra.at("rep");
    // t = 0 is the bottom row: (0.25, 0.75) is the top-left texel centre.
    EXPECT_NEAR(rep.evaluate(At(0.25, 0.75)).r, 1, 1e-6);
    EXPECT_NEAR(rep.evaluate(At(0.75, 0.75)).r, 2, 1e-6);
    EXPECT_NEAR(rep.evaluate(At(0.25, 0.25)).r, 3, 1e-6);
    EXPECT_NEAR(rep.evaluate(At(0.75, 0.25)).g, 40, 1e-5);
    // Bilinear: the centre averages the four texels; halfway along the top row.
    EXPECT_NEAR(rep.evaluate(At(0.5, 0.5)).r, 2.5, 1e-6);
    EXPECT_NEAR(rep.evaluate(At(0.5, 0.75)).r, 1.5, 1e-6);
    // Repeat: u + 1 is the same point; at u = 0 the left texel blends with the right one.
    EXPECT_NEAR(rep.evaluate(At(1.25, 0.75)).r, 1, 1e-6);
    EXPECT_NEAR(rep.evaluate(At(0.0, 0.75)).r, 1.5, 1e-6);
    // Black: half of the footprint falls outside at u = 0; clamp repeats the edge texel.
    EXPECT_NEAR(t.spectra.at("blk")->evaluate(At(0.0, 0.75)).r, 0.5, 1e-6);
    EXPECT_NEAR(t.spectra.at("clp")->evaluate(At(0.0, 0.75)).r, 1, 1e-6);
    EXPECT_NEAR(t.spectra.at("blk")->evaluate(At(1.5, 0.75)).r, 0, 1e-6);
    // scale then invert: 1 - 0.1 * 3.
    EXPECT_NEAR(t.spectra.at("scl")->evaluate(At(0.25, 0.25)).r, 0.7, 1e-6);
    // s = 0.5 u + 0.5: u = -0.5 -> s = 0.25.
    EXPECT_NEAR(t.spectra.at("shift")->evaluate(At(-0.5, 0.25)).r, 3, 1e-6);
    // Float image textures take the luminance.
    Spectrum px(3, 30, 0.5);
    EXPECT_NEAR(t.floats.at("f")->evaluate(At(0.25, 0.25)), px.y(), 1e-5);
}

TEST(Texture, TexelGridFarOutside) {
    // Lookups far outside [0,1] (huge texture-mapping scales) keep the wrap mode's
    // answer instead of casting out-of-range floats to int (fuzz_image).
    Image img = Image::RGB(2, 1);
    img.at(0, 0, 0) = 1;
    img.at(1, 0, 0) = 2;
    auto grid = MakeTexelGrid(img, false);
    for (double s : {1e300, 3e9, -3e9, -1e300}) {
        double edge = s > 0 ? 2 : 1;
        EXPECT_EQ(grid->bilerp(Point2(s, 0.5), WrapMode::Clamp).r, edge) << s;
        EXPECT_EQ(grid->bilerp(Point2(s, 0.5), WrapMode::Black).r, 0) << s;
        double r = grid->bilerp(Point2(s, 0.5), WrapMode::Repeat).r;
        EXPECT_TRUE(r >= 1 && r <= 2) << s << " -> " << r;
    }
    // Repeat keeps the position within the period for large but exact coordinates.
    EXPECT_NEAR(grid->bilerp(Point2(1e6 + 0.25, 0.5), WrapMode::Repeat).r, 1, 1e-6);
}

TEST(Texture, EightBitGamma) {
    TempDir tmp;
    Image img = Image::RGB(1, 1);
    img.at(0, 0, 0) = img.at(0, 0, 1) = img.at(0, 0, 2) = 0.2f;
    WriteImage(tmp.dir() + "/g.png", img);
    NamedTextures t = Build(R"(
        Texture "lin" "spectrum" "imagemap" "string filename" "g.png"
        Texture "raw" "spectrum" "imagemap" "string filename" "g.png" "bool gamma" [ "false" ]
    )", tmp.dir());
    // The PNG stores round(255 * sRGB(0.2)); gamma decodes it back to ~0.2.
    Float stored = std::round(255 * LinearToSRGB(0.2f)) / 255;
    EXPECT_NEAR(t.spectra.at("lin")->evaluate(At(0.5, 0.5)).r, SRGBToLinear(float(stored)), 1e-5);
    EXPECT_NEAR(t.spectra.at("lin")->evaluate(At(0.5, 0.5)).r, 0.2, 3e-3);
    EXPECT_NEAR(t.spectra.at("raw")->evaluate(At(0.5, 0.5)).r, stored, 1e-5);
}

TEST(Texture, NoiseProperties) {
    // Gradient noise vanishes on the integer lattice and stays bounded.
    EXPECT_EQ(Noise(3, -2, 7), 0);
    RNG rng(1);
    double mn = 0, mx = 0, mean = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
        Point3 p(100 * rng.uniform() - 50, 100 * rng.uniform() - 50, 100 * rng.uniform() - 50);
        Float v = Noise(p);
        mn = std::min(mn, v);
        mx = std::max(mx, v);
        mean += v / n;
        EXPECT_EQ(FBm(p, 0.5, 1), v);
        EXPECT_EQ(Turbulence(p, 0.5, 1), std::abs(v));
    }
    EXPECT_LE(mx, 1.1);
    EXPECT_GE(mn, -1.1);
    EXPECT_GT(mx, 0.4);  // not degenerate
    EXPECT_LT(mn, -0.4);
    EXPECT_NEAR(mean, 0, 0.02);
    // Continuity: a tiny step changes the value a little.
    EXPECT_NEAR(Noise(0.3, 0.6, 0.9), Noise(0.3 + 1e-7, 0.6, 0.9), 1e-5);
    // Period 256 of the lattice, negative cells included.
    EXPECT_NEAR(Noise(-7.3, 2.6, 0.9), Noise(-7.3 + 256, 2.6 - 512, 0.9 + 256), 1e-9);
}

// Coordinates beyond the int64 range (a texture scale of 1e30 in a fuzzed
// scene: the lattice cell's conversion was undefined behaviour) and non-finite
// ones give bounded values; there the integer lattice makes the noise 0.
TEST(Texture, NoiseOfHugeAndNonFiniteCoordinates) {
    for (Float big : {2.9e30, -2.9e30, 9.3e18, -1e300})
        EXPECT_EQ(Noise(big, 0.5, 0.5), Noise(0.0, 0.5, 0.5)) << big;
    EXPECT_EQ(Noise(std::nan(""), 0.2, 0.3), 0);
    EXPECT_EQ(Noise(0.1, Infinity, 0.3), 0);
}

TEST(Texture, ProceduralTexturesBuild) {
    NamedTextures t = Build(R"(
        Texture "d" "spectrum" "dots" "rgb inside" [1 0 0] "rgb outside" [0 0 1]
        Texture "fb" "float" "fbm" "integer octaves" [4] "float roughness" [0.6]
        Texture "w" "float" "wrinkled"
        Texture "wi" "float" "windy"
        Texture "m" "spectrum" "marble" "float scale" [2] "float variation" [0.3]
        Texture "sp" "float" "bilerp" "string mapping" "spherical"
    )");
    RNG rng(2);
    int inside = 0;
    for (int i = 0; i < 2000; ++i) {
        SurfaceInteraction si = At(10 * rng.uniform(), 10 * rng.uniform(),
                                   Point3(rng.uniform(), rng.uniform(), rng.uniform()) * 5);
        Spectrum d = t.spectra.at("d")->evaluate(si);
        EXPECT_TRUE(d == Spectrum(1, 0, 0) || d == Spectrum(0, 0, 1));
        inside += d.r == 1;
        EXPECT_GE(t.floats.at("w")->evaluate(si), 0);
        EXPECT_TRUE(std::isfinite(t.floats.at("fb")->evaluate(si)));
        EXPECT_TRUE(std::isfinite(t.floats.at("wi")->evaluate(si)));
        Spectrum m = t.spectra.at("m")->evaluate(si);
        EXPECT_TRUE(m.r >= 0 && m.r <= 1);
    }
    // Dots cover a fraction of the plane: some points inside, most outside.
    EXPECT_GT(inside, 20);
    EXPECT_LT(inside, 1000);
    // Spherical mapping: point on +z axis has theta = 0 -> s = 0; bilerp gives v00 + t (v01 - v00).
    EXPECT_NEAR(t.floats.at("sp")->evaluate(At(0, 0, Point3(0, 0, 2))), 0, 1e-12);
}

TEST(Texture, Errors) {
    EXPECT_THROW(Build(R"(Texture "x" "float" "nosuch")"), Error);
    EXPECT_THROW(Build(R"(Texture "x" "float" "uv")"), Error);
    EXPECT_THROW(Build(R"(Texture "x" "spectrum" "imagemap" "string filename" "missing.png")"), Error);
    EXPECT_THROW(Build(R"(Texture "x" "float" "scale" "texture tex1" "undefined")"), Error);
    EXPECT_THROW(Build(R"(Texture "x" "float" "imagemap" "string filename" "a.png" "string wrap" "mirror")"), Error);
    // Misspelt parameter is left unused and reported.
    EXPECT_THROW(Build(R"(Texture "x" "float" "constant" "float valeu" [2])"), Error);
}
