"""Overhead mode: render time of a gradient integrator against its primal counterpart
at an equal number of base samples per pixel (as in the G-BDPT paper's Table 1,
where 5 means a gradient sample costs as much as a conventional one, since each
base path comes with four offset paths)."""

import csv
import os

from . import analysis
from .runs import integrator_params
from .tools import HarnessError

COLUMNS = ["scene", "gradient", "primal", "spp", "runs", "gradient_seconds",
           "gradient_seconds_stderr", "primal_seconds", "primal_seconds_stderr",
           "overhead", "overhead_stderr"]


def parse_pairs(text):
    pairs = []
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        parts = item.split(":")
        if len(parts) != 2 or not all(parts):
            raise HarnessError("--overhead wants GRADIENT:PRIMAL pairs, e.g. gpt:path,gbdpt:bdpt; "
                               "got '%s'" % item)
        pairs.append((parts[0], parts[1]))
    if not pairs:
        raise HarnessError("--overhead needs at least one GRADIENT:PRIMAL pair")
    return pairs


def run_overhead(tools, scenes, pairs, spp, seeds, args):
    """Both members of a pair are rendered back to back for every seed."""
    raw = []
    os.makedirs(args.out, exist_ok=True)
    for scene in scenes:
        for grad, prim in pairs:
            times = {"gradient": [], "primal": []}  # by role: a pair may name one integrator twice
            for k, seed in enumerate(seeds):
                # Alternate which one goes first, so a drift of machine load cancels out.
                order = [("primal", prim), ("gradient", grad)]
                for role, integ in (order if k % 2 == 0 else order[::-1]):
                    path = os.path.join(args.out, "renders", scene.name,
                                        "overhead-%s-%s-spp%d-s%d.exr" % (role, integ, spp, seed))
                    name, params = integrator_params(integ)
                    meta, wall = tools.render(scene.scene, path, integrator=name, spp=spp,
                                              seed=seed, nthreads=args.nthreads, params=params)
                    got = int(float(meta.get("spp", spp)))
                    if got != spp:
                        raise HarnessError("%s rendered %d spp instead of %d on %s (sampler "
                                           "rounding?); choose a power of two"
                                           % (integ, got, spp, scene.name))
                    secs = float(meta.get("render_seconds", wall))
                    times[role].append(secs)
                    raw.append({"scene": scene.name, "integrator": integ, "role": role, "spp": spp,
                                "seed": seed, "seconds": secs, "wall_seconds": wall})
                    if not args.quiet:
                        print("[overhead] %s %s %d spp seed %d: %.2f s"
                              % (scene.name, integ, spp, seed, secs), flush=True)
            ratio_row = _ratio(scene.name, grad, prim, spp, times)
            raw.append(ratio_row)
    rows = [r for r in raw if "overhead" in r]
    runs = [r for r in raw if "overhead" not in r]
    path = os.path.join(args.out, "overhead.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("%.6g" % r[k] if isinstance(r.get(k), float) else
                            ("" if r.get(k) is None else r[k])) for k in COLUMNS})
    return rows, runs


def _ratio(scene, grad, prim, spp, times):
    gm, gse, n = analysis.mean_stderr(times["gradient"])
    pm, pse, _ = analysis.mean_stderr(times["primal"])
    ratio = gm / pm if gm and pm else None
    ratio_se = None
    if ratio and gse is not None and pse is not None:
        # First-order propagation for a ratio of independent means.
        ratio_se = ratio * ((gse / gm) ** 2 + (pse / pm) ** 2) ** 0.5
    return {"scene": scene, "gradient": grad, "primal": prim, "spp": spp, "runs": n,
            "gradient_seconds": gm, "gradient_seconds_stderr": gse,
            "primal_seconds": pm, "primal_seconds_stderr": pse,
            "overhead": ratio, "overhead_stderr": ratio_se}
