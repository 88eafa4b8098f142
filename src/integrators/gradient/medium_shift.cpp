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

}  // namespace gradus
