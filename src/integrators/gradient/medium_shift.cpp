#include "integrators/gradient/medium_shift.h"

#include <algorithm>
#include <cmath>

namespace gradus {

namespace {

// The pieces of heterogeneous media, clipped to where their sigma_t may be
// non-zero; homogeneous optical depths are summed into *tau.
struct Clipped {
    MediumPiece p[kMaxMediumPieces];
    int n = 0;
    Float len = 0, maxSigma = 0;
};

void Split(const MediumPiece *in, int n, Spectrum *tau, Clipped *out) {
    for (int i = 0; i < n; ++i) {
        const MediumPiece &q = in[i];
        if (!q.medium || !(q.len > 0)) continue;
        if (q.medium->homogeneous()) {
            const Spectrum s = q.medium->sigmaTAt(q.o);
            for (int c = 0; c < 3; ++c)
                if (s[c] > 0) (*tau)[c] += s[c] * q.len;  // Infinity for an escaped piece
            continue;
        }
        Float t0, t1;
        Ray r(q.o, q.d, q.len);
        if (!q.medium->support(r, &t0, &t1) || !(t1 > t0)) continue;
        MediumPiece &c = out->p[out->n++];
        c = {q.o + q.d * t0, q.d, t1 - t0, q.medium};
        out->len += c.len;
        out->maxSigma = std::max(out->maxSigma, q.medium->maxSigmaT());
    }
}

// sigma_t at arc length s along the clipped pieces.
Spectrum SigmaAlong(const Clipped &c, Float s) {
    for (int i = 0; i < c.n; ++i) {
        if (s <= c.p[i].len || i == c.n - 1)
            return c.p[i].medium->sigmaTAt(c.p[i].o + c.p[i].d * std::min(s, c.p[i].len));
        s -= c.p[i].len;
    }
    return Spectrum(0);
}

}  // namespace

Spectrum TransmittanceRatio(const MediumPiece *y, int ny, const MediumPiece *x, int nx, UniformSource rng) {
    Spectrum tauY(0), tauX(0);
    Clipped cy, cx;
    Split(y, ny, &tauY, &cy);
    Split(x, nx, &tauX, &cx);
    Spectrum r;
    for (int c = 0; c < 3; ++c) {
        if (std::isinf(tauY[c])) r[c] = 0;
        else if (std::isinf(tauX[c])) r[c] = 0;  // not a sampled base path
        else r[c] = std::exp(-(tauY[c] - tauX[c]));
    }
    const Float mu = std::max(cy.len * cy.maxSigma, cx.len * cx.maxSigma);
    if (!(mu > 0) || r.isBlack()) return r;
    Spectrum w(1);
    for (Float u = 0;;) {
        u -= std::log(1 - rng.uniform()) / mu;
        if (u >= 1) break;
        const Spectrum sy = cy.n ? SigmaAlong(cy, u * cy.len) : Spectrum(0);
        const Spectrum sx = cx.n ? SigmaAlong(cx, u * cx.len) : Spectrum(0);
        for (int c = 0; c < 3; ++c) w[c] *= 1 - (cy.len * sy[c] - cx.len * sx[c]) / mu;
        if (w.isBlack()) break;
    }
    for (int c = 0; c < 3; ++c) w[c] = std::max<Float>(w[c], 0);
    return r * w;
}

int TraceSegmentPieces(const Scene &scene, const Interaction &from, const Medium *m, const Interaction &to,
                       bool atInfinity, const Vec3 &d, MediumPiece *pieces) {
    Interaction it = from;
    for (int k = 0; k < kMaxMediumPieces; ++k) {
        const Ray r = atInfinity ? it.spawnRay(d) : it.spawnRayTo(to);
        SurfaceInteraction si;
        const bool hit = scene.intersect(r, &si);
        if (hit && si.material) return 0;
        const Float len = hit ? Distance(r.o, si.p) : (atInfinity ? Infinity : Distance(r.o, to.p));
        pieces[k] = {r.o, Normalize(r.d), len, m};
        if (!hit) return k + 1;
        m = si.mediumAfter(r.d, m);
        it = si;
    }
    return 0;
}

bool LockstepSegment(const Scene &scene, Ray ray, const Medium *m, const MediumPiece *xp, int nx, SegmentEnd end,
                     MediumPiece *yp, SurfaceInteraction *hit, Point3 *pMedium, const Medium **mEnd) {
    for (int j = 0; j < nx; ++j) {
        SurfaceInteraction si;
        const bool found = scene.intersect(ray, &si);
        const Vec3 d = Normalize(ray.d);
        const Float len = found ? Distance(ray.o, si.p) : Infinity;
        yp[j] = {ray.o, d, len, m};
        if (j + 1 < nx) {  // an interface, as the base's
            if (!found || si.material) return false;
            m = si.mediumAfter(ray.d, m);
            ray = si.spawnRay(ray.d);
            continue;
        }
        *mEnd = m;
        switch (end) {
        case SegmentEnd::Surface:
            if (!found || !si.material) return false;
            *hit = si;
            return true;
        case SegmentEnd::Escape: return !found;
        case SegmentEnd::Medium: {
            const Float t = xp[j].len;
            if (m != xp[j].medium || !m || !(t < len)) return false;
            const Point3 p = ray.o + d * t;
            if (!(m->sigmaTAt(p).maxComponent() > 0)) return false;
            yp[j].len = t;
            *pMedium = p;
            return true;
        }
        }
    }
    return false;
}

}  // namespace gradus
