#include "integrators/gbdpt/gbdpt_shift.h"

#include "lights/light.h"

namespace gradus {

bool SampleLightPoint(const SubpathShiftContext &ctx, const PathVertex &pt, Float uSel, Point2 u, LightPoint *lp) {
    const BidirContext &bc = *ctx.bidir;
    Float pmf;
    const Light *lt = bc.lightSampler->sample(uSel, &pmf);
    if (!lt || pmf == 0) return false;
    LightLiSample ls;
    if (!lt->sampleLi(VertexIt(pt), u, &ls) || ls.pdf == 0 || ls.L.isBlack()) return false;
    PathVertex &s = lp->v;
    s = PathVertex();
    s.type = VertexType::Light;
    s.light = lt;
    lp->delta = IsDeltaLight(lt->flags);
    lp->infinite = lt->flags & (LIGHT_INFINITE | LIGHT_DELTA_DIRECTION);
    if (lp->delta) s.flags |= VERTEX_DELTA_LIGHT;
    if (lp->infinite) s.flags |= VERTEX_INFINITE;
    s.p = ls.pLight.p;
    s.ng = ls.pLight.n;
    s.ns = ls.pLight.n;
    s.setThroughput(ls.L / (ls.pdf * pmf));
    s.pdfFwd = PdfLightOrigin(bc, s, pt);
    lp->light = lt;
    lp->pmf = pmf;
    lp->pdf = ls.pdf;
    lp->Li = ls.L;
    lp->basePoint = pt.p;
    lp->u = u;
    return true;
}

bool ConnectLightPoint(const SubpathShiftContext &ctx, const LightPoint &lp, SubpathView cam, int t,
                       ConnectResult *res, bool knownVisible, int misSplit, MISSplit *misParts, UniformSource rng) {
    *res = ConnectResult();
    const BidirContext &bc = *ctx.bidir;
    const PathVertex &pt = cam.v[t - 1];
    const BSDF *pb = cam.bsdf ? &cam.bsdf[t - 1] : nullptr;
    const bool medium = ctx.media && pt.type == VertexType::Medium;
    if ((pt.type != VertexType::Surface && !medium) || !IsConnectible(pt, pb) || lp.infinite) return false;
    PathVertex s = lp.v;
    if (!EdgeConnectible(bc, s, pt)) return false;
    Vec3 d = s.p - pt.p;
    Float d2 = d.lengthSquared();
    if (!(d2 > 0)) return false;
    Vec3 wi = d / std::sqrt(d2);
    Spectrum Li;  // radiance over the base's light-sampling density (area measure, Eq. 8 pairs)
    if (lp.delta) {
        LightLiSample ls;
        if (!lp.light->sampleLi(VertexIt(pt), lp.u, &ls) || ls.pdf == 0) return false;
        Li = ls.L / (ls.pdf * lp.pmf);
    } else {
        if (!(lp.light->flags & LIGHT_AREA)) return false;
        Spectrum Le = static_cast<const AreaLight *>(lp.light)->L(Interaction(s.p, s.ng, -wi), -wi);
        Float cosY = AbsDot(Vec3(s.ng), wi);
        Vec3 dx = s.p - lp.basePoint;
        Float d2x = dx.lengthSquared();
        Float cosX = AbsDot(Vec3(s.ng), dx / std::sqrt(d2x));
        if (!(cosX > 0)) return false;
        // p_A(base) = pdf_omega |cos_x| / d_x^2; the offset's geometry |cos_y| / d_y^2.
        Li = Le * ((cosY / d2) / (lp.pmf * lp.pdf * cosX / d2x));
    }
    Spectrum L = pt.throughput() * EvalBSDF(pt, *pb, s, TransportMode::Radiance) * Li *
                 (medium ? Float(1) : AbsDot(wi, Vec3(pt.ns)));
    if (L.isBlack()) return false;
    res->shadowRayTraced = !knownVisible;
    if (ctx.media) {
        if (!knownVisible) L *= Transmittance(bc, pt, VertexIt(pt), Interaction(s.p, s.ng, -wi), rng);
        if (L.isBlack()) return false;
    } else if (!knownVisible && !bc.scene->unoccluded(VertexIt(pt), Interaction(s.p, s.ng, -wi))) {
        return false;
    }
    s.pdfFwd = PdfLightOrigin(bc, s, pt);
    const bool split = misParts && misSplit >= 1 && misSplit + 2 <= t - 1;
    Float w = MISWeight(bc, bc.strategies, SubpathView{&s, nullptr, 1}, cam, 1, t, &s, split ? misSplit : -1,
                        split ? misParts : nullptr);
    res->weight = w;
    res->unweighted = L;
    res->L = L * w;
    return w > 0;
}

}  // namespace gradus
