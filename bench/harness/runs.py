"""Time-budget runs: scenes x integrators x budgets x seeds, measured against references."""

import csv
import os
import sys
import time

from . import analysis

# The first seven columns are the interface; the rest document each run.
CSV_COLUMNS = ["scene", "integrator", "seconds", "spp", "relmse", "mse", "psnr",
               "budget", "seed", "wall_seconds", "relmse_untrimmed", "mean", "ref_mean", "mean_rel",
               "discard_fraction", "discard_count", "discarded_pixels", "ref_noise",
               "cpu_seconds", "loadavg", "layer", "image", "status", "error"]

SUMMARY_COLUMNS = ["scene", "integrator", "budget", "runs", "seconds", "seconds_stderr", "spp",
                   "relmse", "relmse_stderr", "relmse_untrimmed", "relmse_untrimmed_stderr",
                   "mse", "mse_stderr", "psnr", "psnr_stderr", "mean_rel", "mean_rel_stderr",
                   "cpu_seconds", "loadavg",
                   "ref_noise", "speedup",
                   "speedup_extrapolated", "baseline_seconds", "at_noise_floor"]


def trimming(scene, args):
    """(discard_fraction, discard_count): command line first, else the scene list's."""
    f = args.discard_fraction if args.discard_fraction is not None else scene.discard_fraction
    c = args.discard_count if args.discard_count is not None else scene.discard_count
    return float(f or 0.0), int(c or 0)


def render_path(out, scene, integrator, budget, seed):
    return os.path.join(out, "renders", scene, "%s-t%s-s%d.exr"
                        % (integrator, _tag(budget), seed))


def _tag(x):
    x = float(x)
    return str(int(x)) if x == int(x) else str(x).replace(".", "p")


def split_label(label):
    """'gpt/primal' -> ('gpt', 'primal'): an integrator, optionally one layer of its EXR
    (gradient integrators write primal, reconstructed_l1, reconstructed_l2, ...)."""
    integ, _, layer = label.partition("/")
    return integ, (layer or None)


def integrator_params(integ):
    """'vcm[mode=vm;radiusscale=2]' -> ('vcm', ['mode=vm', 'radiusscale=2']): an integrator
    with parameters passed as gradus --param NAME=VALUE (';' separates them, since
    --integrators is comma-separated)."""
    name, bracket, rest = integ.partition("[")
    if not bracket:
        return integ, []
    if not rest.endswith("]"):
        raise ValueError("integrator '%s': parameters must end with ']'" % integ)
    return name, [p for p in rest[:-1].split(";") if p]


def group_labels(labels):
    """[(integrator, [labels])] in first-seen order: one render serves every layer."""
    groups = []
    for label in labels:
        integ, _ = split_label(label)
        for g in groups:
            if g[0] == integ:
                g[1].append(label)
                break
        else:
            groups.append((integ, [label]))
    return groups


def plan(scenes, labels, budgets, seeds):
    """Run order: seed, budget, scene, integrator - integrators of one budget run one
    after another, so a change of machine load hits all of them alike."""
    for seed in seeds:
        for budget in budgets:
            for scene in scenes:
                for integ, group in group_labels(labels):
                    yield scene, integ, group, budget, seed


def measure(tools, scene, integ, labels, budget, seed, args):
    """Renders once and returns one row per label (layer) measured in that render."""
    path = render_path(args.out, scene.name, integ, budget, seed)
    frac, count = trimming(scene, args)
    base = {"scene": scene.name, "budget": budget, "seed": seed,
            "discard_fraction": frac, "discard_count": count, "ref_noise": scene.noise,
            "image": os.path.relpath(path, args.out), "status": "ok", "error": ""}
    try:
        base["loadavg"] = os.getloadavg()[0]
    except OSError:
        base["loadavg"] = None
    try:
        name, params = integrator_params(integ)
        meta, wall = tools.render(scene.scene, path, integrator=name, seconds=budget,
                                  seed=seed, nthreads=args.nthreads, params=params)
        base["wall_seconds"] = wall
        base["cpu_seconds"] = tools.last_cpu_seconds
        base["seconds"] = float(meta.get("render_seconds", wall))
        base["spp"] = int(float(meta.get("spp", 0)))
        if meta.get("integrator") and meta["integrator"] != name:
            raise RuntimeError("image metadata says integrator '%s', asked for '%s'"
                               % (meta["integrator"], name))
    except RuntimeError as e:
        base["status"] = "failed"
        base["error"] = str(e).replace("\n", " ")
    rows = []
    for label in labels:
        row = dict(base, integrator=label)
        row["layer"] = split_label(label)[1] or args.layer or ""
        if row["status"] == "ok":
            try:
                layer = row["layer"] or None
                d = tools.diff(path, scene.reference, frac, count, layer=layer)
                row["relmse"] = d["relmse"]
                row["mse"] = d["mse"]
                row["psnr"] = d["psnr"]
                row["discarded_pixels"] = d.get("discarded_pixels", 0)
                # Means over the pixels the relMSE uses: a lower relMSE bought by losing
                # energy shows here.
                row["mean"] = d.get("mean_image")
                row["ref_mean"] = d.get("mean_reference")
                row["mean_rel"] = d.get("mean_rel_diff")
                if frac or count:
                    row["relmse_untrimmed"] = tools.diff(path, scene.reference,
                                                         layer=layer)["relmse"]
                else:
                    row["relmse_untrimmed"] = d["relmse"]
            except RuntimeError as e:
                row["status"] = "failed"
                row["error"] = str(e).replace("\n", " ")
        rows.append(row)
    return rows


def run_all(tools, scenes, labels, budgets, seeds, args):
    os.makedirs(args.out, exist_ok=True)
    rows = []
    jobs = list(plan(scenes, labels, budgets, seeds))
    csv_path = os.path.join(args.out, "results.csv")
    started = time.monotonic()
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_COLUMNS, extrasaction="ignore")
        w.writeheader()
        stop = False
        for i, (scene, integ, group, budget, seed) in enumerate(jobs, 1):
            if not args.quiet:
                print("[%d/%d] %s %s %ss seed %d ... " % (i, len(jobs), scene.name, integ,
                                                          _tag(budget), seed),
                      end="", flush=True)
            new = measure(tools, scene, integ, group, budget, seed, args)
            for row in new:
                rows.append(row)
                w.writerow(_csv_row(row))
            f.flush()
            if not args.quiet:
                ok = [r for r in new if r["status"] == "ok"]
                if ok:
                    print("%.2fs %d spp relMSE %s" % (ok[0]["seconds"], ok[0]["spp"], ", ".join(
                        "%s%.4g" % ((r["integrator"] + " ") if len(new) > 1 else "", r["relmse"])
                        for r in ok)), flush=True)
                if len(ok) < len(new):
                    print("FAILED", flush=True)
            for row in new:
                if row["status"] != "ok":
                    print("error: %s: %s" % (row["integrator"], row["error"]), file=sys.stderr)
                    stop = stop or args.fail_fast
            if stop:
                break
    if not args.quiet:
        print("measured %d renders (%d rows) in %.0f s; results in %s"
              % (len(jobs), len(rows), time.monotonic() - started, csv_path))
    return rows


def _csv_row(row):
    out = {}
    for k in CSV_COLUMNS:
        v = row.get(k)
        if isinstance(v, float):
            v = "%.6g" % v if k not in ("seconds", "wall_seconds", "budget") else "%.4f" % v
        out[k] = "" if v is None else v
    return out


def write_summary(summary, out):
    path = os.path.join(out, "summary.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=SUMMARY_COLUMNS, extrasaction="ignore")
        w.writeheader()
        for s in summary:
            w.writerow({k: ("" if s.get(k) is None else
                            ("%.6g" % s[k] if isinstance(s[k], float) else s[k]))
                        for k in SUMMARY_COLUMNS})
    return path


def analyse(rows, baseline, floor_correction):
    summary = analysis.summarise(rows)
    analysis.speedups(summary, baseline, floor_correction)
    return summary
