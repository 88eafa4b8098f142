// The glTF 2.0 metallic-roughness material (glTF 2.0 specification, Appendix B:
// BRDF implementation) with KHR_materials_ior and KHR_materials_transmission.
#pragma once
#include <memory>

#include "materials/bsdf.h"
#include "materials/material.h"
#include "materials/microfacet.h"

namespace gradus {

// Appendix B, with H the half vector of (wo, wi) and F_d = f0 + (1 - f0)(1 - |V.H|)^5:
//   specular = D_GGX(H) V_Smith (height-correlated), diffuse = baseColor / pi,
//   dielectric = (1 - F_d) [(1 - t) diffuse + t btdf] + F_d specular,
//   metal = specular (baseColor + (1 - baseColor)(1 - |V.H|)^5),
//   f = (1 - metallic) dielectric + metallic metal.
// f0 = ((ior - 1) / (ior + 1))^2 (KHR_materials_ior). The btdf (KHR_materials_transmission,
// factor t) is Walter et al. 2007's rough transmission (eta = ior, same alpha) without
// its own Fresnel factor (fresnel_mix supplies 1 - F_d), tinted by baseColor. Reflection
// lobes act on the side of wo (wo, wi in one hemisphere, mirrored when wo.z < 0, as the
// other Gradus BxDFs); only the transmission lobe crosses the surface.
class GltfPbrBxDF : public BxDF {
  public:
    // Below this alpha the microfacet lobes are replaced by their smooth (delta) limits;
    // the transmission lobe also when alpha (1 - 1/ior) (its angular width) is below it.
    static constexpr Float SmoothAlpha = 1e-3;
    // alpha = roughness^2 (glTF perceptual roughness). Inputs are clamped: baseColor,
    // metallic, alpha and transmission to [0, 1], ior to [1, 1e4].
    GltfPbrBxDF(const Spectrum &baseColor, Float metallic, Float alpha, Float ior, Float transmission);
    Spectrum f(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    bool sample(const Vec3 &wo, Float uc, Point2 u, TransportMode mode, BSDFSample *s) const override;
    Float pdf(const Vec3 &wo, const Vec3 &wi, TransportMode mode) const override;
    // alpha; 0 when a smooth (delta) lobe is used.
    Float roughness() const override;

    Float alpha() const { return alpha_; }
    Float f0() const { return f0_; }
    // Lobe selection probabilities of sample() for wo (they sum to 1).
    struct LobeProbs {
        Float diffuse = 0, specular = 0, transmission = 0;
    };
    LobeProbs lobeProbs(const Vec3 &wo) const;

  private:
    Float fresnelD(Float cosVH) const;     // F_d (Schlick with f0)
    Spectrum fresnelMix(Float cosVH) const;  // (1 - metallic) F_d + metallic F_metal
    Spectrum base_;
    Float metallic_, alpha_, ior_, t_, f0_;
    Float kd_, kt_;  // (1 - metallic)(1 - t), (1 - metallic) t
    bool hasDiffuse_, hasTrans_, smoothR_, smoothT_;
    MicrofacetDistribution d_;
};

// The "gltfpbr" material (called by CreateMaterial; `bump` is "bumpmap" or null).
// Parameters: basecolor, metallic, roughness, ior, transmission, normalmap, normalscale.
std::shared_ptr<Material> CreateGltfPbrMaterial(const ParamSet &params, const NamedTextures &textures,
                                               const FileLoc &loc, std::shared_ptr<FloatTexture> bump);

// Tangent-space normal mapping (glTF 2.0 normalTexture): n_ts = (2 rgb - 1) with x, y
// scaled by `scale`, in the frame T = shading dpdu, B = shading dpdv orthogonalised,
// N = shading normal. Updates si.shading (n, dpdu, dpdv); the new normal stays on
// the side of the old one.
void ApplyNormalMap(const Spectrum &rgb, Float scale, SurfaceInteraction &si);

}  // namespace gradus
