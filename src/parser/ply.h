// PLY triangle-mesh reader (ASCII, binary little/big endian) for pbrt-v3's
// "plymesh" shape. Faces with 4 vertices are split into two triangles.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "core/geometry.h"

namespace gradus {

struct PlyMesh {
    std::vector<Point3> P;
    std::vector<Normal3> N;   // empty, or one per vertex (nx ny nz)
    std::vector<Point2> uv;   // empty, or one per vertex (u v | s t | texture_u texture_v | texture_s texture_t)
    std::vector<int> indices; // triangles; quads split
};

// Throws gradus::Error naming the file on any malformed, truncated or
// out-of-range input; never crashes on bad data.
PlyMesh ReadPly(const std::string &filename);
// Same, from a memory buffer; `name` is used in error messages.
PlyMesh ReadPlyFromMemory(const char *data, size_t size, const std::string &name = "<memory>");

}  // namespace gradus
