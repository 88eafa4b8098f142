// pbrt-v3 "loopsubdiv": Loop subdivision through OpenSubdiv's Far API
// (uniform refinement, positions pushed to the limit surface, normals from the
// limit tangents). The result is an ordinary triangle mesh in object space.
#pragma once
#include <vector>

#include "core/error.h"
#include "core/geometry.h"

namespace gradus {

struct LoopSubdivResult {
    std::vector<Point3> P;     // limit positions
    std::vector<Normal3> N;    // limit normals, oriented like the faces' winding
    std::vector<int> indices;  // triangles of the finest level
};

// levels = number of uniform refinement steps (0 keeps the control mesh but
// still projects it to the limit). Invalid indices or levels throw Error at loc.
// Triangles with a repeated vertex are dropped before refinement.
LoopSubdivResult LoopSubdivide(const std::vector<Point3> &P, const std::vector<int> &indices, int levels,
                               const FileLoc &loc);

}  // namespace gradus
