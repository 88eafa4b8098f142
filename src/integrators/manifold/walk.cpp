// The manifold walk (JM12 Sec. 4.3): re-trace the chain with fixed half-vectors
// and move x_1 until the end vertex reaches the target. Two solvers share the
// residual and its derivatives: a direct Newton iteration with JM12-style step
// control and ceres::TinySolver (Levenberg-Marquardt).
#include <atomic>
#include <string>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include <ceres/tiny_solver.h>

#include "integrators/manifold/manifold.h"

namespace gradus {

namespace {
// "not reversible" -> "not_reversible" (one token per status in WALKSTATS lines).
std::string Underscored(std::string s) {
    for (char &ch : s)
        if (ch == ' ') ch = '_';
    return s;
}
}  // namespace

namespace {

struct Counters {
    std::atomic<uint64_t> walks{0}, successes{0}, iterations{0}, traces{0}, nanoseconds{0};
    std::array<std::atomic<uint64_t>, size_t(ManifoldStatus::Count)> byStatus{};
    std::array<std::atomic<uint64_t>, kManifoldIterationBins> successIterations{};

    void record(const ManifoldWalkResult &r, uint64_t ns) {
        constexpr auto relaxed = std::memory_order_relaxed;
        walks.fetch_add(1, relaxed);
        if (r.ok()) {
            successes.fetch_add(1, relaxed);
            successIterations[size_t(std::min(r.iterations, kManifoldIterationBins - 1))].fetch_add(1, relaxed);
        }
        iterations.fetch_add(uint64_t(r.iterations), relaxed);
        traces.fetch_add(uint64_t(r.traces), relaxed);
        nanoseconds.fetch_add(ns, relaxed);
        byStatus[size_t(r.status)].fetch_add(1, relaxed);
    }
    void snapshot(ManifoldWalkCounts *o) const {
        constexpr auto relaxed = std::memory_order_relaxed;
        o->walks = walks.load(relaxed);
        o->successes = successes.load(relaxed);
        o->iterations = iterations.load(relaxed);
        o->traces = traces.load(relaxed);
        o->nanoseconds = nanoseconds.load(relaxed);
        for (size_t i = 0; i < byStatus.size(); ++i) o->byStatus[i] = byStatus[i].load(relaxed);
        for (size_t i = 0; i < successIterations.size(); ++i) o->successIterations[i] = successIterations[i].load(relaxed);
    }
    void reset() {
        walks = successes = iterations = traces = nanoseconds = 0;
        for (auto &c : byStatus) c = 0;
        for (auto &c : successIterations) c = 0;
    }
};
// GRADUS_WALK_STATS set: the process's walk counters on stderr at exit, one
// machine-readable line per direction (bench/manifold/walk_stats.py reads them).
struct Stats {
    Counters forward, reverse;
    ~Stats() {
        if (!std::getenv("GRADUS_WALK_STATS")) return;
        ManifoldStatsSnapshot s;
        forward.snapshot(&s);
        reverse.snapshot(&s.reverse);
        for (int k = 0; k < 2; ++k) {
            const ManifoldWalkCounts &c = k ? s.reverse : s;
            if (!c.walks) continue;
            std::fprintf(stderr, "WALKSTATS %s walks %llu success %llu traces %llu ns %llu hist", k ? "reverse" : "forward",
                         (unsigned long long)c.walks, (unsigned long long)c.successes, (unsigned long long)c.traces,
                         (unsigned long long)c.nanoseconds);
            for (uint64_t h : c.successIterations) std::fprintf(stderr, " %llu", (unsigned long long)h);
            std::fprintf(stderr, " status");
            for (size_t i = 0; i < c.byStatus.size(); ++i)
                if (c.byStatus[i]) std::fprintf(stderr, " %s=%llu", Underscored(ToString(ManifoldStatus(i))).c_str(), (unsigned long long)c.byStatus[i]);
            std::fprintf(stderr, "\n");
        }
    }
};
Stats &GlobalStats() {
    static Stats s;
    return s;
}

Float MaxAbs(const Vec3 &p) { return MaxComponent(Abs(p)); }

// Outgoing direction at v for incoming propagation direction d, from the stored
// half-vector offset v.o (inverse of ProjectedHalfVector).
ManifoldStatus Scatter(const ManifoldVertex &v, const Vec3 &d, Vec3 *wo) {
    Vec3 wi = -d;
    const Vec3 &n = v.sp.n;
    Float o2 = v.o.x * v.o.x + v.o.y * v.o.y;
    if (!(o2 < 1)) return ManifoldStatus::Degenerate;
    Vec3 H = v.s * v.o.x + v.t * v.o.y + n * std::sqrt(1 - o2);
    Float cosN = Dot(wi, n);
    if (cosN == 0) return ManifoldStatus::Degenerate;
    bool inFront = cosN > 0;
    Float ci = Dot(wi, H);
    if (v.reflect) {
        *wo = H * (2 * ci) - wi;
        if ((Dot(*wo, n) > 0) != inFront) return ManifoldStatus::WrongSide;
        return ManifoldStatus::Success;
    }
    Float etaA = inFront ? v.sp.etaExterior : v.sp.etaInterior;
    Float etaB = inFront ? v.sp.etaInterior : v.sp.etaExterior;
    if (etaA == etaB) return ManifoldStatus::Degenerate;
    if (ci < 0) {
        H = -H;
        ci = -ci;
    }
    Float eta = etaA / etaB;
    Float sin2t = eta * eta * std::max<Float>(0, 1 - ci * ci);
    if (sin2t >= 1) return ManifoldStatus::TotalInternalReflection;
    Float ct = std::sqrt(1 - sin2t);
    *wo = -wi * eta + H * (eta * ci - ct);
    if ((Dot(*wo, n) > 0) == inFront) return ManifoldStatus::WrongSide;
    return ManifoldStatus::Success;
}

ManifoldStatus Hit(const ManifoldScene &scene, const Point3 &o, const Vec3 &d, int primId,
                   ManifoldSurfacePoint *hit) {
    if (!scene.intersect(Ray(o, d), hit)) return ManifoldStatus::LeftSurface;
    if (hit->primitiveId != primId) return ManifoldStatus::Occluded;
    return ManifoldStatus::Success;
}

// Everything one walk needs, shared by both solvers.
struct WalkContext {
    const ManifoldScene *scene;
    const ManifoldChain *base;
    ManifoldSurfacePoint start, target;
    Vec3 targetS, targetT;  // target tangent frame
    Float scale;
    int traces = 0;
    bool baseSign = true;  // set by initial()

    // The first iterate and its P = dx_1/dx_end (each solver's first derivative):
    // the base itself when the start did not move (no re-trace of a chain we
    // have). Else a first-order prediction from the base, x_1 + dx_1/dx_0 dx_0 +
    // dx_1/dx_end dx_end (both endpoints' moves in their motion axes), traced from
    // the new start; if that trace fails or lands on another sheet than the
    // base's, the trace towards the base's x_1. Sets baseSign, the sign of det P
    // of the base (its sheet of the solution manifold).
    ManifoldStatus initial(ManifoldChain *out, Mat2 *P) {
        const ManifoldChain &b = *base;
        Mat2 P0, Pb;
        if (!FirstVertexDerivatives(b, &P0, &Pb) || !std::isfinite(Pb.det())) return ManifoldStatus::Degenerate;
        baseSign = Pb.det() > 0;
        if (start.p == b.front().sp.p && start.n == b.front().sp.n) {
            *out = b;
            *P = Pb;
            return ManifoldStatus::Success;
        }
        const Vec3 d0 = start.p - b.front().sp.p, dE = target.p - b.back().sp.p;
        const Vec2 m = P0 * Vec2(Dot(d0, b.front().ps), Dot(d0, b.front().pt)) +
                       Pb * Vec2(Dot(dE, b.back().ps), Dot(dE, b.back().pt));
        const ManifoldVertex &x1 = b.v[1];
        if (std::isfinite(m.x) && std::isfinite(m.y) &&
            trace(x1.sp.p + x1.ps * m.x + x1.pt * m.y, out) == ManifoldStatus::Success &&
            FirstVertexDerivative(*out, P) && (P->det() > 0) == baseSign)
            return ManifoldStatus::Success;
        const ManifoldStatus st = trace(x1.sp.p, out);
        if (st != ManifoldStatus::Success) return st;
        return FirstVertexDerivative(*out, P) && std::isfinite(P->det()) ? ManifoldStatus::Success
                                                                          : ManifoldStatus::Degenerate;
    }
    ManifoldStatus trace(const Point3 &aim, ManifoldChain *out) {
        ++traces;
        Vec3 d = aim - start.p;
        Float l = d.length();
        if (!(l > 0)) return ManifoldStatus::Degenerate;
        return TraceChain(*scene, start, d / l, *base, out);
    }
    Float distance(const ManifoldChain &c) const { return Distance(c.back().sp.p, target.p); }
};

// ---- Direct Newton with step control (JM12 Sec. 4.3) ------------------------
ManifoldWalkResult NewtonWalk(WalkContext &ctx, const ManifoldWalkOptions &opts) {
    ManifoldWalkResult res;
    ManifoldChain &cur = res.chain;
    // P = dx_1/dx_end of the current chain (motion axes), kept until cur changes:
    // a rejected trial reuses it, an accepted one brings its own.
    Mat2 P, trialP;
    ManifoldStatus st = ctx.initial(&cur, &P);
    if (st != ManifoldStatus::Success) {
        res.status = st;
        return res;
    }
    // The walk stays on the base's sheet of the solution manifold: the sign of
    // det P changes only across a fold (a caustic of the chain), where the chain's
    // end stops being a local function of x_1.
    const bool startSign = ctx.baseSign;
    if ((P.det() > 0) != startSign) {
        res.status = ManifoldStatus::Fold;
        return res;
    }
    const Float extent = ctx.scene->extent(ctx.base->v[1].sp.primitiveId);
    Float dist = ctx.distance(cur);
    Float step = 1;
    ManifoldStatus lastRejection = ManifoldStatus::StepFloor;
    ManifoldChain trial;
    for (;;) {
        const ManifoldVertex &end = cur.back(), &x1 = cur.v[1];
        // Newton step: the end's offset in its motion axes, mapped to x_1's.
        Vec3 delta = ctx.target.p - end.sp.p;
        Vec2 d1 = P * Vec2(Dot(delta, end.ps), Dot(delta, end.pt));
        Vec3 move = x1.ps * d1.x + x1.pt * d1.y;
        // Converged when the end is at the target and x_1 would not move either:
        // near a fold |dx_1/dx_end| is large, and an end within tolerance can leave
        // the interior (and the chain's Jacobians) far from the solution.
        res.relativeError = std::max(dist, move.length()) / ctx.scale;
        if (res.relativeError < opts.relativeTolerance) {
            res.status = ManifoldStatus::Success;
            return res;
        }
        if (res.iterations >= opts.maxIterations) {
            res.status = ManifoldStatus::IterationCap;
            return res;
        }
        ++res.iterations;
        if (Distance(end.sp.p, cur.v[cur.size - 2].sp.p) < 1e-12 * ctx.scale) {
            res.status = ManifoldStatus::Degenerate;  // last two vertices coincide
            return res;
        }
        if (step == 1 && move.length() > extent) {
            res.status = ManifoldStatus::StepLeavesSurface;
            return res;
        }
        // x_1's trial point on its geometric tangent plane; the trace from the start
        // through it re-projects it onto the surface.
        st = ctx.trace(x1.sp.p + move * step, &trial);
        Float trialDist = Infinity;
        if (st == ManifoldStatus::Success) {
            if (!FirstVertexDerivative(trial, &trialP) || !std::isfinite(trialP.det()))
                st = ManifoldStatus::Degenerate;
            else if ((trialP.det() > 0) != startSign)
                st = ManifoldStatus::Fold;
            else
                trialDist = ctx.distance(trial);
        }
        if (trialDist < dist) {
            std::swap(cur, trial);
            P = trialP;
            dist = trialDist;
            step = std::min<Float>(1, 2 * step);
        } else {
            lastRejection = st == ManifoldStatus::Success ? ManifoldStatus::StepFloor : st;
            step *= 0.5;
            if (step < opts.minStep) {
                res.status = lastRejection;
                return res;
            }
        }
    }
}

// ---- ceres::TinySolver on the same residual ---------------------------------
// Parameters: (a, b), x_1 aimed at p1 + L (a T1 + b T2) in the initial x_1's
// tangent plane; residuals: (x_end - target) in the target frame / scale.
struct WalkFunction {
    using Scalar = Float;
    enum { NUM_RESIDUALS = 2, NUM_PARAMETERS = 2 };
    WalkContext *ctx;
    Point3 p1;
    Vec3 T1, T2;
    Float L;
    mutable ManifoldChain chain;
    mutable ManifoldStatus lastFailure = ManifoldStatus::StepFloor;
    mutable int evaluations = 0;
    // TinySolver evaluates a trial point without J and, if accepted, again with
    // J: keep the last successful trace (and its derivative) so the second call
    // does not re-trace.
    mutable Float cachedX[2] = {Infinity, Infinity};
    mutable Mat2 cachedP;
    // Fast failure, as Newton's step floor: a rejected trial (failed, or not
    // lowering the cost) raises `rejects`, an accepted one lowers it (Newton's
    // step factor 2^-rejects); at maxRejects a trial returns the accepted point's
    // residual, whose cost change of 0 ends TinySolver (function_tolerance).
    int maxRejects = 7;
    bool startSign = true;
    mutable int rejects = 0;
    mutable Float acceptedR[2] = {0, 0};
    mutable bool stopped = false;

    Point3 aim(const Float *x) const { return p1 + (T1 * x[0] + T2 * x[1]) * L; }

    bool reject(ManifoldStatus why, Float *r) const {
        lastFailure = why;
        if (++rejects >= maxRejects) {
            stopped = true;
            r[0] = acceptedR[0];
            r[1] = acceptedR[1];
        } else {
            // TinySolver ignores the return value of trial evaluations: a huge
            // residual makes it reject the step and shrink the trust region.
            r[0] = r[1] = 1e6;
        }
        return true;
    }

    bool operator()(const Float *x, Float *r, Float *J) const {
        ++evaluations;
        Point3 q = aim(x);
        ManifoldStatus st = ManifoldStatus::Success;
        if (x[0] != cachedX[0] || x[1] != cachedX[1]) {
            st = ctx->trace(q, &chain);
            cachedX[0] = cachedX[1] = Infinity;
            if (st == ManifoldStatus::Success) {
                // A trial across a fold (det dx_1/dx_end changes sign) is rejected.
                if (!FirstVertexDerivative(chain, &cachedP) || !std::isfinite(cachedP.det()))
                    st = ManifoldStatus::Degenerate;
                else if ((cachedP.det() > 0) != startSign)
                    st = ManifoldStatus::Fold;
                else {
                    cachedX[0] = x[0];
                    cachedX[1] = x[1];
                }
            }
        }
        if (st != ManifoldStatus::Success) {
            if (!J) return reject(st, r);
            lastFailure = st;
            r[0] = r[1] = 1e6;
            std::fill(J, J + 4, 0.0);
            return false;
        }
        const ManifoldVertex &end = chain.back();
        Vec3 delta = end.sp.p - ctx->target.p;
        r[0] = Dot(delta, ctx->targetS) / ctx->scale;
        r[1] = Dot(delta, ctx->targetT) / ctx->scale;
        if (!J) {
            if (Sqr(r[0]) + Sqr(r[1]) >= Sqr(acceptedR[0]) + Sqr(acceptedR[1]))
                return reject(ManifoldStatus::StepFloor, r);
            return true;
        }
        // An accepted point (or the start).
        rejects = std::max(0, rejects - 1);
        acceptedR[0] = r[0];
        acceptedR[1] = r[1];
        const Float det = cachedP.det();
        if (!(std::abs(det) > 1e-300)) {
            lastFailure = ManifoldStatus::Degenerate;
            return false;
        }
        const Mat2 dEnd = cachedP.inverse();
        // dx_1 / dq: the ray from the start through q hits x_1's geometric tangent plane.
        const ManifoldVertex &x1 = chain.v[1];
        const Vec3 ng1 = GeometricNormal(x1.sp);
        Vec3 dq = q - ctx->start.p;
        Float lambda = (x1.sp.p - ctx->start.p).length() / dq.length();
        Float nq = Dot(ng1, dq);
        auto dx1 = [&](const Vec3 &e) {
            Vec3 m = (e - dq * (Dot(ng1, e) / nq)) * lambda;
            return Vec2(Dot(m, x1.ps), Dot(m, x1.pt));
        };
        Vec2 c0 = dx1(T1), c1 = dx1(T2);
        Mat2 M{c0.x, c1.x, c0.y, c1.y};
        Mat2 F{Dot(end.ps, ctx->targetS), Dot(end.pt, ctx->targetS), Dot(end.ps, ctx->targetT),
               Dot(end.pt, ctx->targetT)};
        Mat2 Jm = F * dEnd * M;
        Float k = L / ctx->scale;
        // Column-major 2x2.
        J[0] = Jm.a * k; J[1] = Jm.c * k; J[2] = Jm.b * k; J[3] = Jm.d * k;
        return true;
    }
};

ManifoldWalkResult CeresWalk(WalkContext &ctx, const ManifoldWalkOptions &opts) {
    ManifoldWalkResult res;
    ManifoldChain init;
    Mat2 initP;
    ManifoldStatus st = ctx.initial(&init, &initP);
    if (st != ManifoldStatus::Success) {
        res.status = st;
        return res;
    }
    res.relativeError = ctx.distance(init) / ctx.scale;
    if (res.relativeError < opts.relativeTolerance) {
        res.chain = init;
        res.status = ManifoldStatus::Success;
        return res;
    }
    WalkFunction f;
    f.ctx = &ctx;
    f.p1 = init.v[1].sp.p;
    f.T1 = init.v[1].ps;
    f.T2 = init.v[1].pt;
    f.L = std::max(Distance(f.p1, ctx.start.p), 1e-12 * ctx.scale);
    f.chain = init;  // x = 0 aims exactly at the initial x_1: reuse its trace
    f.cachedX[0] = f.cachedX[1] = 0;
    f.cachedP = initP;
    f.startSign = initP.det() > 0;
    f.maxRejects = 1 + int(std::ceil(std::log2(1 / std::max(opts.minStep, Float(1e-30)))));
    ceres::TinySolver<WalkFunction> solver;
    solver.options.max_num_iterations = opts.maxIterations;
    solver.options.cost_threshold = 0.5 * Sqr(opts.relativeTolerance);
    solver.options.gradient_tolerance = 0;
    // Fast failure: trials that fail to trace are rejected and shrink the trust
    // region geometrically; stop once a step is below 1% of the tolerance.
    solver.options.parameter_tolerance = 1e-2 * opts.relativeTolerance;
    solver.options.function_tolerance = 1e-300;  // ends the solve on the fast-failure residual
    Eigen::Vector2d x(0, 0);
    const auto &summary = solver.Solve(f, &x);
    res.iterations = summary.iterations;
    if (f.stopped) {  // fast failure: no chain to return
        res.relativeError = std::sqrt(Sqr(f.acceptedR[0]) + Sqr(f.acceptedR[1]));
        res.status = f.lastFailure;
        return res;
    }
    if (x[0] == f.cachedX[0] && x[1] == f.cachedX[1]) {
        res.chain = f.chain;
    } else {
        st = ctx.trace(f.aim(x.data()), &res.chain);
        if (st != ManifoldStatus::Success) {
            res.status = st;
            return res;
        }
    }
    res.relativeError = ctx.distance(res.chain) / ctx.scale;
    if (res.relativeError < opts.relativeTolerance)
        res.status = ManifoldStatus::Success;
    else if (summary.iterations < opts.maxIterations)
        res.status = f.lastFailure;
    else
        res.status = ManifoldStatus::IterationCap;
    return res;
}

}  // namespace

ManifoldStatus TraceChain(const ManifoldScene &scene, const ManifoldSurfacePoint &start,
                          const Vec3 &dir, const ManifoldChain &tmpl, ManifoldChain *out) {
    if (tmpl.size < 2 || tmpl.size > kMaxManifoldVertices) return ManifoldStatus::InvalidInput;
    out->size = tmpl.size;
    SetupManifoldVertex(&out->v[0], start, &tmpl.v[0].frameRef);
    out->v[0].reflect = tmpl.v[0].reflect;
    out->v[0].specular = tmpl.v[0].specular;
    Point3 o = start.p;
    Vec3 d = dir;
    for (int i = 1; i < tmpl.size; ++i) {
        const ManifoldVertex &tv = tmpl.v[i];
        ManifoldSurfacePoint hit;
        ManifoldStatus st = Hit(scene, o, d, tv.sp.primitiveId, &hit);
        if (st != ManifoldStatus::Success) return st;
        ManifoldVertex &v = out->v[i];
        SetupManifoldVertex(&v, hit, &tv.frameRef);
        v.reflect = tv.reflect;
        v.specular = tv.specular;
        v.o = tv.o;
        if (i == tmpl.size - 1) break;
        Vec3 wo;
        st = Scatter(v, d, &wo);
        if (st != ManifoldStatus::Success) return st;
        o = hit.p;
        d = Normalize(wo);
    }
    return ManifoldStatus::Success;
}

namespace {

ManifoldWalkResult Walk(const ManifoldScene &scene, const ManifoldChain &base, const ManifoldSurfacePoint &newStart,
                        const ManifoldSurfacePoint &target, const ManifoldWalkOptions &opts, Counters *counters) {
    const auto t0 = std::chrono::steady_clock::now();
    ManifoldWalkResult res;
    if (base.size < 2 || base.size > kMaxManifoldVertices ||
        target.primitiveId != base.back().sp.primitiveId) {
        res.status = ManifoldStatus::InvalidInput;
    } else {
        WalkContext ctx;
        ctx.scene = &scene;
        ctx.base = &base;
        ctx.start = newStart;
        ctx.target = target;
        ManifoldVertex tv;
        SetupManifoldVertex(&tv, target, &base.back().frameRef);
        ctx.targetS = tv.ps;
        ctx.targetT = tv.pt;
        ctx.scale = std::max({MaxAbs(newStart.p), MaxAbs(target.p), Distance(newStart.p, target.p),
                              Float(1e-30)});
        res = opts.solver == ManifoldSolver::CeresTiny ? CeresWalk(ctx, opts) : NewtonWalk(ctx, opts);
        res.traces = ctx.traces;
    }
    const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0);
    counters->record(res, uint64_t(ns.count()));
    return res;
}

}  // namespace

ManifoldWalkResult ManifoldWalk(const ManifoldScene &scene, const ManifoldChain &base,
                                const ManifoldSurfacePoint &newStart,
                                const ManifoldSurfacePoint &target,
                                const ManifoldWalkOptions &opts) {
    return Walk(scene, base, newStart, target, opts, &GlobalStats().forward);
}

ManifoldStatus CheckReversible(const ManifoldScene &scene, const ManifoldChain &base,
                               const ManifoldChain &offset, const ManifoldWalkOptions &opts,
                               Float relTolerance) {
    if (base.size != offset.size) return ManifoldStatus::InvalidInput;
    ManifoldWalkResult back = Walk(scene, offset, base.front().sp, base.back().sp, opts, &GlobalStats().reverse);
    if (!back.ok()) return back.status;
    Float scale = 0;
    for (int i = 0; i < base.size; ++i) scale = std::max(scale, MaxAbs(base.v[i].sp.p));
    scale = std::max({scale, Distance(base.front().sp.p, base.back().sp.p), Float(1e-30)});
    for (int i = 0; i < base.size; ++i)
        if (Distance(back.chain.v[i].sp.p, base.v[i].sp.p) > relTolerance * scale)
            return ManifoldStatus::NotReversible;
    return ManifoldStatus::Success;
}

int ManifoldWalkCounts::iterationQuantile(double q) const {
    if (successes == 0) return -1;
    const double want = q * double(successes);
    uint64_t below = 0;
    for (int i = 0; i < kManifoldIterationBins; ++i) {
        below += successIterations[size_t(i)];
        if (double(below) >= want && below > 0) return i;
    }
    return kManifoldIterationBins - 1;
}

ManifoldStatsSnapshot GetManifoldStats() {
    ManifoldStatsSnapshot r;
    GlobalStats().forward.snapshot(&r);
    GlobalStats().reverse.snapshot(&r.reverse);
    return r;
}

void ResetManifoldStats() {
    GlobalStats().forward.reset();
    GlobalStats().reverse.reset();
}

std::string FormatManifoldStats(const ManifoldStatsSnapshot &s, const std::string &indent) {
    std::string out;
    char buf[256];
    auto block = [&](const char *what, const ManifoldWalkCounts &c) {
        if (c.walks == 0) return;
        uint64_t within3 = 0;
        for (int i = 0; i <= 3; ++i) within3 += c.successIterations[size_t(i)];
        std::snprintf(buf, sizeof buf,
                      "%smanifold walks (%s) %llu: success %.1f%%, iterations of successes median %d, p90 %d, "
                      "<= 3: %.1f%%; %.2f traces and %.2f us per walk\n",
                      indent.c_str(), what, (unsigned long long)c.walks, 100.0 * double(c.successes) / double(c.walks),
                      c.iterationQuantile(0.5), c.iterationQuantile(0.9),
                      c.successes ? 100.0 * double(within3) / double(c.successes) : 0.0,
                      double(c.traces) / double(c.walks), 1e-3 * double(c.nanoseconds) / double(c.walks));
        out += buf;
        const uint64_t fails = c.failures();
        for (size_t i = 1; i < size_t(ManifoldStatus::Count); ++i)
            if (c.byStatus[i]) {
                std::snprintf(buf, sizeof buf, "%s  failure %-26s %llu (%.1f%% of failures)\n", indent.c_str(),
                              ToString(ManifoldStatus(i)), (unsigned long long)c.byStatus[i],
                              100.0 * double(c.byStatus[i]) / double(fails));
                out += buf;
            }
    };
    block("forward", s);
    block("reverse", s.reverse);
    return out;
}

}  // namespace gradus
