// Helpers shared by the material implementations (internal to gradus_materials):
// parameter clamping, texture queries and the bump-mapped material base.
#pragma once
#include <memory>

#include "materials/material.h"
#include "textures/textures.h"

namespace gradus {
namespace matutil {

inline Spectrum ClampNeg(const Spectrum &s) { return {std::max(0.0, s.r), std::max(0.0, s.g), std::max(0.0, s.b)}; }

inline bool NonConstant(const std::shared_ptr<FloatTexture> &t) { return t && !t->isConstant(); }
inline bool NonConstant(const std::shared_ptr<SpectrumTexture> &t) { return t && !t->isConstant(); }

// Smallest value a float texture can take, when known (constant); else -1.
inline Float ConstantOr(const std::shared_ptr<FloatTexture> &t, Float unknown) {
    if (auto c = dynamic_cast<const ConstantTexture<Float> *>(t.get())) return c->value();
    return unknown;
}

// Material with optional bump map (pbrt-v3 semantics: displacement along the
// shading normal, finite differences in u and v).
class BumpMaterial : public Material {
  public:
    explicit BumpMaterial(std::shared_ptr<FloatTexture> bump) : bump_(std::move(bump)) {}
    BSDF getBSDF(SurfaceInteraction &si, Arena &arena, TransportMode mode) const override {
        if (bump_) ApplyBump(*bump_, si);
        const BxDF *b = build(si, arena, mode);
        return b ? BSDF(si, b) : BSDF();
    }
    // The BxDF at si (after bump mapping); nullptr for "no surface" (e.g. fully black glass).
    virtual const BxDF *build(const SurfaceInteraction &si, Arena &arena, TransportMode mode) const = 0;
    bool hasTextures() const override { return NonConstant(bump_) || texturesVary(); }
    virtual bool texturesVary() const = 0;

    static void ApplyBump(const FloatTexture &d, SurfaceInteraction &si) {
        // Without ray differentials a fixed small step in (u, v) is used, as pbrt-v3 does
        // when the differentials are zero.
        const Float du = 0.0005, dv = 0.0005;
        SurfaceInteraction e = si;
        e.p = si.p + si.shading.dpdu * du;
        e.uv = si.uv + Point2(du, 0);
        Float uDisp = d.evaluate(e);
        e.p = si.p + si.shading.dpdv * dv;
        e.uv = si.uv + Point2(0, dv);
        Float vDisp = d.evaluate(e);
        Float disp = d.evaluate(si);
        Vec3 dpdu = si.shading.dpdu + si.shading.n * ((uDisp - disp) / du) + si.shading.dndu * disp;
        Vec3 dpdv = si.shading.dpdv + si.shading.n * ((vDisp - disp) / dv) + si.shading.dndv * disp;
        if (Cross(dpdu, dpdv).lengthSquared() == 0) return;
        // Keep the perturbed normal on the side of the unperturbed shading normal.
        Vec3 nOld = si.shading.n;
        si.setShadingGeometry(dpdu, dpdv, si.shading.dndu, si.shading.dndv, false);
        if (Dot(si.shading.n, nOld) < 0) si.shading.n = -si.shading.n;
    }

  private:
    std::shared_ptr<FloatTexture> bump_;
};

}  // namespace matutil
}  // namespace gradus
