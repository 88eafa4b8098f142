// The manifold walk (JM12 Sec. 4.3): re-trace the chain with fixed half-vectors
// and move x_1 until the end vertex reaches the target. Two solvers share the
// residual and its derivatives: a direct Newton iteration with JM12-style step
// control and ceres::TinySolver (Levenberg-Marquardt).
#include <atomic>

#include <ceres/tiny_solver.h>

#include "integrators/manifold/manifold.h"

namespace gradus {

namespace {

struct Stats {
    std::atomic<uint64_t> walks{0}, successes{0}, iterations{0}, traces{0};
    std::array<std::atomic<uint64_t>, size_t(ManifoldStatus::Count)> byStatus{};
};
Stats &GlobalStats() {
    static Stats s;
    return s;
}

void Record(const ManifoldWalkResult &r) {
    Stats &s = GlobalStats();
    constexpr auto relaxed = std::memory_order_relaxed;
    s.walks.fetch_add(1, relaxed);
    if (r.ok()) s.successes.fetch_add(1, relaxed);
    s.iterations.fetch_add(uint64_t(r.iterations), relaxed);
    s.traces.fetch_add(uint64_t(r.traces), relaxed);
    s.byStatus[size_t(r.status)].fetch_add(1, relaxed);
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

    ManifoldStatus trace(const Point3 &aim, ManifoldChain *out) {
        ++traces;
        Vec3 d = aim - start.p;
        Float l = d.length();
        if (!(l > 0)) return ManifoldStatus::Degenerate;
        return TraceChain(*scene, start, d / l, *base, out);
    }
    Float distance(const ManifoldChain &c) const { return Distance(c.back().sp.p, target.p); }
    // d(end position, end frame)/d(x_1, x_1 frame).
    bool endDerivative(const ManifoldChain &c, Mat2 *dEnd_dx1) const {
        Mat2 P;
        if (!FirstVertexDerivative(c, &P)) return false;
        Float det = P.det();
        if (!(std::abs(det) > 1e-300) || !std::isfinite(det)) return false;
        *dEnd_dx1 = P.inverse();
        return true;
    }
};

// ---- Direct Newton with step control (JM12 / Mitsuba 0.5 numbers) ----------
ManifoldWalkResult NewtonWalk(WalkContext &ctx, const ManifoldWalkOptions &opts) {
    ManifoldWalkResult res;
    ManifoldChain &cur = res.chain;
    ManifoldStatus st = ctx.trace(ctx.base->v[1].sp.p, &cur);
    if (st != ManifoldStatus::Success) {
        res.status = st;
        return res;
    }
    Float dist = ctx.distance(cur);
    Float step = 1;
    ManifoldStatus lastFailure = ManifoldStatus::NotConverged;
    ManifoldChain trial;
    for (;;) {
        res.relativeError = dist / ctx.scale;
        if (res.relativeError < opts.relativeTolerance) {
            res.status = ManifoldStatus::Success;
            return res;
        }
        if (res.iterations >= opts.maxIterations) break;
        ++res.iterations;
        const ManifoldVertex &end = cur.back(), &x1 = cur.v[1];
        if (Distance(end.sp.p, cur.v[cur.size - 2].sp.p) < 1e-12 * ctx.scale) {
            res.status = ManifoldStatus::Degenerate;  // last two vertices coincide
            return res;
        }
        Mat2 P;
        if (!FirstVertexDerivative(cur, &P)) {
            res.status = ManifoldStatus::Degenerate;
            return res;
        }
        Vec3 delta = ctx.target.p - end.sp.p;
        Vec2 dEnd(Dot(delta, end.s), Dot(delta, end.t));
        Vec2 d1 = P * dEnd;
        Point3 aim = x1.sp.p + (x1.s * d1.x + x1.t * d1.y) * step;
        st = ctx.trace(aim, &trial);
        Float trialDist = st == ManifoldStatus::Success ? ctx.distance(trial) : Infinity;
        if (trialDist < dist) {
            std::swap(cur, trial);
            dist = trialDist;
            step = std::min<Float>(1, 2 * step);
        } else {
            lastFailure = st == ManifoldStatus::Success ? ManifoldStatus::NotConverged : st;
            step *= 0.5;
        }
    }
    res.status = lastFailure;
    return res;
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
    mutable ManifoldStatus lastFailure = ManifoldStatus::NotConverged;
    mutable int evaluations = 0;
    // TinySolver evaluates a trial point without J and, if accepted, again with
    // J: keep the last successful trace so the second call does not re-trace.
    mutable Float cachedX[2] = {Infinity, Infinity};

    Point3 aim(const Float *x) const { return p1 + (T1 * x[0] + T2 * x[1]) * L; }

    bool operator()(const Float *x, Float *r, Float *J) const {
        ++evaluations;
        Point3 q = aim(x);
        ManifoldStatus st = ManifoldStatus::Success;
        if (x[0] != cachedX[0] || x[1] != cachedX[1]) {
            st = ctx->trace(q, &chain);
            cachedX[0] = cachedX[1] = Infinity;
            if (st == ManifoldStatus::Success) { cachedX[0] = x[0]; cachedX[1] = x[1]; }
        }
        if (st != ManifoldStatus::Success) {
            lastFailure = st;
            // TinySolver ignores the return value of trial evaluations: a huge
            // residual makes it reject the step and shrink the trust region.
            r[0] = r[1] = 1e6;
            if (J) std::fill(J, J + 4, 0.0);
            return J == nullptr;
        }
        const ManifoldVertex &end = chain.back();
        Vec3 delta = end.sp.p - ctx->target.p;
        r[0] = Dot(delta, ctx->targetS) / ctx->scale;
        r[1] = Dot(delta, ctx->targetT) / ctx->scale;
        if (!J) return true;
        Mat2 dEnd;
        if (!ctx->endDerivative(chain, &dEnd)) {
            lastFailure = ManifoldStatus::Degenerate;
            return false;
        }
        // dx_1 / dq: the ray from the start through q hits the surface at x_1.
        const ManifoldVertex &x1 = chain.v[1];
        Vec3 dq = q - ctx->start.p;
        Float lambda = (x1.sp.p - ctx->start.p).length() / dq.length();
        Float nq = Dot(x1.sp.n, dq);
        auto dx1 = [&](const Vec3 &e) {
            Vec3 m = (e - dq * (Dot(x1.sp.n, e) / nq)) * lambda;
            return Vec2(Dot(m, x1.s), Dot(m, x1.t));
        };
        Vec2 c0 = dx1(T1), c1 = dx1(T2);
        Mat2 M{c0.x, c1.x, c0.y, c1.y};
        Mat2 F{Dot(end.s, ctx->targetS), Dot(end.t, ctx->targetS), Dot(end.s, ctx->targetT),
               Dot(end.t, ctx->targetT)};
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
    ManifoldStatus st = ctx.trace(ctx.base->v[1].sp.p, &init);
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
    f.T1 = init.v[1].s;
    f.T2 = init.v[1].t;
    f.L = std::max(Distance(f.p1, ctx.start.p), 1e-12 * ctx.scale);
    f.chain = init;  // x = 0 aims exactly at the initial x_1: reuse its trace
    f.cachedX[0] = f.cachedX[1] = 0;
    ceres::TinySolver<WalkFunction> solver;
    solver.options.max_num_iterations = opts.maxIterations;
    solver.options.cost_threshold = 0.5 * Sqr(opts.relativeTolerance);
    solver.options.gradient_tolerance = 0;
    solver.options.parameter_tolerance = 1e-15;
    solver.options.function_tolerance = 0;
    Eigen::Vector2d x(0, 0);
    const auto &summary = solver.Solve(f, &x);
    res.iterations = summary.iterations;
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
    else
        res.status = f.lastFailure;
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

ManifoldWalkResult ManifoldWalk(const ManifoldScene &scene, const ManifoldChain &base,
                                const ManifoldSurfacePoint &newStart,
                                const ManifoldSurfacePoint &target,
                                const ManifoldWalkOptions &opts) {
    ManifoldWalkResult res;
    if (base.size < 2 || base.size > kMaxManifoldVertices ||
        target.primitiveId != base.back().sp.primitiveId) {
        res.status = ManifoldStatus::InvalidInput;
        Record(res);
        return res;
    }
    WalkContext ctx;
    ctx.scene = &scene;
    ctx.base = &base;
    ctx.start = newStart;
    ctx.target = target;
    ManifoldVertex tv;
    SetupManifoldVertex(&tv, target, &base.back().frameRef);
    ctx.targetS = tv.s;
    ctx.targetT = tv.t;
    ctx.scale = std::max({MaxAbs(newStart.p), MaxAbs(target.p), Distance(newStart.p, target.p),
                          Float(1e-30)});
    res = opts.solver == ManifoldSolver::CeresTiny ? CeresWalk(ctx, opts) : NewtonWalk(ctx, opts);
    res.traces = ctx.traces;
    Record(res);
    return res;
}

ManifoldStatus CheckReversible(const ManifoldScene &scene, const ManifoldChain &base,
                               const ManifoldChain &offset, const ManifoldWalkOptions &opts,
                               Float relTolerance) {
    if (base.size != offset.size) return ManifoldStatus::InvalidInput;
    ManifoldWalkResult back = ManifoldWalk(scene, offset, base.front().sp, base.back().sp, opts);
    if (!back.ok()) return back.status;
    Float scale = 0;
    for (int i = 0; i < base.size; ++i) scale = std::max(scale, MaxAbs(base.v[i].sp.p));
    scale = std::max({scale, Distance(base.front().sp.p, base.back().sp.p), Float(1e-30)});
    for (int i = 0; i < base.size; ++i)
        if (Distance(back.chain.v[i].sp.p, base.v[i].sp.p) > relTolerance * scale)
            return ManifoldStatus::NotReversible;
    return ManifoldStatus::Success;
}

ManifoldStatsSnapshot GetManifoldStats() {
    Stats &s = GlobalStats();
    ManifoldStatsSnapshot r;
    r.walks = s.walks.load(std::memory_order_relaxed);
    r.successes = s.successes.load(std::memory_order_relaxed);
    r.iterations = s.iterations.load(std::memory_order_relaxed);
    r.traces = s.traces.load(std::memory_order_relaxed);
    for (size_t i = 0; i < r.byStatus.size(); ++i)
        r.byStatus[i] = s.byStatus[i].load(std::memory_order_relaxed);
    return r;
}

void ResetManifoldStats() {
    Stats &s = GlobalStats();
    s.walks = 0;
    s.successes = 0;
    s.iterations = 0;
    s.traces = 0;
    for (auto &c : s.byStatus) c = 0;
}

}  // namespace gradus
