#include "integrators/gpt/gpt_tracer.h"

#include <algorithm>

#include "core/stats.h"

namespace gradus::gpt {

ShiftVertexClass GradientPathTracer::classify(bool found, SurfaceInteraction &si, BSDF *b) const {
    *b = BSDF();
    if (!found) return ShiftVertexClass::Rough;  // a point at infinity
    if (!si.material) return ShiftVertexClass::Invalid;
    *b = si.material->getBSDF(si, arena_, TransportMode::Radiance);
    return ClassifyBSDF(b, threshold_);
}

// Offset camera rays: the film position moves by exactly one pixel (|T'| = 1,
// equal pdfs), the lens sample is kept.
void GradientPathTracer::initOffset(const CameraSample &cs, int k) {
    OffsetPath &o = off_[k];
    ++st_.offsetPaths;
    CameraSample c2 = cs;
    c2.pFilm = Point2(cs.pFilm.x + kNeighbourOffsets[k].x, cs.pFilm.y + kNeighbourOffsets[k].y);
    Float w2 = scene_.camera->generateRay(c2, &o.ray);
    if (w2 == 0) {
        o.kill(st_, ShiftFailure::Geometry);
        return;
    }
    o.state = OffsetPath::Diverged;
    o.beta = Spectrum(w2);
    o.found = scene_.intersect(o.ray, &o.isect);
    o.cls = classify(o.found, o.isect, &o.bsdf);
}

bool GradientPathTracer::start(const CameraSample &cs, GradientSample *out) {
    Float w = scene_.camera->generateRay(cs, &cur_.ray);
    if (w == 0) return false;
    for (int k = 0; k < kNumNeighbours; ++k) {
        out->active[k] = inside_[k];
        if (inside_[k]) initOffset(cs, k);
    }
    beta_ = Spectrum(w);
    cur_.found = scene_.intersect(cur_.ray, &cur_.isect);
    cur_.cls = classify(cur_.found, cur_.isect, &cur_.bsdf);
    return true;
}

// Diverged offset at a base vertex pair that is rough-rough: reconnects to the
// base's next vertex (or direction at infinity).
void GradientPathTracer::reconnectOffset(OffsetPath &o, const BSDFSample &bs, const PathHit &next) {
    const Vec3 woY = o.isect.wo;
    const Normal3 nsY = o.isect.shading.n;
    ShiftType type = next.found ? ShiftType::Reconnection : ShiftType::Environment;
    st_.attempt(type);
    ShiftVertex target;
    target.atInfinity = !next.found;
    target.p = next.found ? next.isect.p : bs.wi;
    target.n = next.found ? next.isect.n : Normal3(0, 0, 0);
    ReconnectionShift rc;
    if (!ShiftReconnect(cur_.isect.p, o.isect.p, target, &rc)) {
        o.kill(st_, ShiftFailure::Geometry);
        return;
    }
    Spectrum fy = o.bsdf.f(woY, rc.wi);
    Float by = o.bsdf.pdf(woY, rc.wi);
    if (fy.isBlack() || !(by > 0)) {
        o.kill(st_, ShiftFailure::Geometry);
        return;
    }
    bool visible = next.found ? ShiftEdgeVisible(scene_, o.isect, next.isect) : !scene_.occluded(o.isect.spawnRay(rc.wi));
    if (!visible) {
        o.kill(st_, ShiftFailure::Occluded);
        return;
    }
    st_.success(type);
    o.beta *= fy * (AbsDot(rc.wi, nsY) * rc.jacobian / bs.pdf);
    o.lastPdfY = by;
    o.lastJ = rc.jacobian;
    o.lastSpecular = false;
    o.prevIt = o.isect;
    o.wo = -rc.wi;
    o.state = OffsetPath::Reconnected;
}

// Diverged offset that cannot reconnect yet: random replay (specular base
// lobes, or "hybrid") or half-vector copy, then its own next vertex.
void GradientPathTracer::copyHalfVectorOrReplay(OffsetPath &o, const BSDFSample &bs, Float uc, Point2 u) {
    const Vec3 woY = o.isect.wo;
    const Normal3 nsY = o.isect.shading.n;
    Vec3 wiY;
    if (bs.isSpecular() || hybrid_) {
        st_.attempt(ShiftType::Replay);
        ReplayShift rp;
        if (!ShiftReplay(o.bsdf, woY, uc, u, bs.pdf, TransportMode::Radiance, &rp)) {
            o.kill(st_, ShiftFailure::Geometry);
            return;
        }
        st_.success(ShiftType::Replay);
        wiY = rp.sample.wi;
        // f(y)|T'|/p(x) = f(y)/p_y; the pdf ratio p_y|T'|/p_x is 1.
        o.beta *= rp.sample.f * (AbsDot(wiY, nsY) / rp.sample.pdf);
        o.lastPdfY = rp.sample.pdf;
        o.lastJ = rp.jacobian;
        o.lastSpecular = rp.sample.isSpecular();
    } else {
        st_.attempt(ShiftType::HalfVector);
        HalfVectorShift hv;
        const BSDF &bsdf = cur_.bsdf;
        if (!ShiftHalfVector(bsdf.toLocal(cur_.isect.wo), bsdf.toLocal(bs.wi), o.bsdf.toLocal(woY), bs.eta, &hv)) {
            o.kill(st_, ShiftFailure::Geometry);
            return;
        }
        wiY = o.bsdf.toWorld(hv.wi);
        Spectrum fy = o.bsdf.f(woY, wiY);
        Float by = o.bsdf.pdf(woY, wiY);
        if (fy.isBlack() || !(by > 0)) {
            o.kill(st_, ShiftFailure::Geometry);
            return;
        }
        st_.success(ShiftType::HalfVector);
        o.beta *= fy * (AbsDot(wiY, nsY) * hv.jacobian / bs.pdf);
        o.lastPdfY = by;
        o.lastJ = hv.jacobian;
        o.lastSpecular = false;
    }
    o.prevIt = o.isect;
    o.ray = o.isect.spawnRay(wiY);
    o.found = scene_.intersect(o.ray, &o.isect);
    o.cls = classify(o.found, o.isect, &o.bsdf);
}

// The offset's segment for the base's BSDF sample bs towards `next`.
void GradientPathTracer::advanceOffset(OffsetPath &o, const BSDFSample &bs, Float uc, Point2 u, const PathHit &next) {
    const Float cosX = AbsDot(bs.wi, cur_.isect.shading.n);
    switch (o.state) {
    case OffsetPath::Dead: break;
    case OffsetPath::Identical:
        o.beta *= bs.f * (cosX / bs.pdf);
        o.lastPdfY = bs.pdf;
        o.lastJ = 1;
        o.lastSpecular = bs.isSpecular();
        o.prevIt = cur_.isect;
        break;
    case OffsetPath::Reconnected: {
        // Same point and outgoing direction as the base; only wo differs.
        Spectrum fy = cur_.bsdf.f(o.wo, bs.wi);
        Float by = cur_.bsdf.pdf(o.wo, bs.wi);
        if (fy.isBlack() || !(by > 0)) {
            o.kill(st_, ShiftFailure::Geometry);
            break;
        }
        o.beta *= fy * (cosX / bs.pdf);
        o.lastPdfY = by;
        o.lastJ = 1;
        o.lastSpecular = false;
        o.prevIt = cur_.isect;
        o.state = OffsetPath::Identical;
        break;
    }
    case OffsetPath::Diverged:
        if (cur_.cls == ShiftVertexClass::Rough && next.cls == ShiftVertexClass::Rough)
            reconnectOffset(o, bs, next);
        else
            copyHalfVectorOrReplay(o, bs, uc, u);
        break;
    }
    o.diracChain = o.diracChain && o.state != OffsetPath::Dead && o.lastSpecular;
}

void GradientPathTracer::trace(Sampler &sampler, int maxDepth, Float rrThreshold) {
    GRADUS_STAT_COUNTER("G-PT/Paths ended at the interface-crossing limit", nStuck);
    int crossings = 0;  // consecutive interface crossings of the base path
    for (int bounces = 0;; ++bounces) {
        // Invertibility: a diverged offset vertex must be classified like the base's,
        // or the inverse shift would take a different branch.
        for (OffsetPath &o : off_)
            if (o.state == OffsetPath::Diverged && o.cls != cur_.cls) o.kill(st_, ShiftFailure::ClassMismatch);
        emissionTerms();

        if (!cur_.found || bounces >= maxDepth) break;
        for (OffsetPath &o : off_)
            if (o.state == OffsetPath::Diverged && !o.found) o.kill(st_, ShiftFailure::Escaped);

        if (!cur_.isect.material) {  // interface: only identical offsets can follow
            if (++crossings > kMaxInterfaceCrossings) {
                ++nStuck;
                break;
            }
            for (OffsetPath &o : off_)
                if (o.state == OffsetPath::Diverged || o.state == OffsetPath::Reconnected)
                    o.kill(st_, ShiftFailure::Geometry);
            cur_.ray = cur_.isect.spawnRay(cur_.ray.d);
            cur_.found = scene_.intersect(cur_.ray, &cur_.isect);
            cur_.cls = classify(cur_.found, cur_.isect, &cur_.bsdf);
            // Re-entering the emission step commits a neutral ratio for this segment.
            for (OffsetPath &o : off_) o.lastJ = 1, o.lastPdfY = prevBsdfPdf_;
            --bounces;
            continue;
        }
        crossings = 0;
        if (!cur_.bsdf) break;
        nextEventTerms(sampler);

        // BSDF sampling: base direction, then the shifts.
        Float uc = sampler.get1D();
        Point2 u = sampler.get2D();
        BSDFSample bs;
        if (!cur_.bsdf.sample(cur_.isect.wo, uc, u, TransportMode::Radiance, &bs) || !bs.valid()) break;
        Spectrum factor = bs.f * (AbsDot(bs.wi, cur_.isect.shading.n) / bs.pdf);
        PathHit next;
        next.ray = cur_.isect.spawnRay(bs.wi);
        next.found = scene_.intersect(next.ray, &next.isect);
        next.cls = classify(next.found, next.isect, &next.bsdf);
        for (OffsetPath &o : off_) advanceOffset(o, bs, uc, u, next);

        beta_ *= factor;
        specularBounce_ = bs.isSpecular();
        diracChain_ = diracChain_ && specularBounce_;
        prevBsdfPdf_ = bs.pdf;
        prevIt_ = cur_.isect;
        if (bs.isTransmission()) etaScale_ *= Sqr(bs.eta);
        cur_ = next;

        // Russian roulette on the base; offsets follow its decision.
        const Float pSurvive = BaseRouletteSurvival(beta_ * etaScale_, bounces, rrThreshold, sampler.get1D());
        if (pSurvive == 0) break;
        if (pSurvive < 1) {
            beta_ = beta_ / pSurvive;
            for (OffsetPath &o : off_) o.beta = o.beta / pSurvive;
        }
        if (beta_.isBlack()) break;
    }
}

void GradientPathTracer::result(GradientSample *out) const {
    out->primal = primal_;
    out->separated = separated_;
    for (int k = 0; k < kNumNeighbours; ++k) out->diff[k] = off_[k].diff;
}

}  // namespace gradus::gpt
