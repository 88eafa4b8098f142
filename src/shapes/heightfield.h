// pbrt-v3's "heightfield" shape: a grid of nu x nv heights Pz over [0,1]^2 in
// object space, triangulated into a mesh with uv = (x, y).
#pragma once
#include <vector>

#include "core/error.h"
#include "core/geometry.h"
#include "parser/paramset.h"

namespace gradus {

// Object-space triangle mesh data (before TriangleMesh::Create places it).
struct MeshData {
    std::vector<Point3> P;
    std::vector<int> indices;
    std::vector<Normal3> N;  // empty when the shape gives no shading normals
    std::vector<Point2> uv;
};

// Vertex (x, y) of the grid is index x + y * nu at (x/(nu-1), y/(nv-1), Pz[x + y*nu]);
// each cell splits into (x,y)(x+1,y)(x+1,y+1) and (x,y)(x+1,y+1)(x,y+1), as pbrt-v3 does.
// Requires nu, nv >= 2 and Pz.size() == nu * nv.
MeshData HeightfieldMesh(int nu, int nv, const std::vector<Float> &Pz);

// Reads "integer nu", "integer nv", "float Pz"; bad counts are located errors.
MeshData CreateHeightfield(const ParamSet &ps, const FileLoc &loc);

}  // namespace gradus
