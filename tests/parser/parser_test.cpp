// Directives, graphics-state semantics (pbrt-v3 api.cpp behaviour) and
// located syntax/semantic errors of the pbrt-v3 parser.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "parser/scene_desc.h"

using namespace gradus;

namespace {

const std::string kData = GRADUS_PARSER_TEST_DATA;

SceneDesc Parse(const std::string &text) { return ParseString(text, "t.pbrt", kData); }

// Wraps world-block text in a minimal scene.
SceneDesc World(const std::string &body) { return Parse("WorldBegin\n" + body + "\nWorldEnd\n"); }

// The message of the gradus::Error thrown by parsing `text`, or "" if none.
std::string ErrorOf(const std::string &text) {
    try {
        Parse(text);
    } catch (const Error &e) {
        return e.what();
    }
    return "";
}

void ExpectNear(const Point3 &a, const Point3 &b, double eps = 1e-9) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}

void ExpectSameMatrix(const Transform &a, const Transform &b, double eps = 1e-12) {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(a.matrix().m[i][j], b.matrix().m[i][j], eps) << i << "," << j;
}

}  // namespace

// ------------------------------------------------------------ options block

TEST(Parser, OptionDirectivesRecorded) {
    SceneDesc s = Parse(R"(
Film "image" "integer xresolution" [64] "integer yresolution" 32 "string filename" "out.exr"
Sampler "sobol" "integer pixelsamples" [16]
PixelFilter "triangle" "float xwidth" [1]
Integrator "path" "integer maxdepth" [5]
Accelerator "bvh"
TransformTimes 0.25 0.75
Camera "perspective" "float fov" [45]
WorldBegin
WorldEnd
)");
    EXPECT_TRUE(s.film.present);
    EXPECT_EQ(s.film.type, "image");
    EXPECT_EQ(s.film.params.getInt("xresolution", 0), 64);
    EXPECT_EQ(s.film.params.getInt("yresolution", 0), 32);
    EXPECT_EQ(s.film.params.getString("filename", ""), "out.exr");
    EXPECT_EQ(s.sampler.type, "sobol");
    EXPECT_EQ(s.sampler.params.getInt("pixelsamples", 0), 16);
    EXPECT_EQ(s.filter.type, "triangle");
    EXPECT_EQ(s.integrator.type, "path");
    EXPECT_EQ(s.integrator.params.getInt("maxdepth", 0), 5);
    EXPECT_EQ(s.accelerator.type, "bvh");
    EXPECT_TRUE(s.camera.present);
    EXPECT_EQ(s.camera.type, "perspective");
    EXPECT_EQ(s.camera.params.getFloat("fov", 0), 45);
    EXPECT_EQ(s.camera.loc.line, 8);
    EXPECT_EQ(s.camera.loc.column, 1);
    EXPECT_EQ(s.transformStartTime, 0.25);
    EXPECT_EQ(s.transformEndTime, 0.75);
}

TEST(Parser, AbsentOptionsAreNotPresent) {
    SceneDesc s = Parse("WorldBegin WorldEnd");
    EXPECT_FALSE(s.camera.present);
    EXPECT_FALSE(s.film.present);
    EXPECT_FALSE(s.sampler.present);
    EXPECT_FALSE(s.integrator.present);
    EXPECT_TRUE(s.shapes.empty());
}

// ------------------------------------------------------------ transforms

TEST(Parser, TransformsPostMultiply) {
    // CTM = Translate * Scale: the scale applies first to object points.
    SceneDesc s = World("Translate 1 2 3\nScale 2 2 2\nShape \"sphere\"");
    ASSERT_EQ(s.shapes.size(), 1u);
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3(1, 1, 1)), Point3(3, 4, 5));
}

TEST(Parser, RotateAndConcatTransform) {
    SceneDesc s = World(
        "Rotate 90 0 0 1\nShape \"sphere\"\n"
        "Identity\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\nConcatTransform [2 0 0 0 0 2 0 0 0 0 2 0 0 0 0 1]\n"
        "Shape \"sphere\"");
    ASSERT_EQ(s.shapes.size(), 2u);
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3(1, 0, 0)), Point3(0, 1, 0));
    // Column-major like pbrt-v3: translation in elements 12..14; concatenated after.
    ExpectNear(s.shapes[1].worldFromObject.applyPoint(Point3(1, 1, 1)), Point3(7, 8, 9));
}

TEST(Parser, TransformReplacesCtm) {
    SceneDesc s = World("Translate 100 0 0\nTransform [1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1]\nShape \"sphere\"");
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3(0, 0, 0)), Point3(1, 2, 3));
    // Brackets are optional.
    SceneDesc t = World("Transform 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1\nShape \"sphere\"");
    ExpectNear(t.shapes[0].worldFromObject.applyPoint(Point3(0, 0, 0)), Point3(1, 2, 3));
}

TEST(Parser, HandednessFlipScale) {
    SceneDesc s = World("Shape \"sphere\"\nScale -1 1 1\nShape \"sphere\"");
    EXPECT_FALSE(s.shapes[0].worldFromObject.swapsHandedness());
    EXPECT_TRUE(s.shapes[1].worldFromObject.swapsHandedness());
    ExpectNear(s.shapes[1].worldFromObject.applyPoint(Point3(1, 2, 3)), Point3(-1, 2, 3));
}

TEST(Parser, LookAtCameraAndCameraCoordinateSystem) {
    SceneDesc s = Parse(R"(
Scale -1 1 1
LookAt 0 2 10  0 2 0  0 1 0
Camera "perspective"
WorldBegin
CoordSysTransform "camera"
Shape "sphere"
WorldEnd
)");
    Transform expected = Scale(-1, 1, 1) * LookAt(Point3(0, 2, 10), Point3(0, 2, 0), Vec3(0, 1, 0));
    ExpectSameMatrix(s.camera.cameraFromWorld, expected);
    // The eye maps to the camera-space origin, the look point onto +z.
    ExpectNear(s.camera.cameraFromWorld.applyPoint(Point3(0, 2, 10)), Point3(0, 0, 0));
    ExpectNear(s.camera.cameraFromWorld.applyPoint(Point3(0, 2, 0)), Point3(0, 0, 10));
    // "camera" names world-from-camera: a shape there sits at the eye.
    ASSERT_EQ(s.shapes.size(), 1u);
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3(0, 0, 0)), Point3(0, 2, 10));
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3(0, 0, 1)), Point3(0, 2, 9));
}

TEST(Parser, WorldBeginResetsCtm) {
    SceneDesc s = Parse("Translate 5 5 5\nCamera \"perspective\"\nWorldBegin\nShape \"sphere\"\nWorldEnd");
    EXPECT_TRUE(s.shapes[0].worldFromObject.isIdentity());
    ExpectNear(s.camera.cameraFromWorld.applyPoint(Point3(0, 0, 0)), Point3(5, 5, 5));
}

TEST(Parser, NestedAttributeAndTransformBlocks) {
    SceneDesc s = World(R"(
Translate 1 0 0
AttributeBegin
  Translate 0 1 0
  TransformBegin
    Translate 0 0 1
    Shape "sphere"
  TransformEnd
  Shape "sphere"
AttributeEnd
Shape "sphere"
)");
    ASSERT_EQ(s.shapes.size(), 3u);
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3()), Point3(1, 1, 1));
    ExpectNear(s.shapes[1].worldFromObject.applyPoint(Point3()), Point3(1, 1, 0));
    ExpectNear(s.shapes[2].worldFromObject.applyPoint(Point3()), Point3(1, 0, 0));
}

TEST(Parser, TransformBlockDoesNotRestoreAttributes) {
    // TransformBegin/End saves only the transform (pbrt-v3); the material set
    // inside survives the block, the AttributeEnd restores it.
    SceneDesc s = World(R"(
AttributeBegin
  TransformBegin
    Material "mirror"
  TransformEnd
  Shape "sphere"
AttributeEnd
Shape "sphere"
)");
    EXPECT_EQ(s.shapes[0].material, 0);
    EXPECT_EQ(s.shapes[1].material, -1);
}

TEST(Parser, CoordinateSystemRoundTrip) {
    SceneDesc s = World(R"(
Translate 3 0 0
CoordinateSystem "mine"
Identity
Shape "sphere"
CoordSysTransform "mine"
Shape "sphere"
CoordSysTransform "world"
Shape "sphere"
)");
    EXPECT_TRUE(s.shapes[0].worldFromObject.isIdentity());
    ExpectNear(s.shapes[1].worldFromObject.applyPoint(Point3()), Point3(3, 0, 0));
    EXPECT_TRUE(s.shapes[2].worldFromObject.isIdentity());
}

TEST(Parser, ActiveTransformKeepsStartTransform) {
    SceneDesc s = World(R"(
ActiveTransform EndTime
Translate 9 9 9
ActiveTransform StartTime
Translate 1 0 0
ActiveTransform All
Translate 0 1 0
Shape "sphere"
)");
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3()), Point3(1, 1, 0));
}

TEST(Parser, ActiveTransformRestoredByAttributeEnd) {
    SceneDesc s = World(R"(
AttributeBegin
  ActiveTransform EndTime
AttributeEnd
Translate 1 0 0
Shape "sphere"
)");
    ExpectNear(s.shapes[0].worldFromObject.applyPoint(Point3()), Point3(1, 0, 0));
}

TEST(Parser, ReverseOrientationScopedByAttributes) {
    SceneDesc s = World(R"(
AttributeBegin
  ReverseOrientation
  Shape "sphere"
  ReverseOrientation
  Shape "sphere"
  ReverseOrientation
AttributeEnd
Shape "sphere"
)");
    EXPECT_TRUE(s.shapes[0].reverseOrientation);
    EXPECT_FALSE(s.shapes[1].reverseOrientation);
    EXPECT_FALSE(s.shapes[2].reverseOrientation);
}

// ------------------------------------------------------------ materials, lights

TEST(Parser, MaterialBookkeeping) {
    SceneDesc s = World(R"(
Shape "sphere"
MakeNamedMaterial "red" "string type" "matte" "rgb Kd" [0.8 0.1 0.1]
Shape "sphere"
AttributeBegin
  Material "plastic" "float roughness" 0.1
  Shape "sphere"
  NamedMaterial "red"
  Shape "sphere"
AttributeEnd
Shape "sphere"
)");
    ASSERT_EQ(s.shapes.size(), 5u);
    ASSERT_EQ(s.materials.size(), 2u);
    EXPECT_EQ(s.shapes[0].material, -1);
    EXPECT_EQ(s.shapes[1].material, -1);  // MakeNamedMaterial does not select
    EXPECT_EQ(s.materials[0].name, "red");
    EXPECT_EQ(s.materials[0].type, "matte");
    EXPECT_EQ(s.namedMaterials.at("red"), 0);
    EXPECT_EQ(s.materials[1].name, "");
    EXPECT_EQ(s.materials[1].type, "plastic");
    EXPECT_EQ(s.shapes[2].material, 1);
    EXPECT_EQ(s.shapes[3].material, 0);
    EXPECT_EQ(s.shapes[4].material, -1);
    // "string type" is consumed by the parser; Kd is left for the builder.
    EXPECT_NO_THROW({
        s.materials[0].params.getSpectrum("Kd", Spectrum());
        s.materials[0].params.checkUnused("MakeNamedMaterial \"red\"");
    });
}

TEST(Parser, NamedMaterialsAreScopedByAttributes) {
    // pbrt-v3 keeps named materials in the graphics state.
    std::string e = ErrorOf(
        "WorldBegin\nAttributeBegin\nMakeNamedMaterial \"m\" \"string type\" \"matte\"\nAttributeEnd\n"
        "NamedMaterial \"m\"\nWorldEnd\n");
    EXPECT_EQ(e, "t.pbrt:5:15: NamedMaterial: unknown material \"m\"");
}

TEST(Parser, AreaLightAppliesToFollowingShapesOfItsBlock) {
    SceneDesc s = World(R"(
Shape "sphere"
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [1 2 3]
  Shape "sphere"
  Shape "disk"
AttributeEnd
Shape "sphere"
)");
    ASSERT_EQ(s.areaLights.size(), 1u);
    EXPECT_EQ(s.areaLights[0].type, "diffuse");
    EXPECT_EQ(s.shapes[0].areaLight, -1);
    EXPECT_EQ(s.shapes[1].areaLight, 0);
    EXPECT_EQ(s.shapes[2].areaLight, 0);
    EXPECT_EQ(s.shapes[3].areaLight, -1);
    Spectrum L = s.areaLights[0].params.getSpectrum("L", Spectrum());
    EXPECT_EQ(L, Spectrum(1, 2, 3));
}

TEST(Parser, LightSourceTransformAndMedia) {
    SceneDesc s = Parse(R"(
MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [1 1 1]
MediumInterface "" "fog"
Camera "perspective"
WorldBegin
Translate 0 5 0
LightSource "point" "rgb I" [10 10 10]
MediumInterface "fog" ""
Shape "sphere"
MediumInterface "fog"
Shape "sphere"
WorldEnd
)");
    ASSERT_EQ(s.media.size(), 1u);
    EXPECT_EQ(s.media[0].name, "fog");
    EXPECT_EQ(s.media[0].type, "homogeneous");
    EXPECT_EQ(s.camera.mediumName, "fog");
    ASSERT_EQ(s.lights.size(), 1u);
    EXPECT_EQ(s.lights[0].type, "point");
    EXPECT_EQ(s.lights[0].outsideMedium, "fog");
    ExpectNear(s.lights[0].worldFromLight.applyPoint(Point3()), Point3(0, 5, 0));
    EXPECT_EQ(s.shapes[0].insideMedium, "fog");
    EXPECT_EQ(s.shapes[0].outsideMedium, "");
    EXPECT_EQ(s.shapes[1].insideMedium, "fog");
    EXPECT_EQ(s.shapes[1].outsideMedium, "fog");
}

// pbrt-v3 creates the camera at WorldEnd from the graphics state then: a
// MediumInterface after Camera still places it (fog-spotlight's pattern);
// one inside an attribute block does not.
TEST(Parser, CameraMediumIsTheStateAtWorldEnd) {
    SceneDesc a = Parse(R"(
Camera "perspective"
MakeNamedMedium "fog" "string type" "homogeneous"
MediumInterface "" "fog"
WorldBegin
AttributeBegin
MediumInterface "" ""
AttributeEnd
WorldEnd
)");
    EXPECT_EQ(a.camera.mediumName, "fog");
    SceneDesc b = Parse(R"(
MakeNamedMedium "fog" "string type" "homogeneous"
MediumInterface "" "fog"
Camera "perspective"
WorldBegin
MediumInterface "" ""
WorldEnd
)");
    EXPECT_EQ(b.camera.mediumName, "");
}

TEST(Parser, UnknownMediumIsAnError) {
    EXPECT_EQ(ErrorOf("WorldBegin\nMediumInterface \"a\" \"\"\nShape \"sphere\"\nWorldEnd"),
              "t.pbrt:3:1: unknown medium \"a\" (no MakeNamedMedium of that name)");
}

TEST(Parser, Textures) {
    SceneDesc s = World(R"(
Scale 2 2 2
Texture "checks" "spectrum" "checkerboard" "float uscale" [4] "rgb tex1" [1 0 0]
Texture "bump" "float" "imagemap" "string filename" "b.png"
Texture "old" "color" "constant" "rgb value" [1 1 1]
Material "matte" "texture Kd" "checks"
)");
    ASSERT_EQ(s.textures.size(), 3u);
    EXPECT_EQ(s.textures[0].name, "checks");
    EXPECT_EQ(s.textures[0].valueType, "spectrum");
    EXPECT_EQ(s.textures[0].type, "checkerboard");
    ExpectNear(s.textures[0].worldFromTexture.applyPoint(Point3(1, 1, 1)), Point3(2, 2, 2));
    EXPECT_EQ(s.textures[1].valueType, "float");
    EXPECT_EQ(s.textures[2].valueType, "spectrum");  // "color" accepted as spectrum
    EXPECT_EQ(s.materials[0].params.getTexture("Kd"), "checks");
    EXPECT_EQ(ErrorOf("WorldBegin\nTexture \"t\" \"vector\" \"constant\"\nWorldEnd"),
              "t.pbrt:2:13: texture value type must be \"float\", \"spectrum\" or \"color\", got \"vector\"");
}

// ------------------------------------------------------------ instancing

TEST(Parser, ObjectInstancing) {
    SceneDesc s = World(R"(
AttributeBegin
  Material "mirror"
  ObjectBegin "pair"
    Translate 1 0 0
    Shape "sphere"
    Shape "disk"
  ObjectEnd
  Shape "sphere"
AttributeEnd
Translate 0 0 10
ObjectInstance "pair"
Translate 0 0 10
ObjectInstance "pair"
)");
    ASSERT_EQ(s.instances.size(), 1u);
    const InstanceDesc &inst = s.instances.at("pair");
    EXPECT_EQ(inst.name, "pair");
    ASSERT_EQ(inst.shapes.size(), 2u);
    EXPECT_EQ(inst.shapes[0].type, "sphere");
    EXPECT_EQ(inst.shapes[0].material, 0);
    ExpectNear(inst.shapes[0].worldFromObject.applyPoint(Point3()), Point3(1, 0, 0));
    // ObjectEnd restores the transform of ObjectBegin.
    ASSERT_EQ(s.shapes.size(), 1u);
    EXPECT_TRUE(s.shapes[0].worldFromObject.isIdentity());
    ASSERT_EQ(s.instanceUses.size(), 2u);
    ExpectNear(s.instanceUses[0].worldFromInstance.applyPoint(Point3()), Point3(0, 0, 10));
    ExpectNear(s.instanceUses[1].worldFromInstance.applyPoint(Point3()), Point3(0, 0, 20));
    EXPECT_EQ(s.instanceUses[1].name, "pair");
}

TEST(Parser, InstancingErrors) {
    EXPECT_EQ(ErrorOf("WorldBegin\nObjectInstance \"nope\"\nWorldEnd"),
              "t.pbrt:2:16: ObjectInstance of unknown object \"nope\"");
    EXPECT_EQ(ErrorOf("WorldBegin\nObjectBegin \"a\"\nObjectBegin \"b\"\nObjectEnd\nObjectEnd\nWorldEnd"),
              "t.pbrt:3:1: ObjectBegin \"b\" inside the definition of object \"a\"");
    EXPECT_EQ(ErrorOf("WorldBegin\n  ObjectEnd\nWorldEnd"), "t.pbrt:2:3: ObjectEnd outside an object definition");
    EXPECT_EQ(ErrorOf("WorldBegin\nObjectBegin \"a\"\nObjectEnd\nObjectBegin \"a\"\nObjectEnd\nWorldEnd"),
              "t.pbrt:4:13: object \"a\" is already defined");
}

// ------------------------------------------------------------ parameter syntax

TEST(Parser, ParameterValueForms) {
    SceneDesc s = World(R"(Shape "x" "float a" 1.5 "float b" [ -2e-3 ] "string s" "q\"uo\\te\n" "bool t" true
  "bool f" "false" "integer i" [ 1 2 +3 ] "point2 p2" [1 2] "normal n" [0 0 1]
  "vector v" [1 0 0] "point3 p3" [1 2 3 4 5 6] "string many" ["a" "b"] # trailing comment
)");
    const ParamSet &p = s.shapes[0].params;
    EXPECT_EQ(p.getFloat("a", 0), 1.5);
    EXPECT_EQ(p.getFloat("b", 0), -2e-3);
    EXPECT_EQ(p.getString("s", ""), "q\"uo\\te\n");
    EXPECT_TRUE(p.getBool("t", false));
    EXPECT_FALSE(p.getBool("f", true));
    EXPECT_EQ(p.getInts("i"), (std::vector<int>{1, 2, 3}));
    EXPECT_EQ(p.getPoint2("p2", Point2()), Point2(1, 2));
    EXPECT_EQ(p.getNormal("n", Normal3()), Normal3(0, 0, 1));
    EXPECT_EQ(p.getVector3("v", Vec3()), Vec3(1, 0, 0));
    EXPECT_EQ(p.getPoint3s("p3").size(), 2u);
    EXPECT_EQ(p.getStrings("many"), (std::vector<std::string>{"a", "b"}));
    EXPECT_NO_THROW(p.checkUnused("Shape \"x\""));
}

TEST(Parser, LocationsOfDirectivesAndParameters) {
    SceneDesc s = World("  Shape \"sphere\"\n\t\"float radius\" [2]");
    EXPECT_EQ(s.shapes[0].loc.line, 2);
    EXPECT_EQ(s.shapes[0].loc.column, 3);
    FileLoc l = s.shapes[0].params.locOf("radius", FileLoc());
    EXPECT_EQ(l.str(), "t.pbrt:3:2");
}

// ------------------------------------------------------------ Include

TEST(Parser, IncludeRelativeToIncludingFile) {
    SceneDesc s = ParseFile(kData + "/include_main.pbrt");
    ASSERT_EQ(s.shapes.size(), 3u);
    EXPECT_EQ(s.shapes[0].params.getFloat("radius", 0), 1);
    EXPECT_EQ(s.shapes[1].params.getFloat("radius", 0), 2);
    EXPECT_EQ(s.shapes[2].params.getFloat("radius", 0), 3);
    // Entities carry the file they came from.
    EXPECT_NE(s.shapes[1].loc.filename().find("inc/more.pbrt"), std::string::npos);
    EXPECT_EQ(s.shapes[1].loc.line, 2);
    EXPECT_EQ(s.sceneDirectory, kData);
}

TEST(Parser, ErrorInIncludedFileNamesThatFile) {
    try {
        ParseFile(kData + "/include_bad.pbrt");
        FAIL() << "expected an error";
    } catch (const Error &e) {
        EXPECT_EQ(std::string(e.what()), kData + "/inc/bad.pbrt:2:21: malformed number '2x'");
    }
}

TEST(Parser, MissingIncludeFile) {
    try {
        ParseFile(kData + "/include_missing.pbrt");
        FAIL() << "expected an error";
    } catch (const Error &e) {
        std::string m = e.what();
        EXPECT_EQ(m.rfind(kData + "/include_missing.pbrt:2:11: cannot open included file \"does/not/exist.pbrt\"", 0),
                  0u)
            << m;
    }
}

TEST(Parser, MissingSceneFile) {
    EXPECT_THROW(ParseFile(kData + "/no_such_scene.pbrt"), Error);
}

// ------------------------------------------------------------ errors with exact locations

TEST(ParserErrors, UnknownDirective) {
    EXPECT_EQ(ErrorOf("WorldBegin\n  Shap \"sphere\"\nWorldEnd"), "t.pbrt:2:3: unknown directive 'Shap'");
}

TEST(ParserErrors, UnknownParameterType) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"flaot radius\" [1]\nWorldEnd"),
              "t.pbrt:2:16: unknown parameter type 'flaot' in \"flaot radius\"");
}

TEST(ParserErrors, MalformedNumber) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"float radius\" [1.0.0]\nWorldEnd"),
              "t.pbrt:2:32: malformed number '1.0.0'");
    EXPECT_EQ(ErrorOf("Translate 1 x 3\nWorldBegin\nWorldEnd"), "t.pbrt:1:13: malformed number 'x'");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"integer n\" [1.5]\nWorldEnd"),
              "t.pbrt:2:24: parameter \"integer n\" expects integers, got '1.5'");
}

TEST(ParserErrors, NonFiniteNumbersAreRejected) {
    EXPECT_EQ(ErrorOf("WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.5 nan 0.5]\nWorldEnd"),
              "t.pbrt:2:32: non-finite number 'nan' in parameter \"rgb Kd\" (NaN and infinity are not valid values)");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"float radius\" [inf]\nWorldEnd"),
              "t.pbrt:2:32: non-finite number 'inf' in parameter \"float radius\" (NaN and infinity are not valid "
              "values)");
    EXPECT_EQ(ErrorOf("Translate 1 -inf 3\nWorldBegin\nWorldEnd"),
              "t.pbrt:1:13: non-finite number '-inf' (NaN and infinity are not valid values)");
    // Out of double range: not a number at all.
    EXPECT_EQ(ErrorOf("Scale 1e400 1 1\nWorldBegin\nWorldEnd"), "t.pbrt:1:7: malformed number '1e400'");
}

TEST(ParserErrors, UnterminatedString) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\n\"float radius\" 1\nWorldEnd"),
              "t.pbrt:2:7: unterminated string");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere"), "t.pbrt:2:7: unterminated string");
}

TEST(ParserErrors, UnbalancedBrackets) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"float radius\" [1\nWorldEnd"),
              "t.pbrt:2:31: unbalanced '[': no matching ']' before WorldEnd");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"float radius\" [1"),
              "t.pbrt:2:31: unbalanced '[': no matching ']' before end of file");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\" \"float radius\" 1]\nWorldEnd"), "t.pbrt:2:32: unbalanced ']'");
}

TEST(ParserErrors, BlockMismatches) {
    EXPECT_EQ(ErrorOf("WorldBegin\nAttributeEnd\nWorldEnd"),
              "t.pbrt:2:1: AttributeEnd without matching AttributeBegin");
    EXPECT_EQ(ErrorOf("WorldBegin\n TransformEnd\nWorldEnd"),
              "t.pbrt:2:2: TransformEnd without matching TransformBegin");
    EXPECT_EQ(ErrorOf("WorldBegin\nTransformBegin\nAttributeEnd\nWorldEnd"),
              "t.pbrt:3:1: AttributeEnd does not match TransformBegin at t.pbrt:2:1");
    EXPECT_EQ(ErrorOf("WorldBegin\nAttributeBegin\nWorldEnd"),
              "t.pbrt:3:1: WorldEnd inside the AttributeBegin block opened at t.pbrt:2:1");
}

TEST(ParserErrors, DirectivesInTheWrongBlock) {
    EXPECT_EQ(ErrorOf("Shape \"sphere\"\nWorldBegin\nWorldEnd"), "t.pbrt:1:1: Shape is not allowed before WorldBegin");
    EXPECT_EQ(ErrorOf("AttributeBegin\nWorldBegin\nWorldEnd"),
              "t.pbrt:1:1: AttributeBegin is not allowed before WorldBegin");
    EXPECT_EQ(ErrorOf("WorldBegin\nCamera \"perspective\"\nWorldEnd"),
              "t.pbrt:2:1: Camera is not allowed inside the world block (after WorldBegin)");
    EXPECT_EQ(ErrorOf("WorldBegin\n  Film \"image\"\nWorldEnd"),
              "t.pbrt:2:3: Film is not allowed inside the world block (after WorldBegin)");
    EXPECT_EQ(ErrorOf("WorldBegin\nWorldEnd\nShape \"sphere\""), "t.pbrt:3:1: Shape after WorldEnd");
    EXPECT_EQ(ErrorOf("WorldBegin\nWorldBegin\nWorldEnd"),
              "t.pbrt:2:1: WorldBegin is not allowed inside the world block (after WorldBegin)");
}

TEST(ParserErrors, UnknownNames) {
    EXPECT_EQ(ErrorOf("WorldBegin\nNamedMaterial \"gold\"\nWorldEnd"),
              "t.pbrt:2:15: NamedMaterial: unknown material \"gold\"");
    EXPECT_EQ(ErrorOf("WorldBegin\nCoordSysTransform \"nowhere\"\nWorldEnd"),
              "t.pbrt:2:19: unknown coordinate system \"nowhere\"");
    EXPECT_EQ(ErrorOf("WorldBegin\nMakeNamedMaterial \"m\" \"rgb Kd\" [1 1 1]\nWorldEnd"),
              "t.pbrt:2:1: MakeNamedMaterial \"m\" has no \"string type\" parameter");
}

TEST(ParserErrors, MissingWorldEnd) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"sphere\"\n"), "t.pbrt:3:1: missing WorldEnd at end of file");
    EXPECT_EQ(ErrorOf("Camera \"perspective\""),
              "t.pbrt:1:21: end of file before WorldBegin (missing WorldBegin/WorldEnd)");
}

TEST(ParserErrors, ParameterArity) {
    EXPECT_EQ(ErrorOf("WorldBegin\nMaterial \"matte\" \"rgb Kd\" [0.5 0.5]\nWorldEnd"),
              "t.pbrt:2:18: parameter \"rgb Kd\" needs 3 values per colour, got 2 values");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"m\" \"point P\" [0 0 0 1]\nWorldEnd"),
              "t.pbrt:2:11: parameter \"point P\" needs 3 values per item, got 4 values");
    EXPECT_EQ(ErrorOf("WorldBegin\nLightSource \"point\" \"blackbody I\" [6500]\nWorldEnd"),
              "t.pbrt:2:21: parameter \"blackbody I\" needs (temperature scale) pairs, got 1 value");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"float r\" []\nWorldEnd"),
              "t.pbrt:2:11: parameter \"float r\" has no values");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"float r\"\nWorldEnd"),
              "t.pbrt:2:11: parameter \"float r\" has no value");
}

TEST(ParserErrors, WrongValueKinds) {
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"float r\" \"big\"\nWorldEnd"),
              "t.pbrt:2:21: parameter \"float r\" expects numbers, got string \"big\"");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"string f\" [abc]\nWorldEnd"),
              "t.pbrt:2:23: parameter \"string f\" expects quoted strings, got 'abc'");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"bool b\" \"yes\"\nWorldEnd"),
              "t.pbrt:2:20: parameter \"bool b\" expects true or false, got string \"yes\"");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape \"s\" \"float\" 1\nWorldEnd"),
              "t.pbrt:2:11: malformed parameter declaration \"float\" (expected \"type name\")");
}

TEST(ParserErrors, DirectiveArguments) {
    EXPECT_EQ(ErrorOf("Translate 1 2\nWorldBegin\nWorldEnd"),
              "t.pbrt:2:1: Translate expects 3 numbers, got 'WorldBegin'");
    EXPECT_EQ(ErrorOf("WorldBegin\nShape 1\nWorldEnd"), "t.pbrt:2:7: Shape expects a quoted shape type, got '1'");
    EXPECT_EQ(ErrorOf("ActiveTransform Sometimes\nWorldBegin\nWorldEnd"),
              "t.pbrt:1:17: ActiveTransform expects StartTime, EndTime or All, got 'Sometimes'");
    EXPECT_EQ(ErrorOf("WorldBegin\n\"float x\" 1\nWorldEnd"),
              "t.pbrt:2:1: unexpected string \"float x\" (expected a directive)");
    EXPECT_EQ(ErrorOf("LookAt 0 0 0  0 0 1  0 0 1\nWorldBegin\nWorldEnd").rfind("t.pbrt:1:1: LookAt: ", 0), 0u);
    EXPECT_EQ(ErrorOf("Scale 0 1 1\nWorldBegin\nWorldEnd").rfind("t.pbrt:1:1: Scale: ", 0), 0u);
    EXPECT_EQ(ErrorOf("WorldBegin\n Rotate 30 0 0 0\nWorldEnd"), "t.pbrt:2:2: Rotate: zero-length axis");
}

// Random byte mutations of a valid scene (fixed seed): parsing must either
// succeed or throw gradus::Error with a location, never crash or throw
// anything else.
TEST(ParserErrors, RandomMutationsOnlyThrowLocatedErrors) {
    const std::string seed = R"(LookAt 0 1 5 0 0 0 0 1 0
Camera "perspective" "float fov" [40]
Film "image" "integer xresolution" 32
WorldBegin
AttributeBegin
  AreaLightSource "diffuse" "blackbody L" [5000 2]
  Material "matte" "rgb Kd" [0.5 0.5 0.5] "spectrum Ks" [400 1 700 0.5]
  Translate 0 1 0
  Shape "trianglemesh" "point P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2]
AttributeEnd
ObjectBegin "o"
  Shape "sphere" "float radius" 2
ObjectEnd
ObjectInstance "o"
WorldEnd
)";
    std::mt19937 rng(777);
    const char alphabet[] = "[]\"#\n 0123456789.-eAWS";
    int ok = 0, errors = 0;
    for (int iter = 0; iter < 3000; ++iter) {
        std::string s = seed;
        int nmut = 1 + rng() % 3;
        for (int k = 0; k < nmut && !s.empty(); ++k) {
            size_t p = rng() % s.size();
            switch (rng() % 3) {
                case 0: s[p] = alphabet[rng() % (sizeof(alphabet) - 1)]; break;
                case 1: s.erase(p, 1 + rng() % 6); break;
                default: s.insert(p, 1, alphabet[rng() % (sizeof(alphabet) - 1)]); break;
            }
        }
        try {
            ParseString(s, "m.pbrt", "/nonexistent");
            ++ok;
        } catch (const Error &e) {
            ASSERT_EQ(std::string(e.what()).rfind("m.pbrt:", 0), 0u) << e.what();
            ++errors;
        }
    }
    EXPECT_GT(ok, 0);
    EXPECT_GT(errors, 0);
}
