"""Statistics over runs: mean +- standard error, log-log interpolation, speed-ups.

Speed-up of integrator A over the baseline B at A's budget t:
    speedup = T_B(e_A(t)) / t_A
where e_A(t) is A's mean relMSE and T_B(e) is the time B needs to reach error e,
read off B's convergence curve by linear interpolation of log(relMSE) against
log(seconds). Outside B's measured range the curve is extended from its nearest end
with slope -1, the Monte Carlo rate (relMSE ~ 1/time for an unbiased estimator),
and the value is flagged as extrapolated. A slope fitted to a few short, noisy runs
is not used for this: one unlucky seed can make it nearly flat and the factor absurd.

Errors may be corrected for the reference's own noise before this: a render
measured against a noisy reference shows relMSE_true + noise, so noise (the
reference's ref.noise) is subtracted. Points at or below the floor cannot be
placed on a curve and give no speed-up.
"""

import math

MC_SLOPE = -1.0  # log-log slope of relMSE against time for unbiased Monte Carlo


def mean_stderr(values):
    vals = [v for v in values if v is not None and math.isfinite(v)]
    n = len(vals)
    if n == 0:
        return None, None, 0
    m = sum(vals) / n
    if n < 2:
        return m, None, n
    var = sum((v - m) ** 2 for v in vals) / (n - 1)
    return m, math.sqrt(var / n), n


def summarise(rows):
    """Group per-run rows by (scene, integrator, budget); mean +- stderr of each metric."""
    groups = {}
    order = []
    for r in rows:
        if r.get("status") != "ok":
            continue
        key = (r["scene"], r["integrator"], float(r["budget"]))
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(r)
    out = []
    for key in order:
        g = groups[key]
        s = {"scene": key[0], "integrator": key[1], "budget": key[2], "runs": len(g)}
        for metric in ("seconds", "wall_seconds", "spp", "relmse", "relmse_untrimmed", "mse",
                       "psnr", "mean_rel", "cpu_seconds", "loadavg"):
            m, se, _ = mean_stderr([_float(r.get(metric)) for r in g])
            s[metric] = m
            s[metric + "_stderr"] = se
        s["ref_noise"] = _float(g[0].get("ref_noise"))
        out.append(s)
    return out


def _float(x):
    if x is None or x == "":
        return None
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def corrected(err, noise):
    """relMSE minus the reference noise floor; None at or below the floor."""
    if err is None:
        return None
    if noise:
        err = err - noise
    return err if err > 0 else None


def fit_power_law(points):
    """Least-squares fit log e = a + b log t; returns (a, b) or None."""
    pts = [(math.log(t), math.log(e)) for t, e in points if t and e and t > 0 and e > 0]
    if len(pts) < 2:
        return None
    n = len(pts)
    mx = sum(p[0] for p in pts) / n
    my = sum(p[1] for p in pts) / n
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    if sxx <= 0:
        return None
    b = sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx
    return my - b * mx, b


def time_to_error(curve, err):
    """Seconds a method with convergence curve [(seconds, relMSE), ...] needs to reach err.

    Returns (seconds, extrapolated) or (None, False) when no sensible answer exists
    (empty curve, or a curve that does not fall with time)."""
    pts = sorted((t, e) for t, e in curve if t and e and t > 0 and e > 0)
    if not pts or not err or err <= 0:
        return None, False
    le = math.log(err)
    # Inside the measured range: first bracketing segment.
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        l0, l1 = math.log(e0), math.log(e1)
        if (l0 - le) * (l1 - le) <= 0 and l0 != l1:
            f = (le - l0) / (l1 - l0)
            return math.exp(math.log(t0) + f * (math.log(t1) - math.log(t0))), False
    if len(pts) == 1 and pts[0][1] == err:
        return pts[0][0], False
    fit = fit_power_law(pts) if len(pts) > 2 else None
    if fit and fit[1] >= 0:
        return None, False  # the curve does not fall with time at all
    # Extend from the end of the curve nearest in error, at the Monte Carlo rate.
    anchor = min((pts[0], pts[-1]), key=lambda p: abs(math.log(p[1]) - le))
    lt = math.log(anchor[0]) + (le - math.log(anchor[1])) / MC_SLOPE
    return math.exp(lt), True


def speedups(summary, baseline, floor_correction=True):
    """Adds 'speedup', 'speedup_extrapolated', 'baseline_seconds' to each summary row."""
    by_scene = {}
    for s in summary:
        by_scene.setdefault(s["scene"], []).append(s)
    for scene, rows in by_scene.items():
        def err_of(r):
            e = r["relmse"]
            return corrected(e, r.get("ref_noise")) if floor_correction else e
        base_curve = [(r["seconds"], err_of(r)) for r in rows if r["integrator"] == baseline]
        base_curve = [(t, e) for t, e in base_curve if e is not None]
        for r in rows:
            r["speedup"] = None
            r["speedup_extrapolated"] = False
            r["baseline_seconds"] = None
            r["at_noise_floor"] = floor_correction and err_of(r) is None and r["relmse"] is not None
            e = err_of(r)
            if e is None or not r["seconds"] or not base_curve:
                continue
            t_base, extrap = time_to_error(base_curve, e)
            if t_base is None:
                continue
            r["baseline_seconds"] = t_base
            r["speedup"] = t_base / r["seconds"]
            r["speedup_extrapolated"] = extrap
    return summary


def convergence_slope(rows):
    """Fitted log-log slope of relMSE against seconds (about -1 for unbiased MC)."""
    fit = fit_power_law([(r["seconds"], r["relmse"]) for r in rows])
    return fit[1] if fit else None
