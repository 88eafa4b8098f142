// libFuzzer entry for PLY input: parse the bytes as a PLY file, build the
// triangle mesh as "plymesh" would, and query every triangle (interaction,
// area sampling, a ray hit). Any exception other than gradus::Error, any crash
// or sanitizer report is a bug.
//   ./fuzz_ply -max_len=8192 corpus/   (seeds: tests/parser/data/*.ply, tests/robustness/data)
#include <cstdint>

#include "parser/ply.h"
#include "shapes/triangle.h"

namespace gradus {
Float gRayEpsilon = 1e-6;  // defined by the scene library in the renderer
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    using namespace gradus;
    try {
        PlyMesh ply = ReadPlyFromMemory(reinterpret_cast<const char *>(data), size, "fuzz.ply");
        auto mesh = TriangleMesh::Create(Transform(), false, std::move(ply.P), std::move(ply.indices),
                                         std::move(ply.N), {}, std::move(ply.uv), FileLoc());
        int n = std::min(mesh->numTriangles(), 256);
        for (int t = 0; t < n; ++t) {
            SurfaceInteraction si;
            mesh->interaction(t, 0.25, 0.25, Vec3(0, 0, 1), &si);
            Triangle tri(mesh, t);
            Float pdf;
            Interaction it = tri.sampleArea(Point2(0.3, 0.6), &pdf);
            Float tHit;
            Interaction hit;
            tri.intersectP(Ray(it.p + Vec3(0, 0, 1), Vec3(0, 0, -1)), &tHit, &hit);
            (void)tri.area();
            (void)tri.worldBound();
        }
    } catch (const Error &) {
    }
    return 0;
}
