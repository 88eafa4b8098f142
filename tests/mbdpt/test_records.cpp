// Connection records (common/connection_record.h): a matrix connection from a
// light record and the row's camera sums gives ConnectBDPT's result (value
// and O(n) MIS weight of MISWeight) on random pairs of independent subpaths:
// Lambertian (compact), glossy and medium (stored) light endpoints, shading
// normals, a delta light, both heuristics; and the next-event connections
// through the matrix (ConnectLightOrigin).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "bdpt/bdpt_test_util.h"
#include "integrators/common/bidir.h"
#include "integrators/common/connection_record.h"
#include "job/job.h"
#include "lights/light_sampler.h"
#include "parser/scene_desc.h"

namespace gradus {
namespace {

enum class Variant { Area, PointLight, Media };

std::string RecordsScene(Variant v) {
    using namespace bdpt_test;
    std::string objects =
        Sphere("Material \"mirror\"", 0.5, 0.35, 0.3, 0.3) +
        Sphere("Material \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] \"rgb Ks\" [0.5 0.5 0.5] \"float roughness\" [0.1]",
               -0.4, 0.5, -0.2, 0.45) +
        Sphere("Material \"matte\" \"rgb Kd\" [0.5 0.6 0.3]", 0.1, 0.3, -0.5, 0.25);
    std::string camera = "Camera \"perspective\" \"float fov\" [40]", lights = CeilingLight(0.3, 10);
    if (v == Variant::PointLight) lights += "LightSource \"point\" \"point from\" [0.3 1.2 0.2] \"rgb I\" [2 2 2]\n";
    if (v == Variant::Media) {
        camera = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [0.1 0.1 0.1] "
                 "\"rgb sigma_s\" [0.8 0.7 0.6] \"float g\" [0.4]\nMediumInterface \"\" \"fog\"\n" + camera;
        lights = "MediumInterface \"fog\" \"fog\"\n" + lights;
    }
    return BoxScene("bdpt", lights, objects, 16, camera, /*floorNormals=*/true);
}

struct Counts {
    int compared = 0, lambertian = 0, stored = 0, medium = 0, pointLight = 0, maxT = 0, maxS = 0;
};

// Random pairs of independent subpaths of the variant's scene: sample i's
// camera subpath and the light subpath of another sample (a matrix
// connection pairs independent subpaths).
struct SubpathPairs {
    static constexpr int kMaxDepth = 7;
    SubpathPairs(Variant variant, MISHeuristic h)
        : job(BuildJob(variant)), ls(job.scene->lights, "power", FileLoc()), sampler(job.sampler->clone()),
          media(variant == Variant::Media), cv(kMaxDepth + 2), lv(kMaxDepth + 1), cb(kMaxDepth + 2), lb(kMaxDepth + 1) {
        ctx.init(*job.scene, ls, h);
    }
    static RenderJob BuildJob(Variant variant) {
        BuildOptions bo;
        bo.quiet = true;
        return BuildRenderJob(ParseString(RecordsScene(variant)), bo);
    }
    void generate(int i) {
        arena.reset();
        sampler->startPixelSample({i % 16, (i / 16) % 16}, i / 256);
        CameraSample cs;
        Point2 u = sampler->get2D();
        cs.pFilm = Point2(i % 16 + u.x, (i / 16) % 16 + u.y);
        cs.pLens = sampler->get2D();
        Ray ray;
        job.scene->camera->generateRay(cs, &ray);
        RNG rng{uint64_t(i)};
        RNG *mrng = media ? &rng : nullptr;
        const int nC = GenerateCameraSubpath(ctx, ray, *sampler, arena, kMaxDepth + 2, cv.data(), cb.data(), mrng);
        sampler->startPixelSample({(i * 7 + 3) % 16, (i * 5 + 1) % 16}, 100 + i);
        const int nL = GenerateLightSubpath(ctx, *sampler, arena, kMaxDepth + 1, lv.data(), lb.data(), mrng);
        cam = SubpathView{cv.data(), cb.data(), nC};
        light = SubpathView{lv.data(), lb.data(), nL};
    }
    RenderJob job;
    LightSampler ls;
    BidirContext ctx;
    std::unique_ptr<Sampler> sampler;
    const bool media;
    std::vector<PathVertex> cv, lv;
    std::vector<BSDF> cb, lb;
    Arena arena;
    SubpathView cam, light;
};

void CheckRecords(Variant variant, MISHeuristic h) {
    SubpathPairs pairs(variant, h);
    const BidirContext &ctx = pairs.ctx;
    const bool media = pairs.media;
    const int maxDepth = SubpathPairs::kMaxDepth;
    std::vector<PathVertex> &lv = pairs.lv, &cv = pairs.cv;
    std::vector<BSDF> &lb = pairs.lb;
    std::vector<LightRecord> recs(maxDepth + 1);
    CameraSums sums;
    Counts n;
    for (int i = 0; i < 1200; ++i) {
        pairs.generate(i);
        const SubpathView cam = pairs.cam, light = pairs.light;
        const int nC = cam.n, nL = light.n;
        BuildLightRecords(ctx, light, 1000, recs.data());
        sums.build(ctx, cam);
        for (int t = 2; t <= nC; ++t)
            for (int s = 2; s <= nL && s + t - 2 <= maxDepth; ++s) {
                ConnectSamples cu;
                cu.knownVisible = true;  // the same edge for both: no shadow ray
                ConnectResult ref, got;
                const bool okRef = ConnectBDPT(ctx, light, cam, s, t, cu, &ref);
                const LightRecord &r = recs[s - 1];
                if (r.kind == RecordKind::Stored) {
                    EXPECT_EQ(r.vertex, 1000u + uint32_t(s - 1));
                }
                const bool okGot = ConnectRecord(ctx, r, &lv[s - 1], &lb[s - 1], sums, cam, s, t, cu, &got);
                ASSERT_EQ(okRef, okGot) << "s=" << s << " t=" << t << " sample " << i;
                if (!okRef) continue;
                ++n.compared;
                n.lambertian += r.kind == RecordKind::Lambertian;
                n.stored += r.kind == RecordKind::Stored;
                n.medium += lv[s - 1].inMedium() || cv[t - 1].inMedium();
                n.pointLight += lv[0].isDeltaLight();
                n.maxT = std::max(n.maxT, t);
                n.maxS = std::max(n.maxS, s);
                EXPECT_NEAR(got.weight, ref.weight, 1e-6 * ref.weight) << "s=" << s << " t=" << t << " sample " << i;
                for (int c = 0; c < 3; ++c) {
                    const double a = ref.unweighted[c], b = got.unweighted[c];
                    EXPECT_NEAR(b, a, 1e-5 * std::abs(a) + 1e-30) << "channel " << c << " s=" << s << " t=" << t;
                }
            }
    }
    EXPECT_GE(n.compared, 3000);
    EXPECT_GE(n.lambertian, 1000);
    EXPECT_GE(n.stored, 100);  // the plastic sphere (and medium vertices)
    EXPECT_GE(n.maxT, 6);
    EXPECT_GE(n.maxS, 6);
    if (media) {
        EXPECT_GE(n.medium, 300);
    }
    if (variant == Variant::PointLight) {
        EXPECT_GE(n.pointLight, 100);
    }
}

// Next-event estimation through the matrix (ConnectLightOrigin): camera
// vertex t - 1 connected to the emitter vertex of another sample's light
// subpath. Value against the estimator written out here (Veach 1997 Eq. 10.8:
// beta_t f_t Le G / (pmf p_pos), Le and the densities from the light itself,
// not from the stored vertex), weight against MISWeight's O(n) sums with the
// light subpath cut to its origin.
void CheckOrigins(Variant variant, MISHeuristic h) {
    SubpathPairs pairs(variant, h);
    const BidirContext &ctx = pairs.ctx;
    const LightSampler &ls = pairs.ls;
    const bool media = pairs.media;
    const int maxDepth = SubpathPairs::kMaxDepth;
    std::vector<PathVertex> &lv = pairs.lv, &cv = pairs.cv;
    std::vector<BSDF> &lb = pairs.lb, &cb = pairs.cb;
    CameraSums sums;
    int compared = 0, point = 0, area = 0, medium = 0, maxT = 0;
    for (int i = 0; i < 1200; ++i) {
        pairs.generate(i);
        const int nC = pairs.cam.n;
        if (pairs.light.n < 1) continue;
        const PathVertex &y0 = lv[0];
        ASSERT_TRUE(IsMatrixLightOrigin(y0));
        const SubpathView cam{cv.data(), cb.data(), nC}, origin{lv.data(), lb.data(), 1};
        sums.build(ctx, cam);
        for (int t = 2; t <= nC && t - 1 <= maxDepth; ++t) {
            ConnectSamples cu;
            cu.knownVisible = true;
            ConnectResult got;
            const bool ok = ConnectLightOrigin(ctx, y0, sums, cam, t, cu, &got);
            // The reference value.
            const PathVertex &pt = cv[t - 1];
            Spectrum ref(0);
            if (pt.type != VertexType::Light && pt.scatters() && IsConnectible(pt, &cb[t - 1]) &&
                EdgeConnectible(ctx, y0, pt)) {
                Vec3 d = y0.p - pt.p;  // towards the light
                const Float d2 = d.lengthSquared();
                d = d / std::sqrt(d2);
                const Float pmf = ls.pmf(y0.light);
                Spectrum Le;
                if (y0.isDeltaLight()) {
                    Le = Spectrum(2) / (d2 * pmf);  // the scene's point light: I = 2
                } else {
                    Float pdfPos, pdfDir;
                    y0.light->pdfLe(Ray(y0.p, -d), y0.ng, &pdfPos, &pdfDir);
                    Le = static_cast<const AreaLight *>(y0.light)->L(Interaction(y0.p, y0.ng, Vec3(0, 0, 0)), -d) *
                         (AbsDot(Vec3(y0.ng), d) / (d2 * pmf * pdfPos));
                }
                ref = pt.throughput() * EvalBSDF(pt, cb[t - 1], y0, TransportMode::Radiance) * Le * ScatterCos(pt, d);
            }
            const Float wRef = MISWeight(ctx, origin, cam, 1, t, nullptr);
            ASSERT_EQ(ok, !ref.isBlack() && wRef > 0) << "t=" << t << " sample " << i;
            if (!ok) continue;
            ++compared;
            point += y0.isDeltaLight();
            area += !y0.isDeltaLight();
            medium += pt.inMedium();
            maxT = std::max(maxT, t);
            EXPECT_NEAR(got.weight, wRef, 1e-6 * wRef) << "t=" << t << " sample " << i;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got.unweighted[c], ref[c], 1e-5 * std::abs(ref[c]) + 1e-30) << "channel " << c << " t=" << t;
        }
    }
    EXPECT_GE(compared, 1500);
    EXPECT_GE(area, 500);
    EXPECT_GE(maxT, 6);
    if (variant == Variant::PointLight) {
        EXPECT_GE(point, 300);
    }
    if (media) {
        EXPECT_GE(medium, 300);
    }
}

TEST(MBDPTRecords, LightOriginBalance) { CheckOrigins(Variant::Area, MISHeuristic::Balance); }
TEST(MBDPTRecords, LightOriginPower) { CheckOrigins(Variant::Area, MISHeuristic::Power); }
TEST(MBDPTRecords, LightOriginPointLight) { CheckOrigins(Variant::PointLight, MISHeuristic::Balance); }
TEST(MBDPTRecords, LightOriginMedia) { CheckOrigins(Variant::Media, MISHeuristic::Balance); }

TEST(MBDPTRecords, EqualConnectBDPTBalance) { CheckRecords(Variant::Area, MISHeuristic::Balance); }
TEST(MBDPTRecords, EqualConnectBDPTPower) { CheckRecords(Variant::Area, MISHeuristic::Power); }
TEST(MBDPTRecords, EqualConnectBDPTPointLight) { CheckRecords(Variant::PointLight, MISHeuristic::Balance); }
TEST(MBDPTRecords, EqualConnectBDPTMedia) { CheckRecords(Variant::Media, MISHeuristic::Balance); }
TEST(MBDPTRecords, EqualConnectBDPTMediaPower) { CheckRecords(Variant::Media, MISHeuristic::Power); }

}  // namespace
}  // namespace gradus
