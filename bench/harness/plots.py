"""Convergence plots: relMSE against seconds, log-log, one line per integrator."""

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MARKERS = "os^Dv<>pXh"


def convergence_plot(scene, rows, out_base, noise=None, metric="relmse", ylabel="relMSE"):
    """Writes out_base.png and out_base.svg; returns the two paths.

    rows: summary rows of one scene (mean seconds, mean metric, stderr)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6), dpi=100)
    integrators = []
    for r in rows:
        if r["integrator"] not in integrators:
            integrators.append(r["integrator"])
    for i, name in enumerate(integrators):
        pts = sorted((r["seconds"], r[metric], r.get(metric + "_stderr"))
                     for r in rows if r["integrator"] == name
                     and r["seconds"] and r[metric] and r[metric] > 0)
        if not pts:
            continue
        xs = [p[0] for p in pts]
        ys = [p[1] for p in pts]
        errs = [p[2] or 0.0 for p in pts]
        # Error bars are clipped so they stay positive on a log axis.
        lower = [min(e, y * 0.999) for e, y in zip(errs, ys)]
        ax.errorbar(xs, ys, yerr=[lower, errs], marker=MARKERS[i % len(MARKERS)],
                    capsize=3, label=name)
    if noise:
        ax.axhline(noise, color="0.5", linestyle="--", linewidth=1,
                   label="reference noise (%.3g)" % noise)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(scene)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    paths = [out_base + ".png", out_base + ".svg"]
    for p in paths:
        fig.savefig(p)
    plt.close(fig)
    return paths


def overhead_plot(rows, out_base):
    """Bar chart of gradient/primal time ratios at equal base samples."""
    fig, ax = plt.subplots(figsize=(6.4, 3.6), dpi=100)
    labels = ["%s\n%s/%s" % (r["scene"], r["gradient"], r["primal"]) for r in rows]
    vals = [r["overhead"] or 0.0 for r in rows]
    errs = [r.get("overhead_stderr") or 0.0 for r in rows]
    ax.bar(range(len(rows)), vals, yerr=errs, capsize=3, color="tab:blue")
    ax.axhline(5.0, color="0.5", linestyle="--", linewidth=1,
               label="5: gradient sample as costly as a primal one")
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("time ratio at equal spp")
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths = [out_base + ".png", out_base + ".svg"]
    for p in paths:
        fig.savefig(p)
    plt.close(fig)
    return paths
