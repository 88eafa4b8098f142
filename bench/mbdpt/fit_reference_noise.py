#!/usr/bin/python3
"""Per-sample error constants and the reference's own error from equal-time tables.

For an unbiased estimator averaged over independent iterations, relMSE against a noisy but
independent reference is  relMSE(config, T) = a_config / spp(config, T) + c,  where c is the
reference's own relMSE (shared by every configuration and budget). Given the tables that
equal_spp.py printed for one scene at several budgets (rows: configuration, mean relMSE, ...,
spp), this fits c (grid search, relative least squares) and each a_config (for a given c the
mean of (relMSE - c) spp), and prints c, the fit's rms relative residual, the per-sample ratio
a_first / a_config, and for every budget the equal-time ratio with c removed,
(a_first / spp_first) / (a_config / spp_config).

  bench/mbdpt/fit_reference_noise.py OUT/hidden-20.md OUT/hidden-40.md OUT/hidden-120.md
"""
import re
import sys


def load(paths):
    rows, order, budgets = {}, [], []
    for path in paths:
        budget = None
        for line in open(path):
            if budget is None:
                m = re.search(r", ([\d.]+s|\d+spp), seeds", line)
                budget = m.group(1) if m else path
                budgets.append(budget)
            m = re.match(r"\| (\S+) \| ([\d.e+-]+) \| [^|]+\| [^|]+\| [^|]+\| ([\d.]+) \|", line)
            if m and m.group(1) != "configuration":
                if m.group(1) not in rows:
                    order.append(m.group(1))
                rows.setdefault(m.group(1), {})[budget] = (float(m.group(2)), float(m.group(3)))
    return rows, order, budgets


def fit(rows, c):
    err, a = 0.0, {}
    for k, pts in rows.items():
        vals = [(r - c) * s for r, s in pts.values()]
        a[k] = sum(vals) / len(vals)
        err += sum(((a[k] / s + c) / r - 1) ** 2 for r, s in pts.values())
    return err, a


def main():
    rows, order, budgets = load(sys.argv[1:])
    lo = min(r for pts in rows.values() for r, _ in pts.values())
    best_err, c = min((fit(rows, lo * i / 2000)[0], lo * i / 2000) for i in range(2000))
    _, a = fit(rows, c)
    n = sum(len(p) for p in rows.values())
    print("reference's relMSE c = %.4g (rms relative residual of the fit %.3f, %d points)\n" % (c, (best_err / n) ** 0.5, n))
    first = order[0]
    print("| configuration | a (relMSE x spp) | %s / this per sample | %s |" %
          (first, " | ".join("%s / this at %s" % (first, b) for b in budgets)))
    print("|---|---|---|" + "---|" * len(budgets))
    for k in order:
        eq = []
        for b in budgets:
            if b in rows[k] and b in rows[first]:
                eq.append("%.2f" % ((a[first] / rows[first][b][1]) / (a[k] / rows[k][b][1])))
            else:
                eq.append("-")
        print("| %s | %.4g | %.2f | %s |" % (k, a[k], a[first] / a[k], " | ".join(eq)))


if __name__ == "__main__":
    main()
