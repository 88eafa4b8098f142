#include "integrators/gpt/gpt_tracer.h"

#include "samplers/sampling.h"

namespace gradus::gpt {

namespace {

// Emitted radiance of `light` at the end of a segment (hit si if f, else the
// environment along r) and its NEE pdf (solid angle) from `from`.
Spectrum Emitted(const LightSampler &lights, const Light *light, bool f, const SurfaceInteraction &si, const Ray &r,
                 const Interaction &from, bool specular, Float *lightPdf) {
    *lightPdf = 0;
    Spectrum Le(0);
    if (f) {
        if (si.areaLight != light) return Le;
        Le = si.Le(-r.d);
    } else {
        if (!(light->flags & LIGHT_INFINITE)) return Le;
        Le = light->Le(r);
    }
    if (!specular && !Le.isBlack()) *lightPdf = lights.pmf(from.p, light) * light->pdfLi(from, r.d);
    return Le;
}

// The emitters the base or a diverged offset reached with the last segment.
int EmittersReached(const Scene &scene, const PathHit &cur, const OffsetPath *off, const Light *keys[8]) {
    int nkeys = 0;
    auto addKey = [&](const Light *l) {
        for (int i = 0; i < nkeys; ++i)
            if (keys[i] == l) return;
        if (nkeys < 8) keys[nkeys++] = l;
    };
    auto addKeysOf = [&](bool f, const SurfaceInteraction &si) {
        if (f) {
            if (si.areaLight) addKey(si.areaLight);
        } else {
            for (const Light *l : scene.infiniteLights) addKey(l);
        }
    };
    addKeysOf(cur.found, cur.isect);
    for (int k = 0; k < kNumNeighbours; ++k)
        if (off[k].state == OffsetPath::Diverged) addKeysOf(off[k].found, off[k].isect);
    return nkeys;
}

}  // namespace

// The offset's emission term of the BSDF technique for `light`.
Spectrum GradientPathTracer::offsetEmission(const OffsetPath &o, const Light *light, const Spectrum &Lx, Float nx,
                                            Float bx, Float *ny, Float *by) const {
    *ny = *by = 0;
    switch (o.state) {
    case OffsetPath::Dead: break;
    case OffsetPath::Identical:
        *ny = nx;
        *by = bx;
        return o.beta * Lx;
    case OffsetPath::Reconnected: {
        Ray ry(o.prevIt.p, (cur_.found ? cur_.isect.p - o.prevIt.p : cur_.ray.d), Infinity);
        ry.d = Normalize(ry.d);
        Spectrum Cy = o.beta * Emitted(lights_, light, cur_.found, cur_.isect, ry, o.prevIt, o.lastSpecular, ny);
        *by = o.lastPdfY;
        return Cy;
    }
    case OffsetPath::Diverged: {
        Spectrum Cy = o.beta * Emitted(lights_, light, o.found, o.isect, o.ray, o.prevIt, o.lastSpecular, ny);
        *by = o.lastPdfY;
        return Cy;
    }
    }
    return Spectrum(0);
}

// Emission reached by the last segment (BSDF technique): primal and gradient terms.
// Separated light (gradient_film.h): a path whose every bounce was sampled
// from a Dirac lobe adds to the primal and the separated layer and to no
// gradient. The gradients estimate those of the image without it: the
// symmetric estimator (G-BDPT Eq. 3) applied to the integrand f_R(x) =
// f(x) [x not separated], base and offset each tested on their own chain.
// The half-vector/replay shift usually maps a Dirac chain to one (replay of
// a Dirac sample on the same material), but not always (a smooth-coated
// material may replay into its diffuse lobe), so a separated base still
// contributes the offset's f_R(y) and vice versa; the MIS weights depend on
// the densities only and are kept, so the pairs' weights still sum to one.
void GradientPathTracer::emissionTerms() {
    const Light *keys[8];
    const int nkeys = EmittersReached(scene_, cur_, off_, keys);
    for (int i = 0; i < nkeys; ++i) {
        const Light *light = keys[i];
        Float nx;
        Spectrum Lx = Emitted(lights_, light, cur_.found, cur_.isect, cur_.ray, prevIt_, specularBounce_, &nx);
        Float bx = prevBsdfPdf_;
        Spectrum Cx = beta_ * Lx;
        if (!Lx.isBlack()) {
            const Spectrum c = Cx * (specularBounce_ ? 1 : PowerHeuristic(1, bx, 1, nx));
            primal_ += c;
            if (diracChain_) separated_ += c;
        }
        if (diracChain_) Cx = Spectrum(0);  // f_R(x)
        for (int k = 0; k < kNumNeighbours; ++k) {
            if (!inside_[k]) continue;
            OffsetPath &o = off_[k];
            Float ny, by;
            Spectrum Cy = offsetEmission(o, light, Lx, nx, bx, &ny, &by);
            if (o.diracChain) Cy = Spectrum(0);  // f_R(y)
            if (Cx.isBlack() && Cy.isBlack()) continue;
            Float wgt = GradientMISWeight(bx, nx, by, ny, o.ratio * o.lastJ);
            o.diff += (Cy - Cx) * wgt;
        }
    }
    // Commit the last segment's pdf ratio (G-BDPT Eq. 8 uses full-path pdfs).
    for (OffsetPath &o : off_)
        if (o.state != OffsetPath::Dead) o.ratio *= o.lastPdfY * o.lastJ / prevBsdfPdf_;
}

// A diverged offset connects its own vertex to the base's light sample:
// reconnection to an area light's point, the same direction for
// environments, a fresh evaluation of delta lights.
Spectrum GradientPathTracer::divergedNextEvent(const OffsetPath &o, const LightChoice &lc, Float *ny, Float *by,
                                               Float *J) const {
    const Light *light = lc.light;
    const LightLiSample &ls = lc.ls;
    const Vec3 woY = o.isect.wo;
    // The offset keeps the base's light; its own selection pmf enters the MIS only.
    const Float pmfY = lights_.pmf(o.isect.p, light);
    Vec3 wiY;
    Spectrum Ly;
    Interaction pLy;
    if (light->flags & LIGHT_AREA) {
        ShiftVertex target{ls.pLight.p, ls.pLight.n, nullptr, false};
        ReconnectionShift rc;
        if (ShiftReconnect(cur_.isect.p, o.isect.p, target, &rc)) {
            wiY = rc.wi;
            *J = rc.jacobian;
            Ly = static_cast<const AreaLight *>(light)->L(ls.pLight, -wiY);
            *ny = pmfY * light->pdfLi(o.isect, wiY);
            pLy = ls.pLight;
        }
    } else if (light->flags & LIGHT_INFINITE) {
        wiY = ls.wi;  // environment shift: same direction, |T'| = 1
        Ly = ls.L;
        *ny = pmfY * light->pdfLi(o.isect, wiY);
        pLy = Interaction(o.isect.p + (ls.pLight.p - cur_.isect.p), ls.pLight.n, Vec3());
    } else {  // delta lights: same position or direction
        LightLiSample lsy;
        if (light->sampleLi(o.isect, lc.u, &lsy) && lsy.pdf > 0) {
            wiY = lsy.wi;
            Ly = lsy.L;
            *ny = pmfY * lsy.pdf;
            pLy = lsy.pLight;
        }
    }
    if (!(*ny > 0)) return Spectrum(0);
    *by = lc.delta ? 0 : o.bsdf.pdf(woY, wiY);
    Spectrum fy = o.bsdf.f(woY, wiY) * AbsDot(wiY, o.isect.shading.n);
    if (!fy.isBlack() && !Ly.isBlack() && ShiftEdgeVisible(scene_, o.isect, pLy)) return o.beta * fy * Ly * (*J / lc.nx);
    return Spectrum(0);
}

// The offset's next-event term for the base's light sample.
Spectrum GradientPathTracer::offsetNextEvent(const OffsetPath &o, const LightChoice &lc, Float *ny, Float *by,
                                             Float *J) const {
    *ny = *by = 0;
    *J = 1;
    const LightLiSample &ls = lc.ls;
    if (o.state == OffsetPath::Identical) {
        *ny = lc.nx;
        *by = lc.bx;
        return lc.visible ? o.beta * lc.fx * ls.L / lc.nx : Spectrum(0);
    }
    if (o.state == OffsetPath::Reconnected) {
        // Same vertex as the base; only the incoming direction differs.
        const BSDF &bsdf = cur_.bsdf;
        Spectrum fy = bsdf.f(o.wo, ls.wi) * AbsDot(ls.wi, cur_.isect.shading.n);
        *ny = lc.nx;
        *by = lc.delta ? 0 : bsdf.pdf(o.wo, ls.wi);
        if (lc.visible) return o.beta * fy * ls.L / lc.nx;
        if (!fy.isBlack() && lc.fx.isBlack() && !ls.L.isBlack() && ShiftEdgeVisible(scene_, cur_.isect, ls.pLight))
            return o.beta * fy * ls.L / lc.nx;
        return Spectrum(0);
    }
    if (o.state == OffsetPath::Diverged && o.bsdf.hasNonSpecular()) return divergedNextEvent(o, lc, ny, by, J);
    return Spectrum(0);
}

// Next-event estimation at the base vertex (light technique): primal and
// gradient terms. Sampler use: 1D (light) + 2D (point), also without lights.
void GradientPathTracer::nextEventTerms(Sampler &sampler) {
    const BSDF &bsdf = cur_.bsdf;
    const SurfaceInteraction &isect = cur_.isect;
    if (!bsdf.hasNonSpecular()) return;
    if (scene_.lights.empty()) {
        sampler.get1D();
        sampler.get2D();
        return;
    }
    LightChoice lc;
    Float pmf;
    lc.light = lights_.sample(isect.p, sampler.get1D(), &pmf);
    lc.u = sampler.get2D();
    if (!lc.light || !(pmf > 0)) return;
    // sampleLi says false also for zero radiance towards the base (the back of a
    // one-sided emitter, outside a spot cone), with the sample filled in. An
    // offset may still see the light: its term must be evaluated, or the
    // symmetric estimator (G-BDPT Eq. 3) loses w_ij(x) f(y) for f(x) = 0 while
    // the reverse shift weights the pair by w_ji(y) < 1 -- a biased gradient.
    lc.light->sampleLi(isect, lc.u, &lc.ls);
    if (!(lc.ls.pdf > 0)) return;
    const LightLiSample &ls = lc.ls;
    const Vec3 wo = isect.wo;
    lc.delta = IsDeltaLight(lc.light->flags);
    lc.nx = pmf * ls.pdf;
    lc.bx = lc.delta ? 0 : bsdf.pdf(wo, ls.wi);
    lc.fx = bsdf.f(wo, ls.wi) * AbsDot(ls.wi, isect.shading.n);
    lc.visible = !lc.fx.isBlack() && !ls.L.isBlack() && ShiftEdgeVisible(scene_, isect, ls.pLight);
    Spectrum Cx = lc.visible ? beta_ * lc.fx * ls.L / lc.nx : Spectrum(0);
    if (lc.visible) primal_ += Cx * (lc.delta ? 1 : PowerHeuristic(1, lc.nx, 1, lc.bx));
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!inside_[k]) continue;
        OffsetPath &o = off_[k];
        Float ny, by, J;
        Spectrum Cy = offsetNextEvent(o, lc, &ny, &by, &J);
        if (Cx.isBlack() && Cy.isBlack()) continue;
        Float wgt = GradientMISWeight(lc.nx, lc.bx, ny, by, o.ratio * J);
        o.diff += (Cy - Cx) * wgt;
    }
}

}  // namespace gradus::gpt
