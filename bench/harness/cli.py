"""Command line of bench/run."""

import argparse
import datetime
import html
import json
import os
import platform
import shlex
import sys

from . import overhead as overhead_mod
from . import reference, runs, scenes as scenes_mod
from .tools import HarnessError, Tools, find_bin_dir, git_commit, repo_root

DESCRIPTION = """\
Render scenes x integrators x wall-clock budgets with `gradus --time`, measure each
image against a reference with `imgtool diff` (relMSE with the papers' 0.001 offset and
optional outlier trimming, MSE, PSNR), and write DIR/results.csv (one row per run),
DIR/summary.csv and DIR/results.json (mean +- stderr over seeds, speed-ups against the
baseline), convergence plots DIR/convergence-<scene>.png/.svg and DIR/report.html.

Other modes: --overhead GRAD:PRIMAL,... times integrators at equal spp;
--make-reference renders references for scenes that have none."""

EXAMPLES = """\
examples:
  bench/run --scenes cornell-box,veach-bidir --integrators path,bdpt --times 5,15 --out /tmp/b
  bench/run --scenes cornell-box --integrators path --times 5,15,45 --seeds 3 --out /tmp/b
  bench/run --scenes veach-bidir --integrators path,bdpt --times 10,30 --discard-fraction 0.0001
  bench/run --overhead gpt:path,gbdpt:bdpt --spp 16 --scenes cornell-box --out /tmp/o
  bench/run --make-reference --scenes local-cornell-box --ref-spp 4096 --ref-runs 4
  bench/run --list-scenes
"""


def _floats(text, what):
    try:
        vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise HarnessError("%s wants comma-separated numbers, got '%s'" % (what, text))
    if not vals or any(v <= 0 for v in vals):
        raise HarnessError("%s wants positive numbers, got '%s'" % (what, text))
    return vals


def _names(text):
    return [x.strip() for x in text.split(",") if x.strip()]


def parser():
    p = argparse.ArgumentParser(prog="bench/run", description=DESCRIPTION, epilog=EXAMPLES,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scenes", help="comma-separated scene names from the scene list, or paths "
                   "to .pbrt files (default: every listed scene that has a reference)")
    p.add_argument("--integrators", default="path", help="comma-separated names (default: path); "
                   "NAME/LAYER measures one layer of NAME's EXR, e.g. gpt/primal, "
                   "gpt/reconstructed_l2 (one render serves all layers of NAME)")
    p.add_argument("--baseline", help="integrator that speed-ups are measured against "
                   "(default: the first of --integrators)")
    p.add_argument("--times", default="5,15,45,135",
                   help="wall-clock budgets in seconds (default: 5,15,45,135)")
    p.add_argument("--seeds", type=int, default=1,
                   help="independent runs per point, seeds SEED_BASE.. (default: 1)")
    p.add_argument("--seed-base", type=int, default=0)
    p.add_argument("--nthreads", type=int, help="passed to gradus --nthreads")
    p.add_argument("--out", help="output folder (default: bench/out/<date-time>, git-ignored)")
    p.add_argument("--bin-dir", help="folder with gradus and imgtool (default: $GRADUS_BIN, "
                   "else <repo>/build/bin)")
    p.add_argument("--scene-list", help="scene list JSON (default: bench/scenes.json)")
    p.add_argument("--shared-dir", help="the shared folder (default: $GRADUS_SHARED, else "
                   "../shared beside the repository)")
    p.add_argument("--refdir", help="references made by reference mode (default: bench/refs)")
    p.add_argument("--discard-fraction", type=float, help="ignore this fraction of pixels with "
                   "the highest relMSE (G-BDPT paper: 0.0001); overrides the scene list")
    p.add_argument("--discard-count", type=int, help="ignore this many highest-error pixels "
                   "(G-VCM paper: 50); overrides the scene list")
    p.add_argument("--layer", help="EXR layer to measure (default: imgtool's choice)")
    p.add_argument("--report-time", type=float, help="budget whose images the report shows "
                   "(default: the largest)")
    p.add_argument("--crops", type=int, default=2, help="automatic crops per scene (default 2)")
    p.add_argument("--no-floor-correction", action="store_true",
                   help="do not subtract the reference noise floor before computing speed-ups")
    p.add_argument("--no-report", action="store_true", help="only the CSV/JSON results")
    p.add_argument("--report-only", metavar="DIR", help="rebuild summary, plots and report of "
                   "an earlier run from DIR/results.json, without rendering")
    p.add_argument("--fail-fast", action="store_true", help="stop at the first failed render")
    p.add_argument("--dry-run", action="store_true", help="print the plan and exit")
    p.add_argument("--list-scenes", action="store_true", help="print the scene list and exit")
    p.add_argument("--quiet", action="store_true")
    p.add_argument("--verbose", action="store_true", help="print every command")
    g = p.add_argument_group("overhead mode")
    g.add_argument("--overhead", metavar="GRAD:PRIMAL,...",
                   help="time each gradient integrator against its primal one at equal spp")
    g.add_argument("--spp", type=int, default=16, help="base samples per pixel (default: 16)")
    g = p.add_argument_group("reference mode")
    g.add_argument("--make-reference", action="store_true",
                   help="render references for the --scenes into --refdir")
    g.add_argument("--ref-time", type=float, help="seconds per reference run")
    g.add_argument("--ref-spp", type=int, help="samples per pixel per reference run")
    g.add_argument("--ref-runs", type=int, default=4,
                   help="independent runs to average (default: 4; >= 2 gives a noise estimate)")
    g.add_argument("--ref-integrator", help="integrator for references (default: the scene's)")
    g.add_argument("--force", action="store_true", help="replace an existing reference")
    return p


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parser().parse_args(argv)
    try:
        return _main(args, argv)
    except HarnessError as e:
        print("bench/run: error: %s" % e, file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into head and the like
        return 0
    except KeyboardInterrupt:
        print("bench/run: interrupted", file=sys.stderr)
        return 130


def _main(args, argv):
    root = repo_root()
    args.refdir = os.path.abspath(args.refdir or os.path.join(root, "bench", "refs"))
    catalogue, absent, sdir = scenes_mod.load_catalogue(args.scene_list, args.shared_dir)

    if args.list_scenes:
        for name, s in catalogue.items():
            scenes_mod.resolve([name], catalogue, absent, args.refdir)
            print("%-22s %-8s %s\n%22s ref: %s (noise %s)" % (
                name, s.origin, s.scene, "", s.reference or "none (use --make-reference)",
                s.noise))
        for name, folder in absent.items():
            print("%-22s missing  %s" % (name, folder))
        return 0

    tools = Tools(find_bin_dir(args.bin_dir), verbose=args.verbose)
    if args.report_only:
        return _report_only(tools, args)
    available = tools.list_integrators()

    # Every name is checked before the first render.
    if args.overhead:
        pairs = overhead_mod.parse_pairs(args.overhead)
        wanted = [n for pair in pairs for n in pair]
    elif args.make_reference:
        wanted = [args.ref_integrator] if args.ref_integrator else []
    else:
        wanted = _names(args.integrators)
        if not wanted:
            raise HarnessError("--integrators is empty")
    unknown = [n for n in dict.fromkeys(runs.integrator_params(runs.split_label(w)[0])[0] for w in wanted)
               if n not in available]
    if unknown:
        raise HarnessError("unknown integrator%s %s; gradus --list-integrators offers: %s"
                           % ("s" if len(unknown) > 1 else "", ", ".join(unknown),
                              ", ".join(available)))

    if args.scenes:
        names = _names(args.scenes)
    elif args.make_reference:
        raise HarnessError("--make-reference needs --scenes")
    else:
        names = [n for n in catalogue]
    chosen = scenes_mod.resolve(names, catalogue, absent, args.refdir)
    if not args.scenes:
        chosen = [s for s in chosen if s.reference]
        if not chosen:
            raise HarnessError("no scene with a reference found; give --scenes")

    if args.make_reference:
        if not args.ref_time and not args.ref_spp:
            raise HarnessError("reference mode needs --ref-time and/or --ref-spp")
        if args.dry_run:
            for s in chosen:
                print("reference %s: %d runs of %s" % (s.name, args.ref_runs, s.scene))
            return 0
        for s in chosen:
            reference.make_reference(tools, s, args)
        return 0

    if not args.out:
        stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
        args.out = os.path.join(root, "bench", "out", stamp)
    args.out = os.path.abspath(args.out)
    seeds = list(range(args.seed_base, args.seed_base + max(1, args.seeds)))
    meta = {"command": "bench/run " + " ".join(shlex.quote(a) for a in argv),
            "date": datetime.datetime.now().isoformat(timespec="seconds"),
            "host": platform.node(), "cpus": os.cpu_count(), "commit": git_commit(root),
            "bin_dir": tools.bin_dir, "shared_dir": sdir, "nthreads": args.nthreads,
            "seeds": seeds, "available_integrators": available}

    if args.overhead:  # equal-spp timing needs no reference
        return _overhead(tools, chosen, pairs, seeds, args, meta)

    missing = [s.name for s in chosen if not s.reference]
    if missing:
        raise HarnessError("no reference for %s: make one first, e.g. bench/run --make-reference "
                           "--scenes %s --ref-spp 4096 --refdir %s"
                           % (", ".join(missing), ",".join(missing), args.refdir))

    integrators = wanted
    baseline = args.baseline or integrators[0]
    if baseline not in integrators:
        raise HarnessError("--baseline %s is not among --integrators" % baseline)
    budgets = _floats(args.times, "--times")
    report_budget = args.report_time or max(budgets)
    if report_budget not in budgets:
        raise HarnessError("--report-time %g is not among --times" % report_budget)

    renderers = len(runs.group_labels(integrators))
    total = len(seeds) * sum(budgets) * len(chosen) * renderers
    if not args.quiet or args.dry_run:
        print("plan: %d scene(s) x %d integrator(s) x budgets %s s x %d seed(s): about %.0f s "
              "of rendering (+ scene loading)" % (len(chosen), renderers,
                                                  ",".join("%g" % b for b in budgets),
                                                  len(seeds), total))
    if args.dry_run:
        for scene, integ, labels, budget, seed in runs.plan(chosen, integrators, budgets, seeds):
            print("  %s %s %gs seed %d -> %s" % (scene.name, integ, budget, seed,
                                                 ", ".join(labels)))
        return 0

    rows = runs.run_all(tools, chosen, integrators, budgets, seeds, args)
    meta.update({"scenes": [s.as_dict() for s in chosen], "integrators": integrators,
                 "baseline": baseline, "budgets": budgets, "report_budget": report_budget,
                 "discard_fraction": args.discard_fraction, "discard_count": args.discard_count,
                 "layer": args.layer})
    return _finish(tools, args, meta, chosen, rows)


def _report_only(tools, args):
    """Summary, plots and report again from an earlier run's results.json."""
    src = os.path.abspath(args.report_only)
    try:
        with open(os.path.join(src, "results.json")) as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise HarnessError("cannot read %s/results.json: %s" % (src, e))
    meta = data["meta"]
    args.out = src
    args.discard_fraction = meta.get("discard_fraction")
    args.discard_count = meta.get("discard_count")
    args.layer = meta.get("layer")
    if args.baseline:
        meta["baseline"] = args.baseline
    if args.report_time:
        meta["report_budget"] = args.report_time
    chosen = [scenes_mod.Scene(**d) for d in meta["scenes"]]
    return _finish(tools, args, meta, chosen, data["runs"])


def _finish(tools, args, meta, chosen, rows):
    integrators, baseline = meta["integrators"], meta["baseline"]
    budgets, report_budget = meta["budgets"], meta.get("report_budget") or max(meta["budgets"])
    floor = not args.no_floor_correction
    meta["floor_correction"] = floor
    summary = runs.analyse(rows, baseline, floor)
    runs.write_summary(summary, args.out)
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump({"meta": meta, "runs": rows, "summary": summary}, f, indent=1)

    if not args.no_report:
        from . import report  # matplotlib loads only when a report is made
        sections = [report.overview_section(summary, chosen, integrators, baseline,
                                            report_budget)]
        for s in chosen:
            srows = [r for r in summary if r["scene"] == s.name]
            if not srows:
                sections.append("<h2>%s</h2><p class=warn>no successful run</p>"
                                % html.escape(s.name))
                continue
            assets = report.prepare_scene_assets(tools, s, srows, rows, integrators, baseline,
                                                 report_budget, args, crop_count=args.crops)
            sections.append(report.scene_section(s, srows, assets, integrators, baseline,
                                                 report_budget, args, floor))
        path = report.write_report(os.path.join(args.out, "report.html"),
                                   "Gradus benchmark: relMSE against render time",
                                   _header(meta, integrators, baseline, budgets, chosen),
                                   sections)
        if not args.quiet:
            print("report: %s" % path)
    failed = [r for r in rows if r["status"] != "ok"]
    if failed:
        print("bench/run: %d of %d runs failed (see the 'error' column of results.csv)"
              % (len(failed), len(rows)), file=sys.stderr)
        return 1
    return 0


def _header(meta, integrators, baseline, budgets, chosen):
    items = [("command", "<code>%s</code>" % html.escape(meta["command"])),
             ("date", html.escape(meta["date"])),
             ("machine", "%s, %s CPUs, gradus --nthreads %s" % (html.escape(meta["host"]),
                                                               meta["cpus"],
                                                               meta["nthreads"] or "default")),
             ("commit", html.escape(meta["commit"])),
             ("integrators", html.escape(", ".join(integrators)) +
              " (baseline: %s)" % html.escape(baseline)),
             ("budgets", ", ".join("%g s" % b for b in budgets)),
             ("seeds", ", ".join(str(s) for s in meta["seeds"])),
             ("scenes", " ".join('<a href="#scene-%s">%s</a>' % (html.escape(s.name),
                                                                 html.escape(s.name))
                                 for s in chosen)),
             ("files", '<a href="results.csv">results.csv</a>, <a href="summary.csv">summary.csv'
                       '</a>, <a href="results.json">results.json</a>')]
    return items


def _overhead(tools, chosen, pairs, seeds, args, meta):
    from . import plots, report
    if args.dry_run:
        for s in chosen:
            for g, p in pairs:
                print("overhead %s: %s vs %s at %d spp, %d seed(s)" % (s.name, g, p, args.spp,
                                                                       len(seeds)))
        return 0
    rows, raw = overhead_mod.run_overhead(tools, chosen, pairs, args.spp, seeds, args)
    meta.update({"pairs": pairs, "spp": args.spp, "scenes": [s.as_dict() for s in chosen]})
    with open(os.path.join(args.out, "overhead.json"), "w") as f:
        json.dump({"meta": meta, "runs": raw, "overhead": rows}, f, indent=1)
    png = None
    if not args.no_report:
        png = plots.overhead_plot(rows, os.path.join(args.out, "overhead"))[0]
        items = [("command", "<code>%s</code>" % html.escape(meta["command"])),
                 ("date", html.escape(meta["date"])), ("commit", html.escape(meta["commit"])),
                 ("files", '<a href="overhead.csv">overhead.csv</a>, '
                           '<a href="overhead.json">overhead.json</a>')]
        report.write_report(os.path.join(args.out, "report.html"),
                            "Gradus benchmark: overhead at equal samples", items,
                            [report.overhead_section(rows, png, args.out)])
    if not args.quiet:
        for r in rows:
            print("%s: %s / %s at %d spp = x%.2f" % (r["scene"], r["gradient"], r["primal"],
                                                     r["spp"], r["overhead"] or float("nan")))
        print("results: %s" % os.path.join(args.out, "overhead.csv"))
    return 0
