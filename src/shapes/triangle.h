// Triangle meshes, stored in world space (transformed at load, like pbrt-v3),
// or in an object's space when the object is instanced (MeshPlacement).
#pragma once
#include <memory>
#include <vector>

#include "core/error.h"
#include "shapes/shape.h"
#include "textures/texture.h"

namespace gradus {

// Where an instanced (shared) mesh sits in the world: one per object instance.
// swapsHandedness is that of worldFromMesh alone; the mesh's own
// transformSwapsHandedness is that of the transform it was built with.
struct MeshPlacement {
    Transform worldFromMesh;
    bool swapsHandedness = false;
    explicit MeshPlacement(const Transform &xf) : worldFromMesh(xf), swapsHandedness(xf.swapsHandedness()) {}
};

struct TriangleMesh {
    std::vector<Point3> p;     // world space
    std::vector<Normal3> n;    // optional per-vertex shading normals (world)
    std::vector<Vec3> s;       // optional per-vertex tangents (world)
    std::vector<Point2> uv;    // optional
    std::vector<int> indices;  // 3 per triangle
    bool reverseOrientation = false;
    bool transformSwapsHandedness = false;
    // Alpha cut-outs (pbrt-v3): hits where alpha is 0 are ignored; shadow rays
    // also ignore hits where shadowAlpha is 0. Null when absent.
    std::shared_ptr<const FloatTexture> alpha, shadowAlpha;
    int numTriangles() const { return int(indices.size() / 3); }
    // Builds the world-space mesh; validates indices and rejects non-finite
    // P, N, S or uv values (throws Error at loc naming the vertex).
    static std::shared_ptr<TriangleMesh> Create(const Transform &worldFromObject, bool reverseOrientation,
                                                std::vector<Point3> P, std::vector<int> indices,
                                                std::vector<Normal3> N, std::vector<Vec3> S,
                                                std::vector<Point2> uv, const FileLoc &loc);
    // World-space corners of triangle `tri` (placement: null for a world mesh).
    void corners(int tri, const MeshPlacement *placement, Point3 c[3]) const;
    // Recomputes the barycentrics of ray r's (world-space) hit on triangle `tri`
    // in double precision (Embree's are single precision); keeps the given ones
    // when the ray is parallel to the triangle. Clamped onto the triangle.
    void refineBarycentrics(int tri, const Ray &r, Float *b1, Float *b2,
                            const MeshPlacement *placement = nullptr) const;
    // Fills the world-space surface interaction for a hit with barycentrics
    // (b1, b2) on triangle `tri`. With a placement, the corners, normals and
    // tangents are placed first, so the result equals that of the mesh
    // flattened with worldFromMesh (up to rounding).
    void interaction(int tri, Float b1, Float b2, const Vec3 &wo, SurfaceInteraction *si,
                     const MeshPlacement *placement = nullptr) const;
};

// One triangle of a world mesh as a Shape (area lights). Its corners, unit
// normal (oriented as the mesh's interaction orients it, where that does not
// vary over the triangle) and area are kept with it: light sampling reads no
// mesh arrays and computes no cross product per sample.
class Triangle : public Shape {
  public:
    Triangle(std::shared_ptr<const TriangleMesh> mesh, int tri);
    Float area() const override;
    Bounds3 worldBound() const override;
    Interaction sampleArea(Point2 u, Float *pdf) const override;
    bool intersectP(const Ray &r, Float *tHit, Interaction *hit) const override;

  private:
    // The unit normal at barycentrics (b0, b1, 1 - b0 - b1), oriented.
    Normal3 orientedNormal(Float b0, Float b1) const;
    std::shared_ptr<const TriangleMesh> mesh_;
    int tri_;
    Point3 p_[3];
    Normal3 n_;           // unit geometric normal, oriented when !varies_
    Float area_ = 0;
    bool varies_ = false;  // shading normals that do not all face one side of n_
};

}  // namespace gradus
