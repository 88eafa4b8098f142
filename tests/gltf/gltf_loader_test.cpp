// glTF loader on the files of make_gltf.py, checked on the SceneDesc (no
// material needed): world transforms against products computed here, instancing,
// decoded indices and attributes, strip/fan triangulation, camera, lights,
// defaults, MASK, the "gltfimage" textures against the glTF sampler rules, the
// lights built from the LightDescs, and the errors of malformed files.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <regex>

#include "gltf_test_util.h"
#include "job/job.h"
#include "textures/textures.h"

namespace gradus::gltftest {
namespace {

// ---------------------------------------------------------------- 4x4 matrices
using M4 = std::array<std::array<double, 4>, 4>;
M4 Identity() {
    M4 m{};
    for (int i = 0; i < 4; ++i) m[i][i] = 1;
    return m;
}
M4 Mul(const M4 &a, const M4 &b) {
    M4 r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) r[i][j] += a[i][k] * b[k][j];
    return r;
}
M4 ColumnMajor(const std::array<double, 16> &v) {
    M4 m{};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) m[r][c] = v[4 * c + r];
    return m;
}
// glTF TRS: T * R * S, R from the unit quaternion (x, y, z, w).
M4 TRS(const std::array<double, 3> &t, const std::array<double, 4> &q, const std::array<double, 3> &s) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                            {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                            {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    M4 m = Identity();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m[r][c] = R[r][c] * s[c];
        m[r][3] = t[r];
    }
    return m;
}
void ExpectMatrix(const Transform &t, const M4 &e, const std::string &what) {
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(t.matrix().m[r][c], e[r][c], 1e-12) << what << " [" << r << "][" << c << "]";
}

TEST(GltfLoader, NestedNodeTransformsAreProductsOfMatrixAndTrs) {
    SceneDesc d = Load("hierarchy.gltf");
    ASSERT_EQ(d.shapes.size(), 4u);  // mesh i on node A, B, C, D
    const M4 A = ColumnMajor({0, 0, -2, 0, 0, 3, 0, 0, 1, 0, 0, 0, 5, -1, 2, 1});
    const M4 B = TRS({1, 2, 3}, {0, 0, std::sin(0.35), std::cos(0.35)}, {2, 0.5, 1.5});
    const M4 C = TRS({-0.5, 0.25, 4}, {0.5, 0.5, 0.5, 0.5}, {1, -2, 1});
    const M4 D = ColumnMajor({0, 1.5, 0, 0, -1, 0, 0, 0, 0, 0, 0.5, 0, 0, 7, 0, 1});
    ExpectMatrix(d.shapes[0].worldFromObject, A, "A");
    ExpectMatrix(d.shapes[1].worldFromObject, Mul(A, B), "A B");
    ExpectMatrix(d.shapes[2].worldFromObject, Mul(Mul(A, B), C), "A B C");
    ExpectMatrix(d.shapes[3].worldFromObject, Mul(Mul(A, B), D), "A B D");
    EXPECT_TRUE(d.shapes[2].worldFromObject.swapsHandedness());  // C scales y by -2
    EXPECT_FALSE(d.shapes[3].worldFromObject.swapsHandedness());
}

TEST(GltfLoader, MeshOfThreeNodesIsOneInstanceUsedThreeTimes) {
    SceneDesc d = Load("instancing.gltf");
    EXPECT_TRUE(d.shapes.empty());
    ASSERT_EQ(d.instances.size(), 1u);
    const InstanceDesc &inst = d.instances.begin()->second;
    EXPECT_EQ(inst.shapes.size(), 1u);
    ASSERT_EQ(d.instanceUses.size(), 3u);
    const double t[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, -1}};
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(d.instanceUses[i].name, inst.name);
        M4 e = Identity();
        for (int k = 0; k < 3; ++k) e[k][3] = t[i][k];
        ExpectMatrix(d.instanceUses[i].worldFromInstance, e, "use " + std::to_string(i));
    }
}

TEST(GltfLoader, IndicesDecodeExactlyForEveryIndexType) {
    SceneDesc d = Load("indices.gltf");
    ASSERT_EQ(d.shapes.size(), 4u);
    // Mesh 0: not indexed (6 vertices).
    std::vector<double> seq = {0, 1, 2, 3, 4, 5};
    EXPECT_EQ(Numbers(d.shapes[0].params, "indices"), seq);
    EXPECT_EQ(Numbers(d.shapes[0].params, "P"), (std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1, 2, 1, 1, 1, 2, 1}));
    // Meshes 1-3: u8, u16, u32 indices.
    for (int m = 1; m <= 3; ++m) {
        SCOPED_TRACE("mesh " + std::to_string(m));
        EXPECT_EQ(Numbers(d.shapes[m].params, "indices"), (std::vector<double>{0, 1, 2, 0, 2, 3, 3, 2, 4}));
        EXPECT_EQ(Numbers(d.shapes[m].params, "P"), (std::vector<double>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 2, 0}));
        EXPECT_EQ(d.shapes[m].type, "trianglemesh");
    }
}

TEST(GltfLoader, QuantizedAttributesDecodeAsTheSpecSays) {
    SceneDesc d = Load("quantized.gltf");
    ASSERT_EQ(d.shapes.size(), 2u);
    // POSITION as plain i16 integers.
    EXPECT_EQ(Numbers(d.shapes[0].params, "P"), (std::vector<double>{0, 0, 0, 1000, 0, 0, 0, -1000, 300}));
    // NORMAL as normalized i8: max(c / 127, -1) (-128 -> -1).
    EXPECT_EQ(Numbers(d.shapes[0].params, "N"), (std::vector<double>{0, 0, 1, 0, -1, 0, -1, 0, 0}));
    // TEXCOORD_0 as normalized u16: c / 65535.
    std::vector<double> uv = Numbers(d.shapes[0].params, "uv");
    const double q[6] = {0, 0, 65535, 0, 32768, 65535};
    ASSERT_EQ(uv.size(), 6u);
    for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(uv[i], q[i] / 65535.0) << i;
    // Mesh 1: POSITION as normalized u8: c / 255.
    std::vector<double> p = Numbers(d.shapes[1].params, "P");
    const double q2[9] = {0, 0, 0, 255, 0, 0, 0, 51, 255};
    ASSERT_EQ(p.size(), 9u);
    for (int i = 0; i < 9; ++i) EXPECT_DOUBLE_EQ(p[i], q2[i] / 255.0) << i;
}

TEST(GltfLoader, SparseAccessorsSubstituteTheirValues) {
    SceneDesc d = Load("sparse.gltf");
    ASSERT_EQ(d.shapes.size(), 2u);
    std::vector<double> e = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 2, 0, 3, 3, 0};
    const int idx[2] = {1, 4};
    const double val[6] = {5, 0, 0, -1, -2, 0.5};
    for (int k = 0; k < 2; ++k)
        for (int c = 0; c < 3; ++c) e[3 * idx[k] + c] = val[3 * k + c];
    EXPECT_EQ(Numbers(d.shapes[0].params, "P"), e);
    // No bufferView: zeros, then the sparse values at elements 1 and 2.
    EXPECT_EQ(Numbers(d.shapes[1].params, "P"), (std::vector<double>{0, 0, 0, 0, 0, 1, 0, 1, 1}));
}

// Triangles equal up to a cyclic rotation (same winding).
bool SameTriangle(const std::vector<double> &t, size_t i, const std::array<int, 3> &e) {
    for (int r = 0; r < 3; ++r)
        if (t[i] == e[r] && t[i + 1] == e[(r + 1) % 3] && t[i + 2] == e[(r + 2) % 3]) return true;
    return false;
}

TEST(GltfLoader, StripsAndFansTriangulateAsTheSpecSays) {
    SceneDesc d = Load("strip_fan.gltf");
    ASSERT_EQ(d.shapes.size(), 2u);
    // glTF 2.0 3.7.2.1: strip triangle i = (v_i, v_{i+(1+i%2)}, v_{i+(2-i%2)});
    // fan triangle i = (v_{i+1}, v_{i+2}, v_0).
    std::vector<double> strip = Numbers(d.shapes[0].params, "indices");
    ASSERT_EQ(strip.size(), 3u * 4);
    for (int i = 0; i < 4; ++i)
        EXPECT_TRUE(SameTriangle(strip, 3 * i, {i, i + 1 + i % 2, i + 2 - i % 2})) << "strip triangle " << i;
    std::vector<double> fan = Numbers(d.shapes[1].params, "indices");
    ASSERT_EQ(fan.size(), 3u * 3);
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(SameTriangle(fan, 3 * i, {i + 1, i + 2, 0})) << "fan triangle " << i;
}

TEST(GltfLoader, CornellBoxStructure) {
    SceneDesc d = Load("cornell.gltf");
    // Walls (3 primitives) and the light are world shapes; the cube is one instance of two nodes.
    EXPECT_EQ(d.shapes.size(), 4u);
    ASSERT_EQ(d.instances.size(), 1u);
    ASSERT_EQ(d.instanceUses.size(), 2u);
    const M4 mirror = TRS({0, 0, 0}, {0, 0, 0, 1}, {-1, 1, 1});
    const double boxT[2][3] = {{-0.35, 0.6, -0.3}, {0.35, 0.3, 0.3}}, boxDeg[2] = {18, -17};
    const double boxS[2][3] = {{0.55, 1.2, 0.55}, {0.6, 0.6, 0.6}};
    for (int i = 0; i < 2; ++i) {
        double h = boxDeg[i] * Pi / 360;
        M4 e = Mul(mirror, TRS({boxT[i][0], boxT[i][1], boxT[i][2]}, {0, std::sin(h), 0, std::cos(h)},
                               {boxS[i][0], boxS[i][1], boxS[i][2]}));
        ExpectMatrix(d.instanceUses[i].worldFromInstance, e, "box " + std::to_string(i));
        EXPECT_TRUE(d.instanceUses[i].worldFromInstance.swapsHandedness());
    }
    // The builder places the cube's one stored mesh twice (Embree instances).
    auto scene = BuildScene(d, Point2i{16, 16});
    EXPECT_EQ(scene->features.numInstances, 2);
    EXPECT_EQ(scene->features.numInstancedTriangles, 2 * 12);
    int emitters = 0;
    for (const auto &s : d.shapes) {
        ExpectMatrix(s.worldFromObject, mirror, "wall/light");
        if (s.areaLight < 0) continue;
        ++emitters;
        const EntityDesc &al = d.areaLights.at(s.areaLight);
        EXPECT_EQ(al.type, "diffuse");
        std::vector<double> L = Numbers(al.params, "L");
        ASSERT_EQ(L.size(), 3u);
        EXPECT_NEAR(L[0], 14, 1e-12);
        EXPECT_NEAR(L[1], 11, 1e-12);
        EXPECT_NEAR(L[2], 7, 1e-12);
    }
    EXPECT_EQ(emitters, 1);
    EXPECT_EQ(d.materials.size(), 5u);  // four and the default
    for (const auto &m : d.materials) EXPECT_EQ(m.type, "gltfpbr");
    EXPECT_EQ(Numbers(d.materials[1].params, "basecolor"), (std::vector<double>{0.62, 0.07, 0.05}));
    EXPECT_EQ(Numbers(d.materials[1].params, "metallic"), std::vector<double>{0});
    EXPECT_EQ(Numbers(d.materials[1].params, "roughness"), std::vector<double>{1});
    // No punctual light: the default environment besides the emitter, said in a
    // note; off on request (gradus --envmap none).
    ASSERT_EQ(d.lights.size(), 1u);
    EXPECT_EQ(d.lights[0].type, "infinite");
    bool noted = false;
    for (const auto &n : d.notes)
        noted |= n.find("uniform white environment lights the scene besides its emissive surfaces") != std::string::npos;
    EXPECT_TRUE(noted);
    EXPECT_TRUE(Load("cornell.gltf", "", false).lights.empty());
}

TEST(GltfLoader, CameraTransformAndYfov) {
    for (const char *file : {"cornell.gltf", "cornell.glb"}) {
        SCOPED_TRACE(file);
        SceneDesc d = Load(file);
        ASSERT_TRUE(d.camera.present);
        EXPECT_EQ(d.camera.type, "perspective");
        std::vector<double> fov = Numbers(d.camera.params, "yfov");
        ASSERT_EQ(fov.size(), 1u);
        EXPECT_NEAR(fov[0], 38, 1e-12);
        // Camera node at (0, 1, 3.6), looking down glTF's -Z: Gradus camera space
        // (+Z forward, +X right, +Y up) of world p is (p.x, p.y - 1, 3.6 - p.z).
        for (const Point3 &p : {Point3(0, 0, 0), Point3(1, 2, -1), Point3(-0.3, 0.7, 2)}) {
            Point3 c = d.camera.cameraFromWorld.applyPoint(p);
            EXPECT_NEAR(c.x, p.x, 1e-12);
            EXPECT_NEAR(c.y, p.y - 1, 1e-12);
            EXPECT_NEAR(c.z, 3.6 - p.z, 1e-12);
        }
        // Film: aspectRatio 1 -> 480 x 480, named after the file.
        EXPECT_EQ(Numbers(d.film.params, "xresolution"), std::vector<double>{480});
        EXPECT_EQ(Numbers(d.film.params, "yresolution"), std::vector<double>{480});
        EXPECT_EQ(String(d.film.params, "filename"), "cornell.exr");
    }
    // By name (camera or node), and an unknown name lists the cameras.
    EXPECT_TRUE(Load("cornell.gltf", "view").camera.present);
    EXPECT_TRUE(Load("cornell.gltf", "camera").camera.present);
    try {
        Load("cornell.gltf", "nope");
        ADD_FAILURE() << "no error for an unknown camera";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("no camera named \"nope\" (cameras: view)"), std::string::npos) << e.what();
    }
}

TEST(GltfLoader, PunctualLightDescs) {
    SceneDesc d = Load("lights.gltf");
    ASSERT_EQ(d.lights.size(), 3u);  // no default environment
    EXPECT_EQ(d.lights[0].type, "point");
    EXPECT_EQ(d.lights[1].type, "spot");
    EXPECT_EQ(d.lights[2].type, "distant");
    auto scaled = [](double s) { return std::vector<double>{kColor[0] * s, kColor[1] * s, kColor[2] * s}; };
    EXPECT_EQ(Numbers(d.lights[0].params, "I"), scaled(kPointI));
    EXPECT_EQ(Numbers(d.lights[1].params, "I"), scaled(kSpotI));
    EXPECT_EQ(Numbers(d.lights[2].params, "L"), scaled(kDirI));
    EXPECT_NEAR(Numbers(d.lights[1].params, "coneangle").at(0), kSpotOuter * 180 / Pi, 1e-12);
    EXPECT_NEAR(Numbers(d.lights[1].params, "conedeltaangle").at(0), (kSpotOuter - kSpotInner) * 180 / Pi, 1e-12);
    EXPECT_EQ(String(d.lights[1].params, "falloff"), "gltf");
    Point3 at = d.lights[0].worldFromLight.applyPoint(Point3(0, 0, 0));
    EXPECT_NEAR(at.y, 2, 1e-12);
    // Lights only: the default camera is said in a note.
    ASSERT_TRUE(d.camera.present);
    bool noted = false;
    for (const auto &n : d.notes) noted |= n.find("no camera in the file") != std::string::npos;
    EXPECT_TRUE(noted);
}

TEST(GltfLoader, PunctualLightValuesFromTheirDescs) {
    SceneDesc d = Load("lights.gltf");
    std::vector<std::shared_ptr<Light>> owned;
    std::vector<const Light *> lights;
    Bounds3 b;
    b.expand(Point3(-10, -10, -10));
    b.expand(Point3(10, 10, 10));
    for (const auto &ld : d.lights) {
        owned.push_back(CreateLight(ld, d));
        owned.back()->preprocess(b);
        lights.push_back(owned.back().get());
    }
    CheckPunctualLights(lights);
}

TEST(GltfLoader, FileWithoutCameraAndLightsGetsDefaultsAndNotes) {
    SceneDesc d = Load("defaults.gltf");
    ASSERT_EQ(d.lights.size(), 1u);
    EXPECT_EQ(d.lights[0].type, "infinite");
    EXPECT_TRUE(d.camera.present);
    EXPECT_EQ(Numbers(d.camera.params, "yfov"), std::vector<double>{45});
    EXPECT_EQ(Numbers(d.film.params, "xresolution"), std::vector<double>{640});
    EXPECT_EQ(Numbers(d.film.params, "yresolution"), std::vector<double>{480});
    EXPECT_EQ(String(d.film.params, "filename"), "defaults.exr");
    bool cam = false, env = false;
    for (const auto &n : d.notes) {
        cam |= n.find("defaults.gltf") != std::string::npos && n.find("default camera") != std::string::npos;
        env |= n.find("uniform white environment") != std::string::npos;
    }
    EXPECT_TRUE(cam);
    EXPECT_TRUE(env);
    // The default camera looks at the triangle (its centre projects to the image centre).
    Point3 c = d.camera.cameraFromWorld.applyPoint(Point3(0.5, 0.5, 0));
    EXPECT_NEAR(c.x, 0, 1e-9);
    EXPECT_NEAR(c.y, 0, 1e-9);
    EXPECT_GT(c.z, 0);
}

// ---------------------------------------------------------------- textures
// texture.gltf's image (4x2, top row first) and samplers.
const int kTexels[2][4][4] = {{{255, 0, 0, 255}, {0, 255, 0, 128}, {0, 0, 255, 64}, {255, 255, 255, 0}},
                              {{10, 20, 30, 200}, {40, 50, 60, 100}, {70, 80, 90, 50}, {100, 110, 120, 25}}};
enum WrapMode { kRepeat, kClamp, kMirror };
struct SamplerCase {
    WrapMode s, t;
    bool nearest;
};
const SamplerCase kSamplers[5] = {{kRepeat, kRepeat, true}, {kClamp, kClamp, false}, {kMirror, kMirror, false},
                                  {kRepeat, kClamp, false}, {kMirror, kRepeat, true}};

// OpenGL 4.6, 8.14.2 (which glTF's wrap modes name).
int Wrap(int i, int n, WrapMode w) {
    auto mod = [](int a, int m) { return ((a % m) + m) % m; };
    if (w == kRepeat) return mod(i, n);
    if (w == kClamp) return std::clamp(i, 0, n - 1);
    auto mirror = [](int a) { return a >= 0 ? a : -(1 + a); };
    return (n - 1) - mirror(mod(i, 2 * n) - n);
}
double SrgbDecode(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// Texel channel c (rgb decoded from sRGB, alpha linear) filtered at (u, v).
double Expected(const SamplerCase &s, double u, double v, int c) {
    auto texel = [&](int x, int y) {
        double code = kTexels[Wrap(y, 2, s.t)][Wrap(x, 4, s.s)][c] / 255.0;
        return c == 3 ? code : SrgbDecode(code);
    };
    if (s.nearest) return texel(int(std::floor(u * 4)), int(std::floor(v * 2)));
    double x = u * 4 - 0.5, y = v * 2 - 0.5;
    int x0 = int(std::floor(x)), y0 = int(std::floor(y));
    double fx = x - x0, fy = y - y0;
    return (1 - fx) * (1 - fy) * texel(x0, y0) + fx * (1 - fy) * texel(x0 + 1, y0) +
           (1 - fx) * fy * texel(x0, y0 + 1) + fx * fy * texel(x0 + 1, y0 + 1);
}

const TextureDesc *FindTexture(const SceneDesc &d, const std::string &suffix) {
    for (const auto &t : d.textures)
        if (t.name.size() >= suffix.size() && t.name.compare(t.name.size() - suffix.size(), suffix.size(), suffix) == 0)
            return &t;
    return nullptr;
}

TEST(GltfTextures, WrapModesFiltersAndTextureTransform) {
    SceneDesc d = Load("texture.gltf");
    const double uvs[][2] = {{0.1, 0.2},  {0.3, 0.75}, {1.3, -0.4}, {-0.7, 2.2}, {0.99, 0.01},
                             {2.6, 1.4},  {-1.1, -0.3}, {0.5, 0.5}, {0.125, 0.25}, {-2.4, 3.9}};
    for (int m = 0; m < 5; ++m) {
        const std::string name = "/materials/" + std::to_string(m) + "/pbrMetallicRoughness/baseColorTexture:rgb";
        const TextureDesc *td = FindTexture(d, name);
        ASSERT_NE(td, nullptr) << name;
        EXPECT_EQ(td->type, "gltfimage");
        auto tex = MakeSpectrumTexture(*td, d, NamedTextures());
        for (const auto &uv : uvs) {
            double u = uv[0], v = uv[1];
            if (m == 3) {  // KHR_texture_transform: T(offset) R(rotation) S(scale), GLSL column-major
                const double ox = 0.25, oy = -0.5, r = 0.3, sx = 2, sy = 0.5;
                double su = sx * u, sv = sy * v;
                u = std::cos(r) * su - std::sin(r) * sv + ox;
                v = std::sin(r) * su + std::cos(r) * sv + oy;
            }
            SurfaceInteraction si;
            si.uv = Point2(uv[0], uv[1]);
            Spectrum got = tex->evaluate(si);
            const double factor[3] = {m == 4 ? 0.5 : 1, m == 4 ? 0.25 : 1, 1};
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], factor[c] * Expected(kSamplers[m], u, v, c), 2e-6)
                    << "material " << m << " uv (" << uv[0] << ", " << uv[1] << ") channel " << c;
        }
    }
}

TEST(GltfTextures, AlphaMaskBecomesACutoffAlphaTexture) {
    SceneDesc d = Load("mask.gltf");
    ASSERT_EQ(d.shapes.size(), 3u);
    // Material 0: MASK with a texture: "texture alpha" reading channel a with cutoff 0.4.
    const Param *alpha = Find(d.shapes[0].params, "alpha");
    ASSERT_NE(alpha, nullptr);
    ASSERT_EQ(alpha->type, "texture");
    const TextureDesc *td = nullptr;
    for (const auto &t : d.textures)
        if (t.name == alpha->strings.at(0)) td = &t;
    ASSERT_NE(td, nullptr);
    EXPECT_EQ(td->valueType, "float");
    EXPECT_EQ(String(td->params, "channel"), "a");
    EXPECT_NEAR(Numbers(td->params, "cutoff").at(0), 0.4, 1e-12);
    auto tex = MakeFloatTexture(*td, d, NamedTextures());
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {  // at texel centres: 1 where alpha >= 0.4, else 0
            SurfaceInteraction si;
            si.uv = Point2((x + 0.5) / 4, (y + 0.5) / 2);
            EXPECT_EQ(tex->evaluate(si), kTexels[y][x][3] / 255.0 >= 0.4 ? 1.0 : 0.0) << x << "," << y;
        }
    // Material 1: MASK, constant alpha 0.2 below the default cutoff 0.5: cut away.
    const Param *a1 = Find(d.shapes[1].params, "alpha");
    ASSERT_NE(a1, nullptr);
    EXPECT_EQ(a1->type, "float");
    EXPECT_EQ(a1->numbers, std::vector<double>{0});
    // Material 2: BLEND, rendered opaque, with a note.
    EXPECT_EQ(Find(d.shapes[2].params, "alpha"), nullptr);
    bool noted = false;
    for (const auto &n : d.notes) noted |= n.find("BLEND") != std::string::npos;
    EXPECT_TRUE(noted);
}

TEST(GltfLoader, GltfAssetDirectivePlacesTheAsset) {
    SceneDesc d = ParseString("WorldBegin\nAttributeBegin\nTranslate 0 5 0\nGltfAsset \"cornell.gltf\"\nAttributeEnd\nWorldEnd\n",
                              "asset.pbrt", GLTF_TEST_DATA);
    ASSERT_EQ(d.shapes.size(), 4u);
    M4 e = TRS({0, 5, 0}, {0, 0, 0, 1}, {-1, 1, 1});
    for (const auto &s : d.shapes) ExpectMatrix(s.worldFromObject, e, "asset shape");
    EXPECT_FALSE(d.camera.present);  // the asset's camera is used only when named
}

// ---------------------------------------------------------------- malformed files
// Loads `file`, expecting gradus::Error; returns its message ("" if none).
std::string ErrorOf(const std::string &file) {
    try {
        Load(file);
    } catch (const Error &e) {
        return e.what();
    } catch (const std::exception &e) {
        ADD_FAILURE() << file << ": not a gradus::Error: " << e.what();
        return "";
    }
    ADD_FAILURE() << file << ": loaded without error";
    return "";
}

// "line:col" of the first occurrence of `needle` after the first of `after` in `file`.
std::string LineColOf(const std::string &file, const std::string &needle, const std::string &after = "") {
    std::string text = ReadText(Data(file));
    size_t from = after.empty() ? 0 : text.find(after);
    size_t at = text.find(needle, from == std::string::npos ? 0 : from);
    if (at == std::string::npos) return "?";
    int line = 1 + int(std::count(text.begin(), text.begin() + at, '\n'));
    size_t bol = text.rfind('\n', at);
    int col = int(at - (bol == std::string::npos ? 0 : bol + 1)) + 1;
    return std::to_string(line) + ":" + std::to_string(col);
}

struct Malformed {
    std::string file;
    std::string where;                // expected "line:col" after the file name ("" = any)
    std::vector<std::string> says;    // substrings of the message
};

void PrintTo(const Malformed &m, std::ostream *os) { *os << m.file; }

class GltfMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(GltfMalformed, GivesALocatedError) {
    const Malformed &m = GetParam();
    std::string msg = ErrorOf(m.file);
    SCOPED_TRACE(msg);
    // "<path>/<file>[ (JSON chunk)]:line:col: message"
    const std::string path = Data(m.file);
    ASSERT_EQ(msg.rfind(path, 0), 0u) << "the message does not start with the file";
    std::smatch lc;
    std::string rest = msg.substr(path.size());
    ASSERT_TRUE(std::regex_search(rest, lc, std::regex("^( \\(JSON chunk\\))?:([0-9]+):([0-9]+): ")))
        << "no line:col after the file name";
    if (!m.where.empty()) {
        EXPECT_EQ(lc[2].str() + ":" + lc[3].str(), m.where);
    }
    for (const auto &s : m.says) EXPECT_NE(msg.find(s), std::string::npos) << "missing \"" << s << "\"";
}

std::vector<Malformed> MalformedCases() {
    // The line of bad-json.gltf's trailing comma, as nlohmann::json reports it.
    std::string jsonLine = LineColOf("bad-json.gltf", "\"mesh\": 0, }");
    jsonLine = jsonLine.substr(0, jsonLine.find(':'));
    return {
        {"bad-length.glb", "", {".glb header says", "the file has", "truncated"}},
        {"bad-cut-json.glb", "", {"JSON chunk runs past the end of the file"}},
        {"bad-cut-bin.glb", "", {"BIN chunk", "runs past the end of the file"}},
        {"bad-count.gltf", LineColOf("bad-count.gltf", "{", "\"accessors\""),
         {"accessor needs 12000 bytes of buffer view 0, which has 36", "(at /accessors/0)"}},
        {"bad-componenttype.gltf", LineColOf("bad-componenttype.gltf", "5130"),
         {"invalid componentType 5130", "(at /accessors/0/componentType)"}},
        {"bad-type.gltf", LineColOf("bad-type.gltf", "\"VEC2\""),
         {"wrong type", "POSITION", "(at /accessors/0/type)"}},
        {"bad-index.gltf", "", {"index 7 (element 1) is out of range: POSITION has 3 vertices", "/indices"}},
        {"bad-missing-buffer.gltf", "", {"missing-buffer.bin", "not found"}},
        {"bad-extension.gltf", LineColOf("bad-extension.gltf", "\"EXT_not_a_real_extension\"", "extensionsRequired"),
         {"required extension \"EXT_not_a_real_extension\" is not supported", "(at /extensionsRequired/0)"}},
        {"bad-cycle.gltf", "", {"node 0 is reached twice", "tree", "(at /nodes/1/children/0)"}},
        {"bad-json.gltf", "", {"not a valid glTF 2.0 file", "parse error", "line " + jsonLine}},
        {"does-not-exist.gltf", "", {"cannot open"}},
    };
}

INSTANTIATE_TEST_SUITE_P(Files, GltfMalformed, ::testing::ValuesIn(MalformedCases()),
                         [](const ::testing::TestParamInfo<Malformed> &info) {
                             std::string s = info.param.file;
                             for (char &c : s)
                                 if (!std::isalnum((unsigned char)c)) c = '_';
                             return s;
                         });

}  // namespace
}  // namespace gradus::gltftest

// scenes/cornell-box.glb is the generator's cornell.glb, kept in the project
// for users: it must not drift from what make_gltf.py writes.
TEST(GltfScenes, ShippedCornellBoxIsTheGeneratorsOutput) {
    using namespace gradus::gltftest;
    const std::string shipped = ReadText(std::string(GRADUS_SOURCE_DIR) + "/scenes/cornell-box.glb");
    const std::string generated = ReadText(Data("cornell.glb"));
    ASSERT_FALSE(generated.empty());
    EXPECT_TRUE(shipped == generated) << "regenerate it: python3 tests/gltf/make_gltf.py DIR && cp DIR/cornell.glb scenes/cornell-box.glb";
}
