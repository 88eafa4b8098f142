#!/usr/bin/python3
"""Manifold walks harvested from real renders: every walk an integrator makes while
rendering a scene, counted by the walk itself (GRADUS_WALK_STATS=1 makes gradus print
its process-wide walk counters at exit, one WALKSTATS line per direction: forward
walks and the reverse walks of the reversibility check).

  bench/manifold/walk_stats.py --bin-dir build/bin --label after --out walks.csv
  bench/manifold/walk_stats.py --bin-dir /path/to/baseline/bin --label before --out walks.csv

Appends one CSV row per (run, direction) and prints a Markdown table. The runs are
fixed sample counts (not time budgets), so a walk set depends only on the scene, the
integrator and the seed; the per-walk time is wall time inside the walk (2 threads).
"""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHARED = os.path.join(ROOT, "..", "shared", "scenes")

# (name, scene, integrator, extra gradus arguments); solver variants are added below.
RUNS = [
    ("water-caustic gvcm case 2", f"{SHARED}/water-caustic/scene.pbrt", "gvcm",
     ["--resolution", "256x256", "--spp", "2"]),
    ("veach-ajar pmlt manifold", f"{SHARED}/veach-ajar/scene.pbrt", "pmlt",
     ["--resolution", "320x180", "--spp", "8"]),
    ("veach-ajar gbdpt", f"{SHARED}/veach-ajar/scene.pbrt", "gbdpt", ["--resolution", "320x180", "--spp", "2"]),
    ("veach-ajar gmlt", f"{SHARED}/veach-ajar/scene.pbrt", "gmlt",
     ["--resolution", "320x180", "--spp", "8"]),
    ("caustic-glass gbdpt", f"{SHARED}/caustic-glass/glass.pbrt", "gbdpt", ["--resolution", "210x300", "--spp", "2"]),
    ("glass-cube gvcm", f"{ROOT}/scenes/glass-cube.pbrt", "gvcm", ["--spp", "2"]),
    ("glass-cube gmlt", f"{ROOT}/scenes/glass-cube.pbrt", "gmlt", ["--spp", "16"]),
    ("glossy-box gbdpt", f"{ROOT}/scenes/glossy-box.pbrt", "gbdpt", ["--spp", "4"]),
]
SOLVER_INTEGRATORS = {"gbdpt", "gvcm"}  # integrators with a manifoldsolver parameter

FIELDS = ["label", "run", "solver", "direction", "walks", "success_pct", "median_iters", "p90_iters",
          "within3_pct", "cap_pct_of_failures", "traces_per_walk", "us_per_walk", "failures"]


def quantile(hist, total, q):
    acc = 0
    for i, h in enumerate(hist):
        acc += h
        if acc >= q * total and acc > 0:
            return i
    return len(hist) - 1


def parse(line):
    tok = line.split()
    d = {"direction": tok[1]}
    i = 2
    while tok[i] != "hist":
        d[tok[i]] = int(tok[i + 1])
        i += 2
    j = tok.index("status")
    d["hist"] = [int(x) for x in tok[i + 1:j]]
    d["status"] = {k: int(v) for k, v in (t.split("=") for t in tok[j + 1:])}
    return d


def row(label, name, solver, d):
    walks, succ = d["walks"], d["success"]
    fails = walks - succ
    hist = d["hist"]
    st = d["status"]
    cap = st.get("iteration_cap", 0) + st.get("not_converged", 0)  # "not converged" was the cap's name before
    return {
        "label": label, "run": name, "solver": solver, "direction": d["direction"], "walks": walks,
        "success_pct": round(100.0 * succ / walks, 1),
        "median_iters": quantile(hist, succ, 0.5) if succ else "",
        "p90_iters": quantile(hist, succ, 0.9) if succ else "",
        "within3_pct": round(100.0 * sum(hist[:4]) / succ, 1) if succ else "",
        "cap_pct_of_failures": round(100.0 * cap / fails, 1) if fails else 0.0,
        "traces_per_walk": round(d["traces"] / walks, 2),
        "us_per_walk": round(d["ns"] / walks / 1000.0, 2),
        "failures": " ".join(f"{k}={v}" for k, v in sorted(st.items(), key=lambda kv: -kv[1]) if k != "success"),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--label", required=True, help="e.g. before / after")
    ap.add_argument("--out", required=True, help="CSV file (appended)")
    ap.add_argument("--only", default="", help="comma-separated substrings of run names")
    ap.add_argument("--solvers", default="newton,ceres")
    args = ap.parse_args()
    gradus = os.path.join(args.bin_dir, "gradus")
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        if new:
            w.writeheader()
        for name, scene, integ, extra in RUNS:
            if args.only and not any(s in name for s in args.only.split(",")):
                continue
            if not os.path.exists(scene):
                print(f"skip {name}: {scene} absent", file=sys.stderr)
                continue
            solvers = args.solvers.split(",") if integ in SOLVER_INTEGRATORS else ["newton"]
            for solver in solvers:
                cmd = [gradus, scene, "--integrator", integ, "--quiet", "--seed", "1",
                       "--outfile", "/tmp/walk_stats.exr"] + extra
                if integ in SOLVER_INTEGRATORS:
                    cmd += ["--param", f"manifoldsolver={solver}"]
                env = dict(os.environ, GRADUS_WALK_STATS="1")
                p = subprocess.run(cmd, env=env, capture_output=True, text=True)
                if p.returncode != 0:
                    print(f"{name} ({solver}) failed: {p.stderr[-2000:]}", file=sys.stderr)
                    continue
                for line in p.stderr.splitlines():
                    if line.startswith("WALKSTATS"):
                        r = row(args.label, name, solver, parse(line))
                        w.writerow(r)
                        f.flush()
                        print("| " + " | ".join(str(r[k]) for k in FIELDS) + " |", flush=True)


if __name__ == "__main__":
    main()
