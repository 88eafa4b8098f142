#include "integrators/gpt/gpt.h"

#include <algorithm>

#include "core/error.h"
#include "integrators/factories.h"
#include "samplers/sampling.h"

namespace gradus {

std::unique_ptr<Integrator> CreateGPTIntegrator(const EntityDesc &d) { return std::make_unique<GPTIntegrator>(d); }

GPTIntegrator::GPTIntegrator(const EntityDesc &desc) : loc_(desc.loc) {
    const ParamSet &ps = desc.params;
    maxDepth_ = ps.getInt("maxdepth", 5);
    rrThreshold_ = ps.getFloat("rrthreshold", 1);
    strategy_ = ps.getString("lightsamplestrategy", "spatial");
    shiftThreshold_ = ps.getFloat("shiftthreshold", 0.001);
    std::string mode = ps.getString("shift", "halfvector");
    std::string rec = ps.getString("reconstruction", "l1");
    alpha_ = ps.getFloat("alpha", 0.2);
    std::string pf = ps.getString("pixelfilter", "film");
    if (pf != "box" && pf != "film")
        throw Error(ps.locOf("pixelfilter", desc.loc), "unknown \"pixelfilter\" \"" + pf + "\" (box, film)");
    filmFilter_ = pf == "film";
    ps.getInts("pixelbounds");
    if (maxDepth_ < 0) throw Error(ps.locOf("maxdepth", desc.loc), "\"maxdepth\" must be >= 0");
    if (!(shiftThreshold_ >= 0)) throw Error(ps.locOf("shiftthreshold", desc.loc), "\"shiftthreshold\" must be >= 0");
    if (!(alpha_ >= 0)) throw Error(ps.locOf("alpha", desc.loc), "\"alpha\" must be >= 0");
    if (mode == "halfvector")
        mode_ = ShiftMode::HalfVector;
    else if (mode == "hybrid")
        mode_ = ShiftMode::Hybrid;
    else
        throw Error(ps.locOf("shift", desc.loc), "unknown \"shift\" \"" + mode + "\" (halfvector, hybrid)");
    try {
        norm_ = ParseReconstructionNorm(rec);
    } catch (const Error &) {
        throw Error(ps.locOf("reconstruction", desc.loc),
                    "unknown \"reconstruction\" \"" + rec + "\" (l1, l2, weighted)");
    }
}

void GPTIntegrator::preprocess(const Scene &scene, Film &film) {
    lightSampler_ = LightSampler(scene.lights, strategy_, loc_, scene.bounds);
    initGradients(film, filmFilter_);
    scene_ = &scene;
    stats_.reset();
}

void GPTIntegrator::estimate(const CameraSample &cs, Sampler &sampler, Arena &arena, SampleRecorder &rec) const {
    bool inside[kNumNeighbours];
    Point2i p = rec.pixel();
    // Box: only pairs of film pixels need gradients. Film filter: samples of
    // pixels around the film reach it too (targets outside are dropped).
    for (int k = 0; k < kNumNeighbours; ++k) inside[k] = filmFilter_ || pairInside(p, k);
    GradientSample s = sample(cs, sampler, arena, inside);
    gfilm_.record(rec, s);
}

void GPTIntegrator::finish(const Film &film, const RenderStats &stats, Image *out) {
    finishGradients(film, stats, norm_, alpha_, out);
}

std::string GPTIntegrator::statistics() const {
    return withReconstructionReport(stats_.format(std::string("G-PT shifts (") +
                                                  (mode_ == ShiftMode::Hybrid ? "hybrid" : "halfvector") +
                                                  ", threshold " + std::to_string(shiftThreshold_) + ")"));
}

namespace {

// State of one offset path relative to the base path.
struct OffsetPath {
    enum State { Dead, Diverged, Reconnected, Identical };
    State state = Dead;
    // Diverged: the offset's own current vertex.
    Ray ray;
    bool found = false;
    SurfaceInteraction isect;
    BSDF bsdf;
    ShiftVertexClass cls = ShiftVertexClass::Invalid;
    // Reconnected: the offset's incoming direction at the base vertex.
    Vec3 wo;
    Spectrum beta{0};       // f(y) |T'| / p(x) up to the current vertex
    Float ratio = 1;        // prod p_y |T'| / p_x over committed segments
    Float lastPdfY = 1;     // last segment: the offset's own pdf of its direction
    Float lastJ = 1;        // last segment: |T'| (solid angle)
    bool lastSpecular = true;
    Interaction prevIt;     // the offset's previous vertex
    Spectrum diff{0};
    void kill(LocalShiftStats &st, ShiftFailure why) {
        state = Dead;
        ratio = 0;
        st.fail(why);
    }
};

}  // namespace

GradientSample GPTIntegrator::sample(const CameraSample &cs, Sampler &sampler, Arena &arena,
                                     const bool inside[kNumNeighbours]) const {
    GradientSample out;
    LocalShiftStats st;
    const Scene &scene = *scene_;
    const Camera &camera = *scene.camera;
    auto classify = [&](bool found, SurfaceInteraction &si, BSDF *b) {
        *b = BSDF();
        if (!found) return ShiftVertexClass::Rough;  // a point at infinity
        if (!si.material) return ShiftVertexClass::Invalid;
        *b = si.material->getBSDF(si, arena, TransportMode::Radiance);
        return ClassifyBSDF(b, shiftThreshold_);
    };

    Ray ray;
    Float w = camera.generateRay(cs, &ray);
    if (w == 0) return out;

    // Offset camera rays: the film position moves by exactly one pixel (|T'| = 1,
    // equal pdfs), the lens sample is kept.
    OffsetPath off[kNumNeighbours];
    for (int k = 0; k < kNumNeighbours; ++k) {
        out.active[k] = inside[k];
        if (!inside[k]) continue;
        OffsetPath &o = off[k];
        ++st.offsetPaths;
        CameraSample c2 = cs;
        c2.pFilm = Point2(cs.pFilm.x + kNeighbourOffsets[k].x, cs.pFilm.y + kNeighbourOffsets[k].y);
        Float w2 = camera.generateRay(c2, &o.ray);
        if (w2 == 0) {
            o.kill(st, ShiftFailure::Geometry);
            continue;
        }
        o.state = OffsetPath::Diverged;
        o.beta = Spectrum(w2);
        o.found = scene.intersect(o.ray, &o.isect);
        o.cls = classify(o.found, o.isect, &o.bsdf);
    }

    Spectrum beta(w), primal(0);
    bool specularBounce = true;
    Float prevBsdfPdf = 1;  // the camera segment acts as a specular technique with pdf 1
    Interaction prevIt;
    Float etaScale = 1;
    SurfaceInteraction isect;
    bool found = scene.intersect(ray, &isect);
    BSDF bsdf;
    ShiftVertexClass cls = classify(found, isect, &bsdf);

    for (int bounces = 0;; ++bounces) {
        // Invertibility: a diverged offset vertex must be classified like the base's,
        // or the inverse shift would take a different branch.
        for (OffsetPath &o : off)
            if (o.state == OffsetPath::Diverged && o.cls != cls) o.kill(st, ShiftFailure::ClassMismatch);

        // ---- Emission reached by the last segment (BSDF technique) ----
        {
            const Light *keys[8];
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
            addKeysOf(found, isect);
            for (const OffsetPath &o : off)
                if (o.state == OffsetPath::Diverged) addKeysOf(o.found, o.isect);
            // Emitted radiance of `light` at the end of a segment, and its NEE pdf (solid angle).
            auto emitted = [&](const Light *light, bool f, const SurfaceInteraction &si, const Ray &r,
                               const Interaction &from, bool specular, Float *lightPdf) -> Spectrum {
                *lightPdf = 0;
                Spectrum Le(0);
                if (f) {
                    if (si.areaLight != light) return Le;
                    Le = si.Le(-r.d);
                } else {
                    if (!(light->flags & LIGHT_INFINITE)) return Le;
                    Le = light->Le(r);
                }
                if (!specular && !Le.isBlack()) *lightPdf = lightSampler_.pmf(from.p, light) * light->pdfLi(from, r.d);
                return Le;
            };
            for (int i = 0; i < nkeys; ++i) {
                const Light *light = keys[i];
                Float nx;
                Spectrum Lx = emitted(light, found, isect, ray, prevIt, specularBounce, &nx);
                Float bx = prevBsdfPdf;
                Spectrum Cx = beta * Lx;
                if (!Lx.isBlack()) primal += Cx * (specularBounce ? 1 : PowerHeuristic(1, bx, 1, nx));
                for (int k = 0; k < kNumNeighbours; ++k) {
                    if (!inside[k]) continue;
                    OffsetPath &o = off[k];
                    Spectrum Cy(0);
                    Float ny = 0, by = 0;
                    switch (o.state) {
                    case OffsetPath::Dead: break;
                    case OffsetPath::Identical:
                        Cy = o.beta * Lx;
                        ny = nx;
                        by = bx;
                        break;
                    case OffsetPath::Reconnected: {
                        Ray ry(o.prevIt.p, (found ? isect.p - o.prevIt.p : ray.d), Infinity);
                        ry.d = Normalize(ry.d);
                        Cy = o.beta * emitted(light, found, isect, ry, o.prevIt, o.lastSpecular, &ny);
                        by = o.lastPdfY;
                        break;
                    }
                    case OffsetPath::Diverged:
                        Cy = o.beta * emitted(light, o.found, o.isect, o.ray, o.prevIt, o.lastSpecular, &ny);
                        by = o.lastPdfY;
                        break;
                    }
                    if (Cx.isBlack() && Cy.isBlack()) continue;
                    Float wgt = GradientMISWeight(bx, nx, by, ny, o.ratio * o.lastJ);
                    o.diff += (Cy - Cx) * wgt;
                }
            }
            // Commit the last segment's pdf ratio (G-BDPT Eq. 8 uses full-path pdfs).
            for (OffsetPath &o : off)
                if (o.state != OffsetPath::Dead) o.ratio *= o.lastPdfY * o.lastJ / prevBsdfPdf;
        }

        if (!found || bounces >= maxDepth_) break;
        for (OffsetPath &o : off)
            if (o.state == OffsetPath::Diverged && !o.found) o.kill(st, ShiftFailure::Escaped);

        if (!isect.material) {  // interface: only identical offsets can follow
            for (OffsetPath &o : off)
                if (o.state == OffsetPath::Diverged || o.state == OffsetPath::Reconnected)
                    o.kill(st, ShiftFailure::Geometry);
            ray = isect.spawnRay(ray.d);
            found = scene.intersect(ray, &isect);
            cls = classify(found, isect, &bsdf);
            // Re-entering the emission step commits a neutral ratio for this segment.
            for (OffsetPath &o : off) o.lastJ = 1, o.lastPdfY = prevBsdfPdf;
            --bounces;
            continue;
        }
        if (!bsdf) break;
        const Vec3 wo = isect.wo;

        // ---- Next-event estimation ----
        if (bsdf.hasNonSpecular() && !scene.lights.empty()) {
            Float pmf;
            const Light *light = lightSampler_.sample(isect.p, sampler.get1D(), &pmf);
            Point2 uLight = sampler.get2D();
            LightLiSample ls;
            if (light && pmf > 0 && light->sampleLi(isect, uLight, &ls) && ls.pdf > 0) {
                const bool delta = IsDeltaLight(light->flags);
                Float nx = pmf * ls.pdf;
                Float bx = delta ? 0 : bsdf.pdf(wo, ls.wi);
                Spectrum fx = bsdf.f(wo, ls.wi) * AbsDot(ls.wi, isect.shading.n);
                bool visX = !fx.isBlack() && !ls.L.isBlack() && scene.unoccluded(isect, ls.pLight);
                Spectrum Cx = visX ? beta * fx * ls.L / nx : Spectrum(0);
                if (visX) primal += Cx * (delta ? 1 : PowerHeuristic(1, nx, 1, bx));
                for (int k = 0; k < kNumNeighbours; ++k) {
                    if (!inside[k]) continue;
                    OffsetPath &o = off[k];
                    Spectrum Cy(0);
                    Float ny = 0, by = 0, J = 1;
                    if (o.state == OffsetPath::Identical) {
                        Cy = visX ? o.beta * fx * ls.L / nx : Spectrum(0);
                        ny = nx;
                        by = bx;
                    } else if (o.state == OffsetPath::Reconnected) {
                        Spectrum fy = bsdf.f(o.wo, ls.wi) * AbsDot(ls.wi, isect.shading.n);
                        ny = nx;
                        by = delta ? 0 : bsdf.pdf(o.wo, ls.wi);
                        if (visX) Cy = o.beta * fy * ls.L / nx;
                        else if (!fy.isBlack() && fx.isBlack() && !ls.L.isBlack() &&
                                 scene.unoccluded(isect, ls.pLight))
                            Cy = o.beta * fy * ls.L / nx;
                    } else if (o.state == OffsetPath::Diverged && o.bsdf.hasNonSpecular()) {
                        const Vec3 woY = o.isect.wo;
                        // The offset keeps the base's light; its own selection pmf enters the MIS only.
                        const Float pmfY = lightSampler_.pmf(o.isect.p, light);
                        Vec3 wiY;
                        Spectrum Ly;
                        Interaction pLy;
                        if (light->flags & LIGHT_AREA) {
                            ShiftVertex target{ls.pLight.p, ls.pLight.n, nullptr, false};
                            ReconnectionShift rc;
                            if (ShiftReconnect(isect.p, o.isect.p, target, &rc)) {
                                wiY = rc.wi;
                                J = rc.jacobian;
                                Ly = static_cast<const AreaLight *>(light)->L(ls.pLight, -wiY);
                                ny = pmfY * light->pdfLi(o.isect, wiY);
                                pLy = ls.pLight;
                            }
                        } else if (light->flags & LIGHT_INFINITE) {
                            wiY = ls.wi;  // environment shift: same direction, |T'| = 1
                            Ly = ls.L;
                            ny = pmfY * light->pdfLi(o.isect, wiY);
                            pLy = Interaction(o.isect.p + (ls.pLight.p - isect.p), ls.pLight.n, Vec3());
                        } else {  // delta lights: same position or direction
                            LightLiSample lsy;
                            if (light->sampleLi(o.isect, uLight, &lsy) && lsy.pdf > 0) {
                                wiY = lsy.wi;
                                Ly = lsy.L;
                                ny = pmfY * lsy.pdf;
                                pLy = lsy.pLight;
                            }
                        }
                        if (ny > 0) {
                            by = delta ? 0 : o.bsdf.pdf(woY, wiY);
                            Spectrum fy = o.bsdf.f(woY, wiY) * AbsDot(wiY, o.isect.shading.n);
                            if (!fy.isBlack() && !Ly.isBlack() && scene.unoccluded(o.isect, pLy))
                                Cy = o.beta * fy * Ly * (J / nx);
                        }
                    }
                    if (Cx.isBlack() && Cy.isBlack()) continue;
                    Float wgt = GradientMISWeight(nx, bx, ny, by, o.ratio * J);
                    o.diff += (Cy - Cx) * wgt;
                }
            }
        } else if (bsdf.hasNonSpecular()) {
            sampler.get1D();
            sampler.get2D();
        }

        // ---- BSDF sampling: base direction, then the shifts ----
        Float uc = sampler.get1D();
        Point2 u = sampler.get2D();
        BSDFSample bs;
        if (!bsdf.sample(wo, uc, u, TransportMode::Radiance, &bs) || !bs.valid()) break;
        Float cosX = AbsDot(bs.wi, isect.shading.n);
        Spectrum factor = bs.f * (cosX / bs.pdf);
        Ray nextRay = isect.spawnRay(bs.wi);
        SurfaceInteraction next;
        bool nextFound = scene.intersect(nextRay, &next);
        BSDF nextBsdf;
        ShiftVertexClass nextCls = classify(nextFound, next, &nextBsdf);

        for (OffsetPath &o : off) {
            switch (o.state) {
            case OffsetPath::Dead: break;
            case OffsetPath::Identical:
                o.beta *= factor;
                o.lastPdfY = bs.pdf;
                o.lastJ = 1;
                o.lastSpecular = bs.isSpecular();
                o.prevIt = isect;
                break;
            case OffsetPath::Reconnected: {
                // Same point and outgoing direction as the base; only wo differs.
                Spectrum fy = bsdf.f(o.wo, bs.wi);
                Float by = bsdf.pdf(o.wo, bs.wi);
                if (fy.isBlack() || !(by > 0)) {
                    o.kill(st, ShiftFailure::Geometry);
                    break;
                }
                o.beta *= fy * (cosX / bs.pdf);
                o.lastPdfY = by;
                o.lastJ = 1;
                o.lastSpecular = false;
                o.prevIt = isect;
                o.state = OffsetPath::Identical;
                break;
            }
            case OffsetPath::Diverged: {
                const Vec3 woY = o.isect.wo;
                const Normal3 nsY = o.isect.shading.n;
                bool reconnect = cls == ShiftVertexClass::Rough && nextCls == ShiftVertexClass::Rough;
                if (reconnect) {
                    ShiftType type = nextFound ? ShiftType::Reconnection : ShiftType::Environment;
                    st.attempt(type);
                    ShiftVertex target;
                    target.atInfinity = !nextFound;
                    target.p = nextFound ? next.p : bs.wi;
                    target.n = nextFound ? next.n : Normal3(0, 0, 0);
                    ReconnectionShift rc;
                    if (!ShiftReconnect(isect.p, o.isect.p, target, &rc)) {
                        o.kill(st, ShiftFailure::Geometry);
                        break;
                    }
                    Spectrum fy = o.bsdf.f(woY, rc.wi);
                    Float by = o.bsdf.pdf(woY, rc.wi);
                    if (fy.isBlack() || !(by > 0)) {
                        o.kill(st, ShiftFailure::Geometry);
                        break;
                    }
                    bool visible = nextFound ? scene.unoccluded(o.isect, next)
                                             : !scene.occluded(o.isect.spawnRay(rc.wi));
                    if (!visible) {
                        o.kill(st, ShiftFailure::Occluded);
                        break;
                    }
                    st.success(type);
                    o.beta *= fy * (AbsDot(rc.wi, nsY) * rc.jacobian / bs.pdf);
                    o.lastPdfY = by;
                    o.lastJ = rc.jacobian;
                    o.lastSpecular = false;
                    o.prevIt = o.isect;
                    o.wo = -rc.wi;
                    o.state = OffsetPath::Reconnected;
                    break;
                }
                Vec3 wiY;
                if (bs.isSpecular() || mode_ == ShiftMode::Hybrid) {
                    st.attempt(ShiftType::Replay);
                    ReplayShift rp;
                    if (!ShiftReplay(o.bsdf, woY, uc, u, bs.pdf, TransportMode::Radiance, &rp)) {
                        o.kill(st, ShiftFailure::Geometry);
                        break;
                    }
                    st.success(ShiftType::Replay);
                    wiY = rp.sample.wi;
                    // f(y)|T'|/p(x) = f(y)/p_y; the pdf ratio p_y|T'|/p_x is 1.
                    o.beta *= rp.sample.f * (AbsDot(wiY, nsY) / rp.sample.pdf);
                    o.lastPdfY = rp.sample.pdf;
                    o.lastJ = rp.jacobian;
                    o.lastSpecular = rp.sample.isSpecular();
                } else {
                    st.attempt(ShiftType::HalfVector);
                    HalfVectorShift hv;
                    if (!ShiftHalfVector(bsdf.toLocal(wo), bsdf.toLocal(bs.wi), o.bsdf.toLocal(woY), bs.eta, &hv)) {
                        o.kill(st, ShiftFailure::Geometry);
                        break;
                    }
                    wiY = o.bsdf.toWorld(hv.wi);
                    Spectrum fy = o.bsdf.f(woY, wiY);
                    Float by = o.bsdf.pdf(woY, wiY);
                    if (fy.isBlack() || !(by > 0)) {
                        o.kill(st, ShiftFailure::Geometry);
                        break;
                    }
                    st.success(ShiftType::HalfVector);
                    o.beta *= fy * (AbsDot(wiY, nsY) * hv.jacobian / bs.pdf);
                    o.lastPdfY = by;
                    o.lastJ = hv.jacobian;
                    o.lastSpecular = false;
                }
                o.prevIt = o.isect;
                o.ray = o.isect.spawnRay(wiY);
                o.found = scene.intersect(o.ray, &o.isect);
                o.cls = classify(o.found, o.isect, &o.bsdf);
                break;
            }
            }
        }

        beta *= factor;
        specularBounce = bs.isSpecular();
        prevBsdfPdf = bs.pdf;
        prevIt = isect;
        if (bs.isTransmission()) etaScale *= Sqr(bs.eta);
        ray = nextRay;
        isect = next;
        found = nextFound;
        bsdf = nextBsdf;
        cls = nextCls;

        // Russian roulette on the base; offsets follow its decision.
        Spectrum rrBeta = beta * etaScale;
        Float uRR = sampler.get1D();
        if (rrBeta.maxComponent() < rrThreshold_ && bounces > 3) {
            Float q = std::max<Float>(0.05, 1 - rrBeta.maxComponent());
            if (uRR < q) break;
            beta = beta / (1 - q);
            for (OffsetPath &o : off) o.beta = o.beta / (1 - q);
        }
        if (beta.isBlack()) break;
    }

    out.primal = primal;
    for (int k = 0; k < kNumNeighbours; ++k) out.diff[k] = off[k].diff;
    stats_.add(st);
    return out;
}

}  // namespace gradus
