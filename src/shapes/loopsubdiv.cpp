#include "shapes/loopsubdiv.h"

#include <opensubdiv/far/error.h>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>

#include <memory>
#include <string>

namespace gradus {

namespace {

using namespace OpenSubdiv;

// Vertex primvar in the form PrimvarRefiner expects.
struct OsdPoint {
    double v[3] = {0, 0, 0};
    void Clear(void * = nullptr) { v[0] = v[1] = v[2] = 0; }
    void AddWithWeight(const OsdPoint &s, double w) {
        v[0] += w * s.v[0];
        v[1] += w * s.v[1];
        v[2] += w * s.v[2];
    }
    Vec3 vec() const { return Vec3(v[0], v[1], v[2]); }
};

// OpenSubdiv reports topology problems through a global callback; keep it quiet
// (bad topology shows up as a null refiner, which is reported with a location).
void QuietOsdErrors(Far::ErrorType, const char *) {}

}  // namespace

LoopSubdivResult LoopSubdivide(const std::vector<Point3> &P, const std::vector<int> &indices, int levels,
                               const FileLoc &loc) {
    if (levels < 0 || levels > 8)
        throw Error(loc, "loopsubdiv: \"levels\" must be in [0, 8] (got " + std::to_string(levels) + ")");
    if (indices.size() % 3 != 0) throw Error(loc, "loopsubdiv: number of indices is not a multiple of 3");
    for (size_t i = 0; i < P.size(); ++i)
        if (!P[i].isFinite()) throw Error(loc, "loopsubdiv: \"P\" of vertex " + std::to_string(i) + " is not finite");
    std::vector<int> faces;
    faces.reserve(indices.size());
    for (size_t f = 0; f + 2 < indices.size(); f += 3) {
        int a = indices[f], b = indices[f + 1], c = indices[f + 2];
        for (int i : {a, b, c})
            if (i < 0 || size_t(i) >= P.size())
                throw Error(loc, "loopsubdiv: vertex index " + std::to_string(i) + " out of range (" +
                                     std::to_string(P.size()) + " vertices)");
        if (a == b || b == c || a == c) continue;  // degenerate face
        faces.insert(faces.end(), {a, b, c});
    }
    LoopSubdivResult out;
    if (faces.empty()) return out;

    Far::SetErrorCallback(QuietOsdErrors);
    const int numFaces = int(faces.size() / 3);
    std::vector<int> vertsPerFace(size_t(numFaces), 3);
    Far::TopologyDescriptor desc;
    desc.numVertices = int(P.size());
    desc.numFaces = numFaces;
    desc.numVertsPerFace = vertsPerFace.data();
    desc.vertIndicesPerFace = faces.data();
    // Smooth boundaries as B-spline curves (corners are not pinned), like pbrt-v3.
    Sdc::Options sdc;
    sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
    using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
    std::unique_ptr<Far::TopologyRefiner> refiner(
        Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, sdc)));
    if (!refiner) throw Error(loc, "loopsubdiv: OpenSubdiv rejected the mesh topology");
    Far::TopologyRefiner::UniformOptions uniform(levels);
    uniform.fullTopologyInLastLevel = true;  // Limit() needs the edges of the last level
    refiner->RefineUniform(uniform);

    // Interpolate positions level by level into one buffer.
    std::vector<OsdPoint> verts(size_t(refiner->GetNumVerticesTotal()));
    for (size_t i = 0; i < P.size(); ++i) verts[i].v[0] = P[i].x, verts[i].v[1] = P[i].y, verts[i].v[2] = P[i].z;
    Far::PrimvarRefinerReal<double> primvar(*refiner);
    OsdPoint *src = verts.data();
    for (int level = 1; level <= levels; ++level) {
        OsdPoint *dst = src + refiner->GetLevel(level - 1).GetNumVertices();
        primvar.Interpolate(level, src, dst);
        src = dst;
    }
    const Far::TopologyLevel &fine = refiner->GetLevel(levels);
    const int nv = fine.GetNumVertices();
    std::vector<OsdPoint> limit(nv), tan1(nv), tan2(nv);
    primvar.Limit(src, limit, tan1, tan2);

    out.P.resize(nv);
    for (int i = 0; i < nv; ++i) out.P[i] = limit[i].vec();
    out.indices.reserve(size_t(fine.GetNumFaces()) * 3);
    std::vector<Vec3> faceSum(nv, Vec3(0, 0, 0));  // area-weighted face normals (orientation reference)
    for (int f = 0; f < fine.GetNumFaces(); ++f) {
        Far::ConstIndexArray fv = fine.GetFaceVertices(f);
        if (fv.size() != 3) continue;
        out.indices.insert(out.indices.end(), {fv[0], fv[1], fv[2]});
        Vec3 n = Cross(out.P[fv[1]] - out.P[fv[0]], out.P[fv[2]] - out.P[fv[0]]);
        if (!n.isFinite()) continue;
        for (int k = 0; k < 3; ++k) faceSum[fv[k]] += n;
    }
    out.N.resize(nv);
    for (int i = 0; i < nv; ++i) {
        Vec3 n = Cross(tan1[i].vec(), tan2[i].vec());
        const Vec3 &ref = faceSum[i];
        if (!(n.lengthSquared() > 0) || !n.isFinite()) n = ref;
        if (Dot(n, ref) < 0) n = -n;
        out.N[i] = n.lengthSquared() > 0 ? Normalize(n) : Normal3(0, 0, 0);
    }
    return out;
}

}  // namespace gradus
