#include "integrators/gpt/gpt_volume.h"

#include <algorithm>

#include "core/stats.h"
#include "samplers/sampling.h"

namespace gradus::gpt {

Spectrum VolumeVertex::f(const Vec3 &wo, const Vec3 &wi) const {
    if (kind == InMedium) return Spectrum(mi.phase.p(wo, wi));
    return bsdf.f(wo, wi) * AbsDot(wi, isect.shading.n);
}

Float VolumeVertex::pdf(const Vec3 &wo, const Vec3 &wi) const {
    return kind == InMedium ? mi.phase.p(wo, wi) : bsdf.pdf(wo, wi);
}

namespace {

// Emitted radiance of `light` reached by a vertex v along v.ray, and its
// next-event density (solid angle) from `from`.
Spectrum Emitted(const LightSampler &lights, const Light *light, const VolumeVertex &v, const Vec3 &d,
                 const Interaction &from, bool specular, Float *lightPdf) {
    *lightPdf = 0;
    Spectrum Le(0);
    if (v.kind == VolumeVertex::Surface) {
        if (v.isect.areaLight != light) return Le;
        Le = v.isect.Le(-d);
    } else if (v.kind == VolumeVertex::Infinity) {
        if (!(light->flags & LIGHT_INFINITE)) return Le;
        Le = light->Le(Ray(from.p, d));
    } else {
        return Le;
    }
    if (!specular && !Le.isBlack()) *lightPdf = lights.pmf(from.p, light) * light->pdfLi(from, d);
    return Le;
}

}  // namespace

void VolumeGradientPathTracer::classify(VolumeVertex *v) const {
    v->bsdf = BSDF();
    if (v->kind != VolumeVertex::Surface) {
        v->cls = ShiftVertexClass::Rough;  // phase functions and points at infinity
        return;
    }
    if (!v->isect.material) {
        v->cls = ShiftVertexClass::Invalid;
        return;
    }
    v->bsdf = v->isect.material->getBSDF(v->isect, arena_, TransportMode::Radiance);
    v->cls = ClassifyBSDF(&v->bsdf, threshold_);
}

bool VolumeGradientPathTracer::start(const CameraSample &cs, GradientSample *out) {
    Float w = scene_.camera->generateRay(cs, &ray_);
    if (w == 0) return false;
    medium_ = scene_.cameraMedium;
    for (int k = 0; k < kNumNeighbours; ++k) {
        out->active[k] = inside_[k];
        if (!inside_[k]) continue;
        VolumeOffset &o = off_[k];
        ++st_.offsetPaths;
        CameraSample c2 = cs;
        c2.pFilm = Point2(cs.pFilm.x + kNeighbourOffsets[k].x, cs.pFilm.y + kNeighbourOffsets[k].y);
        Float w2 = scene_.camera->generateRay(c2, &o.ray);
        if (w2 == 0) {
            o.kill(st_, ShiftFailure::Geometry);
            continue;
        }
        o.state = OffsetPath::Diverged;
        o.beta = Spectrum(w2);
        o.medium = scene_.cameraMedium;
    }
    beta_ = Spectrum(w);
    return true;
}

// The base from its scattering vertex to the next one (path's LiVolumetric
// loop: distance sampling per segment, interfaces crossed without a bounce).
VolumeGradientPathTracer::Event VolumeGradientPathTracer::walkBase(int bounces, int maxDepth) {
    GRADUS_STAT_COUNTER("G-PT/Paths ended at the interface-crossing limit", nStuck);
    nSeg_ = 0;
    Ray ray = ray_;
    const Medium *m = medium_;
    for (int crossings = 0;;) {
        SurfaceInteraction isect;
        const bool found = scene_.intersect(ray, &isect);
        MediumInteraction mi;
        BaseSegment &s = seg_[nSeg_++];
        s.ray = ray;
        s.medium = m;
        s.factor = Spectrum(1);
        if (m) {
            Ray seg = ray;
            seg.tMax = found ? Dot(isect.p - ray.o, ray.d) / ray.d.lengthSquared() : Infinity;
            s.factor = m->sample(seg, rng_, &mi);
        }
        beta_ *= s.factor;
        if (beta_.isBlack() || !beta_.isFinite()) return Event::End;
        if (mi.valid()) {
            s.end = BaseSegment::Scatter;
            s.dist = Distance(ray.o, mi.p);
            next_.kind = VolumeVertex::InMedium;
            next_.mi = mi;
        } else if (!found) {
            s.end = BaseSegment::Escape;
            s.dist = Infinity;
            next_.kind = VolumeVertex::Infinity;
        } else {
            s.dist = Distance(ray.o, isect.p);
            if (!isect.material) {  // interface
                s.end = BaseSegment::Crossing;
                if (isect.areaLight && !isect.Le(-ray.d).isBlack()) {
                    // Primal only (gpt_volume.h, limitation), weighted as path does.
                    const Spectrum Le = isect.Le(-ray.d);
                    Spectrum c = beta_ * Le;
                    if (!specularBounce_) {
                        const Float lp = lights_.pmf(prevIt_.p, isect.areaLight) * isect.areaLight->pdfLi(prevIt_, ray.d);
                        c = c * PowerHeuristic(1, prevPdf_, 1, lp);
                    }
                    primal_ += c;
                    if (diracChain_) separated_ += c;
                }
                if (bounces >= maxDepth) return Event::End;
                if (++crossings > kMaxInterfaceCrossings || nSeg_ >= kMaxMediumPieces) {
                    ++nStuck;
                    return Event::End;
                }
                m = isect.mediumAfter(ray.d, m);
                ray = isect.spawnRay(ray.d);
                continue;
            }
            s.end = BaseSegment::Hit;
            next_.kind = VolumeVertex::Surface;
            next_.isect = isect;
        }
        next_.ray = ray;
        next_.arriving = m;
        classify(&next_);
        return s.end == BaseSegment::Scatter ? Event::Scatter
                                             : (s.end == BaseSegment::Escape ? Event::Escape : Event::Hit);
    }
}

// The product of the base's segment factors of this step.
Spectrum VolumeGradientPathTracer::segmentsFactor() const {
    Spectrum f(1);
    for (int j = 0; j < nSeg_; ++j) f *= seg_[j].factor;
    return f;
}

// A diverged offset walks its own segments in lockstep with the base's.
bool VolumeGradientPathTracer::walkOffset(VolumeOffset &o) {
    for (int j = 0; j < nSeg_; ++j) {
        const BaseSegment &s = seg_[j];
        SurfaceInteraction isect;
        const bool found = scene_.intersect(o.ray, &isect);
        const Vec3 dy = Normalize(o.ray.d);
        const Float sy = found ? Distance(o.ray.o, isect.p) : Infinity;
        const MediumPiece px = s.piece();
        MediumPiece py{o.ray.o, dy, sy, o.medium};
        switch (s.end) {
        case BaseSegment::Crossing:
            if (!found || isect.material) {
                o.kill(st_, ShiftFailure::Escaped);
                return false;
            }
            o.beta *= s.factor * TransmittanceRatio(&py, 1, &px, 1, rng_);
            o.medium = isect.mediumAfter(o.ray.d, o.medium);
            o.ray = isect.spawnRay(o.ray.d);
            break;
        case BaseSegment::Scatter: {
            // Free-flight distance copied along the offset's ray (|T'| = 1).
            if (o.medium != s.medium || !(s.dist < sy)) {
                o.kill(st_, ShiftFailure::Escaped);
                return false;
            }
            const Point3 y = o.ray.o + dy * s.dist;
            const Float sigY = s.medium->sigmaTAt(y).maxComponent();
            const Float sigX = s.medium->sigmaTAt(next_.mi.p).maxComponent();
            if (!(sigY > 0) || !(sigX > 0)) {
                o.kill(st_, ShiftFailure::Geometry);
                return false;
            }
            py.len = s.dist;
            // sigma_s(y) / sigma_s(x): a grid scales every channel by its density.
            o.beta *= s.factor * TransmittanceRatio(&py, 1, &px, 1, rng_) * (sigY / sigX);
            o.v.kind = VolumeVertex::InMedium;
            o.v.mi = MediumInteraction();
            o.v.mi.p = y;
            o.v.mi.n = Normal3(0, 0, 0);
            o.v.mi.wo = -dy;
            o.v.mi.medium = s.medium;
            o.v.mi.phase = s.medium->phase;
            break;
        }
        case BaseSegment::Hit:
            if (!found || !isect.material) {
                o.kill(st_, ShiftFailure::Escaped);
                return false;
            }
            o.beta *= s.factor * TransmittanceRatio(&py, 1, &px, 1, rng_);
            o.v.kind = VolumeVertex::Surface;
            o.v.isect = isect;
            break;
        case BaseSegment::Escape:
            if (found) {
                o.kill(st_, ShiftFailure::Escaped);
                return false;
            }
            o.beta *= s.factor * TransmittanceRatio(&py, 1, &px, 1, rng_);
            o.v.kind = VolumeVertex::Infinity;
            break;
        }
    }
    o.v.ray = o.ray;
    o.v.arriving = o.medium;
    classify(&o.v);
    return true;
}

// Straight pieces from `from` towards the base's next vertex (or direction wi
// at infinity) through interfaces; 0 when a surface with a material blocks it
// (gradient/medium_shift.h, shared with gbdpt's shifts).
int VolumeGradientPathTracer::tracePieces(const VolumeVertex &from, const Vec3 &wi, MediumPiece *pieces) const {
    return TraceSegmentPieces(scene_, from.it(), from.leaving(wi), next_.it(), next_.kind == VolumeVertex::Infinity,
                              wi, pieces);
}

bool VolumeGradientPathTracer::edgeFree(const Interaction &a, bool aSurface, const Interaction &b, bool bSurface,
                                        const Vec3 &d) const {
    return !(aSurface && InTangentPlane(a.n, d)) && !(bSurface && InTangentPlane(b.n, d));
}

// Diverged offset, base vertices cur_ and next_ both rough: reconnection to next_.
void VolumeGradientPathTracer::reconnect(VolumeOffset &o) {
    const bool atInf = next_.kind == VolumeVertex::Infinity;
    const ShiftType type = atInf ? ShiftType::Environment : ShiftType::Reconnection;
    st_.attempt(type);
    ShiftVertex target;
    target.atInfinity = atInf;
    target.p = atInf ? Point3(wi_) : next_.it().p;
    target.n = next_.kind == VolumeVertex::Surface ? next_.isect.n : Normal3(0, 0, 0);  // no cosine at medium points
    ReconnectionShift rc;
    const Interaction &yIt = o.v.it();
    if (!ShiftReconnect(cur_.it().p, yIt.p, target, &rc)) {
        o.kill(st_, ShiftFailure::Geometry);
        return;
    }
    const Vec3 woY = yIt.wo;
    const Spectrum fy = o.v.f(woY, rc.wi);
    const Float by = o.v.pdf(woY, rc.wi);
    if (fy.isBlack() || !(by > 0)) {
        o.kill(st_, ShiftFailure::Geometry);
        return;
    }
    MediumPiece ypieces[kMaxMediumPieces], xpieces[kMaxMediumPieces];
    const int ny = edgeFree(yIt, o.v.kind == VolumeVertex::Surface, next_.it(), next_.kind == VolumeVertex::Surface,
                            rc.wi)
                       ? tracePieces(o.v, rc.wi, ypieces)
                       : 0;
    // The offset must arrive in the medium the base arrives in.
    if (ny == 0 || ypieces[ny - 1].medium != seg_[nSeg_ - 1].medium) {
        o.kill(st_, ShiftFailure::Occluded);
        return;
    }
    for (int j = 0; j < nSeg_; ++j) xpieces[j] = seg_[j].piece();
    const Spectrum R = TransmittanceRatio(ypieces, ny, xpieces, nSeg_, rng_);
    st_.success(type);
    o.beta *= fy * (rc.jacobian / pdfX_) * segmentsFactor() * R;
    o.lastPdfY = by;
    o.lastJ = rc.jacobian;
    o.lastSpecular = false;
    o.prevIt = yIt;
    o.wo = -rc.wi;
    o.state = OffsetPath::Reconnected;
}

// Diverged offset that does not reconnect: its direction at its own vertex.
bool VolumeGradientPathTracer::shiftDirection(VolumeOffset &o, Vec3 *wiY) {
    const Vec3 woY = o.v.it().wo;
    if (o.v.kind == VolumeVertex::InMedium) {
        // The same world direction (|T'| = 1); the base's factor is phase / pdf = 1.
        st_.attempt(ShiftType::HalfVector);
        const Float py = o.v.mi.phase.p(woY, wi_);
        if (!(py > 0)) {
            o.kill(st_, ShiftFailure::Geometry);
            return false;
        }
        st_.success(ShiftType::HalfVector);
        *wiY = wi_;
        o.beta *= Spectrum(py / pdfX_);
        o.lastPdfY = py;
        o.lastJ = 1;
        o.lastSpecular = false;
        return true;
    }
    const Normal3 nsY = o.v.isect.shading.n;
    if (bs_.isSpecular() || hybrid_) {
        st_.attempt(ShiftType::Replay);
        ReplayShift rp;
        if (!ShiftReplay(o.v.bsdf, woY, uc_, u_, bs_.pdf, TransportMode::Radiance, &rp)) {
            o.kill(st_, ShiftFailure::Geometry);
            return false;
        }
        st_.success(ShiftType::Replay);
        *wiY = rp.sample.wi;
        o.beta *= rp.sample.f * (AbsDot(*wiY, nsY) / rp.sample.pdf);
        o.lastPdfY = rp.sample.pdf;
        o.lastJ = rp.jacobian;
        o.lastSpecular = rp.sample.isSpecular();
        return true;
    }
    st_.attempt(ShiftType::HalfVector);
    HalfVectorShift hv;
    const BSDF &bx = cur_.bsdf;
    if (!ShiftHalfVector(bx.toLocal(cur_.isect.wo), bx.toLocal(bs_.wi), o.v.bsdf.toLocal(woY), bs_.eta, &hv)) {
        o.kill(st_, ShiftFailure::Geometry);
        return false;
    }
    *wiY = o.v.bsdf.toWorld(hv.wi);
    const Spectrum fy = o.v.bsdf.f(woY, *wiY);
    const Float by = o.v.bsdf.pdf(woY, *wiY);
    if (fy.isBlack() || !(by > 0)) {
        o.kill(st_, ShiftFailure::Geometry);
        return false;
    }
    st_.success(ShiftType::HalfVector);
    o.beta *= fy * (AbsDot(*wiY, nsY) * hv.jacobian / bs_.pdf);
    o.lastPdfY = by;
    o.lastJ = hv.jacobian;
    o.lastSpecular = false;
    return true;
}

// The offset from the base's step cur_ -> next_.
void VolumeGradientPathTracer::advanceOffset(VolumeOffset &o) {
    switch (o.state) {
    case OffsetPath::Dead: return;
    case OffsetPath::Identical:
        o.beta *= scatterFactor_ * segmentsFactor();
        o.lastPdfY = pdfX_;
        o.lastJ = 1;
        o.lastSpecular = bs_.isSpecular() && cur_.kind == VolumeVertex::Surface;
        o.prevIt = cur_.it();
        break;
    case OffsetPath::Reconnected: {
        const Spectrum fy = cur_.f(o.wo, wi_);
        const Float by = cur_.pdf(o.wo, wi_);
        if (fy.isBlack() || !(by > 0)) {
            o.kill(st_, ShiftFailure::Geometry);
            return;
        }
        o.beta *= fy * (1 / pdfX_) * segmentsFactor();
        o.lastPdfY = by;
        o.lastJ = 1;
        o.lastSpecular = false;
        o.prevIt = cur_.it();
        o.state = OffsetPath::Identical;
        break;
    }
    case OffsetPath::Diverged:
        if (atCamera_) {
            walkOffset(o);
            return;  // the camera segment: the Dirac chain goes on
        }
        if (cur_.cls == ShiftVertexClass::Rough && next_.cls == ShiftVertexClass::Rough) {
            reconnect(o);
        } else {
            Vec3 wiY;
            if (!shiftDirection(o, &wiY)) return;
            o.prevIt = o.v.it();
            o.medium = o.v.leaving(wiY);
            o.ray = o.v.it().spawnRay(wiY);
            walkOffset(o);
        }
        break;
    }
    o.diracChain = o.diracChain && o.state != OffsetPath::Dead && o.lastSpecular;
}

// Emission reached by the last segment (BSDF/phase technique); gpt_terms.cpp's
// scheme (separated light, gradient MIS), then the segment's ratio is committed.
void VolumeGradientPathTracer::emissionTerms() {
    const Light *keys[8];
    int nkeys = 0;
    auto addKey = [&](const Light *l) {
        for (int i = 0; i < nkeys; ++i)
            if (keys[i] == l) return;
        if (nkeys < 8) keys[nkeys++] = l;
    };
    auto addKeysOf = [&](const VolumeVertex &v) {
        if (v.kind == VolumeVertex::Surface && v.isect.areaLight) addKey(v.isect.areaLight);
        if (v.kind == VolumeVertex::Infinity)
            for (const Light *l : scene_.infiniteLights) addKey(l);
    };
    addKeysOf(cur_);
    for (const VolumeOffset &o : off_)
        if (o.state == OffsetPath::Diverged) addKeysOf(o.v);
    const Vec3 dX = Normalize(cur_.ray.d);
    for (int i = 0; i < nkeys; ++i) {
        const Light *light = keys[i];
        Float nx;
        const Spectrum Lx = Emitted(lights_, light, cur_, dX, prevIt_, specularBounce_, &nx);
        const Float bx = prevPdf_;
        Spectrum Cx = beta_ * Lx;
        if (!Lx.isBlack()) {
            const Spectrum c = Cx * (specularBounce_ ? 1 : PowerHeuristic(1, bx, 1, nx));
            primal_ += c;
            if (diracChain_) separated_ += c;
        }
        if (diracChain_) Cx = Spectrum(0);
        for (int k = 0; k < kNumNeighbours; ++k) {
            if (!inside_[k]) continue;
            VolumeOffset &o = off_[k];
            Float ny = 0, by = 0;
            Spectrum Cy(0);
            if (o.state == OffsetPath::Identical) {
                ny = nx;
                by = bx;
                Cy = o.beta * Lx;
            } else if (o.state == OffsetPath::Reconnected) {
                const Vec3 d = cur_.kind == VolumeVertex::Infinity ? dX : Normalize(cur_.it().p - o.prevIt.p);
                Cy = o.beta * Emitted(lights_, light, cur_, d, o.prevIt, o.lastSpecular, &ny);
                by = o.lastPdfY;
            } else if (o.state == OffsetPath::Diverged) {
                Cy = o.beta * Emitted(lights_, light, o.v, Normalize(o.v.ray.d), o.prevIt, o.lastSpecular, &ny);
                by = o.lastPdfY;
            }
            if (o.diracChain) Cy = Spectrum(0);
            if (Cx.isBlack() && Cy.isBlack()) continue;
            o.diff += (Cy - Cx) * GradientMISWeight(bx, nx, by, ny, o.ratio * o.lastJ);
        }
    }
}

// A diverged offset connects its own vertex to the base's light sample.
Spectrum VolumeGradientPathTracer::divergedNextEvent(const VolumeOffset &o, const LightChoice &lc, Float *ny,
                                                     Float *by, Float *J) {
    const Light *light = lc.light;
    const LightLiSample &ls = lc.ls;
    const Interaction &yIt = o.v.it();
    const Vec3 woY = yIt.wo;
    const Float pmfY = lights_.pmf(yIt.p, light);
    Vec3 wiY;
    Spectrum Ly;
    Interaction pLy;
    if (light->flags & LIGHT_AREA) {
        ShiftVertex target{ls.pLight.p, ls.pLight.n, nullptr, false};
        ReconnectionShift rc;
        if (ShiftReconnect(cur_.it().p, yIt.p, target, &rc)) {
            wiY = rc.wi;
            *J = rc.jacobian;
            Ly = static_cast<const AreaLight *>(light)->L(ls.pLight, -wiY);
            *ny = pmfY * light->pdfLi(yIt, wiY);
            pLy = ls.pLight;
        }
    } else if (light->flags & LIGHT_INFINITE) {
        wiY = ls.wi;
        Ly = ls.L;
        *ny = pmfY * light->pdfLi(yIt, wiY);
        pLy = Interaction(yIt.p + (ls.pLight.p - cur_.it().p), ls.pLight.n, Vec3());
    } else {
        LightLiSample lsy;
        if (light->sampleLi(yIt, lc.u, &lsy) && lsy.pdf > 0) {
            wiY = lsy.wi;
            Ly = lsy.L;
            *ny = pmfY * lsy.pdf;
            pLy = lsy.pLight;
        }
    }
    if (!(*ny > 0)) return Spectrum(0);
    *by = lc.delta ? 0 : o.v.pdf(woY, wiY);
    const Spectrum fy = o.v.f(woY, wiY);
    if (fy.isBlack() || Ly.isBlack() || !edgeFree(yIt, o.v.kind == VolumeVertex::Surface, pLy, true, wiY))
        return Spectrum(0);
    const Spectrum tr = scene_.transmittance(yIt, o.v.leaving(wiY), pLy, rng_);
    return o.beta * fy * Ly * tr * (*J / lc.nx);
}

// Next-event estimation at the base vertex (surface or medium): primal and
// gradient terms. Sampler use as path's: 1D (light) + 2D (point).
void VolumeGradientPathTracer::nextEventTerms(Sampler &sampler) {
    if (!cur_.hasNonSpecular()) return;
    if (scene_.lights.empty()) {
        sampler.get1D();
        sampler.get2D();
        return;
    }
    const Interaction &it = cur_.it();
    LightChoice lc;
    Float pmf;
    lc.light = lights_.sample(it.p, sampler.get1D(), &pmf);
    lc.u = sampler.get2D();
    if (!lc.light || !(pmf > 0)) return;
    lc.light->sampleLi(it, lc.u, &lc.ls);  // offsets are evaluated also when the base gets no radiance
    if (!(lc.ls.pdf > 0)) return;
    const LightLiSample &ls = lc.ls;
    const Vec3 wo = it.wo;
    const bool surface = cur_.kind == VolumeVertex::Surface;
    lc.delta = IsDeltaLight(lc.light->flags);
    lc.nx = pmf * ls.pdf;
    lc.bx = lc.delta ? 0 : cur_.pdf(wo, ls.wi);
    lc.fx = cur_.f(wo, ls.wi);
    // The shadow ray's transmittance, shared by the offsets through this vertex.
    bool trDone = false;
    Spectrum tr(0);
    auto shadowTr = [&]() {
        if (!trDone) {
            trDone = true;
            if (!ls.L.isBlack() && edgeFree(it, surface, ls.pLight, true, ls.wi))
                tr = scene_.transmittance(it, cur_.leaving(ls.wi), ls.pLight, rng_);
        }
        return tr;
    };
    Spectrum Cx(0);
    if (!lc.fx.isBlack() && !ls.L.isBlack()) Cx = beta_ * lc.fx * ls.L * shadowTr() / lc.nx;
    if (!Cx.isBlack()) primal_ += Cx * (lc.delta ? 1 : PowerHeuristic(1, lc.nx, 1, lc.bx));
    for (int k = 0; k < kNumNeighbours; ++k) {
        if (!inside_[k]) continue;
        VolumeOffset &o = off_[k];
        Float ny = 0, by = 0, J = 1;
        Spectrum Cy(0);
        if (o.state == OffsetPath::Identical) {
            ny = lc.nx;
            by = lc.bx;
            Cy = o.beta * lc.fx * ls.L * (lc.fx.isBlack() ? Spectrum(0) : shadowTr()) / lc.nx;
        } else if (o.state == OffsetPath::Reconnected) {
            const Spectrum fy = cur_.f(o.wo, ls.wi);
            ny = lc.nx;
            by = lc.delta ? 0 : cur_.pdf(o.wo, ls.wi);
            if (!fy.isBlack() && !ls.L.isBlack()) Cy = o.beta * fy * ls.L * shadowTr() / lc.nx;
        } else if (o.state == OffsetPath::Diverged && o.v.hasNonSpecular()) {
            Cy = divergedNextEvent(o, lc, &ny, &by, &J);
        }
        if (Cx.isBlack() && Cy.isBlack()) continue;
        o.diff += (Cy - Cx) * GradientMISWeight(lc.nx, lc.bx, ny, by, o.ratio * J);
    }
}

void VolumeGradientPathTracer::trace(Sampler &sampler, int maxDepth, Float rrThreshold) {
    GRADUS_STAT_COUNTER("G-PT/Medium scattering vertices", nMediumVertices);
    for (int bounces = 0;; ++bounces) {
        const Event ev = walkBase(bounces, maxDepth);
        if (ev == Event::End) break;
        for (VolumeOffset &o : off_) advanceOffset(o);
        cur_ = next_;
        atCamera_ = false;
        // Invertibility: a diverged offset vertex must be classified like the base's.
        for (VolumeOffset &o : off_)
            if (o.state == OffsetPath::Diverged && o.v.cls != cur_.cls) o.kill(st_, ShiftFailure::ClassMismatch);
        if (ev == Event::Scatter) {
            if (bounces >= maxDepth) break;
            ++nMediumVertices;
        } else {
            emissionTerms();
        }
        // Commit the last segment's density ratio (G-BDPT Eq. 8 uses full-path densities).
        for (VolumeOffset &o : off_)
            if (o.state != OffsetPath::Dead) o.ratio *= o.lastPdfY * o.lastJ / prevPdf_;
        if (ev == Event::Escape || bounces >= maxDepth) break;
        if (ev == Event::Hit && !cur_.bsdf) break;

        nextEventTerms(sampler);

        // The scattering direction, with path's sampler use.
        if (cur_.kind == VolumeVertex::InMedium) {
            uc_ = sampler.get1D();  // the lobe choice of a surface vertex (path keeps the dimensions)
            u_ = sampler.get2D();
            const Float pdf = cur_.mi.phase.sample(cur_.mi.wo, u_, &wi_);
            if (!(pdf > 0)) break;
            bs_ = BSDFSample();
            bs_.pdf = pdf;
            bs_.wi = wi_;
            pdfX_ = pdf;
            scatterFactor_ = Spectrum(1);
            specularBounce_ = false;
        } else {
            uc_ = sampler.get1D();
            u_ = sampler.get2D();
            if (!cur_.bsdf.sample(cur_.isect.wo, uc_, u_, TransportMode::Radiance, &bs_) || !bs_.valid()) break;
            wi_ = bs_.wi;
            pdfX_ = bs_.pdf;
            scatterFactor_ = bs_.f * (AbsDot(wi_, cur_.isect.shading.n) / bs_.pdf);
            specularBounce_ = bs_.isSpecular();
            if (bs_.isTransmission()) etaScale_ *= Sqr(bs_.eta);
        }
        beta_ *= scatterFactor_;
        diracChain_ = diracChain_ && specularBounce_;
        prevPdf_ = pdfX_;
        prevIt_ = cur_.it();
        ray_ = cur_.it().spawnRay(wi_);
        medium_ = cur_.leaving(wi_);

        // Russian roulette on the base (path's); offsets follow its decision.
        const Float pSurvive = BaseRouletteSurvival(beta_ * etaScale_, bounces, rrThreshold, sampler.get1D());
        if (pSurvive == 0) break;
        if (pSurvive < 1) {
            beta_ = beta_ / pSurvive;
            for (VolumeOffset &o : off_) o.beta = o.beta / pSurvive;
        }
        if (beta_.isBlack()) break;
    }
}

void VolumeGradientPathTracer::result(GradientSample *out) const {
    out->primal = primal_;
    out->separated = separated_;
    for (int k = 0; k < kNumNeighbours; ++k) out->diff[k] = off_[k].diff;
}

}  // namespace gradus::gpt
