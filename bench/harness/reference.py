"""Reference mode: long renders, or the spp-weighted average of independent runs.

The reference of scene NAME goes to <refdir>/NAME/: run-<k>.exr (kept so the
reference can be extended or checked), ref.exr (imgtool merge of the runs),
ref.json (scene, integrator, seeds, spp and seconds of each run, commit) and
ref.noise, the estimated relMSE of ref.exr itself:

    the runs are split into two halves A and B (merged separately). For
    independent unbiased estimates with variance ~ 1/spp,
        relMSE(A, B) ~ s2 (1/nA + 1/nB),   relMSE(ref) ~ s2 / (nA + nB),
    so relMSE(ref) ~ relMSE(A, B) / ((1/nA + 1/nB) (nA + nB))  (= /4 for equal halves).

This mirrors how the shared references' ref.noise was estimated (a second,
independent render) and uses the same 0.001 offset.
"""

import datetime
import json
import os
import shutil

from .tools import HarnessError, git_commit, repo_root


REF_SEED_BASE = 100000  # far from the seeds of timed runs (0, 1, 2, ...)


def make_reference(tools, scene, args):
    folder = os.path.join(args.refdir, scene.name)
    ref = os.path.join(folder, "ref.exr")
    if os.path.exists(ref) and not args.force:
        raise HarnessError("%s exists; use --force to replace it" % ref)
    if scene.origin == "shared":
        raise HarnessError("scene '%s' already has a pbrt-v3 reference (%s); reference mode "
                           "is for scenes without one" % (scene.name, scene.reference))
    runs = max(1, int(args.ref_runs))
    os.makedirs(folder, exist_ok=True)
    records = []
    paths = []
    for k in range(runs):
        seed = REF_SEED_BASE + k
        path = os.path.join(folder, "run-%d.exr" % k)
        if not args.quiet:
            print("[reference %s %d/%d] seed %d ..." % (scene.name, k + 1, runs, seed),
                  end=" ", flush=True)
        meta, wall = tools.render(scene.scene, path, integrator=args.ref_integrator,
                                  seconds=args.ref_time, spp=args.ref_spp, seed=seed,
                                  nthreads=args.nthreads)
        rec = {"file": os.path.basename(path), "seed": seed, "spp": int(float(meta.get("spp", 0))),
               "render_seconds": float(meta.get("render_seconds", wall)), "wall_seconds": wall,
               "integrator": meta.get("integrator")}
        if not args.quiet:
            print("%d spp, %.1f s" % (rec["spp"], rec["render_seconds"]), flush=True)
        records.append(rec)
        paths.append(path)
    spp = [r["spp"] for r in records]
    weights = spp if all(spp) else None
    if len(paths) == 1:
        shutil.copyfile(paths[0], ref)
    else:
        tools.merge(ref, paths, weights)
    noise, pair = None, None
    if len(paths) >= 2:
        half = len(paths) // 2
        a, b = os.path.join(folder, "half-a.exr"), os.path.join(folder, "half-b.exr")
        _merge_or_copy(tools, a, paths[:half], spp[:half] if weights else None)
        _merge_or_copy(tools, b, paths[half:], spp[half:] if weights else None)
        pair = tools.diff(a, b)["relmse"]
        na = float(sum(spp[:half]) if weights else half)
        nb = float(sum(spp[half:]) if weights else len(paths) - half)
        noise = pair / ((1.0 / na + 1.0 / nb) * (na + nb))
        os.remove(a)
        os.remove(b)
        with open(os.path.join(folder, "ref.noise"), "w") as f:
            f.write("%.3g\n" % noise)
    info = {
        "scene": scene.scene, "name": scene.name,
        "integrator": records[0]["integrator"],
        "requested": {"integrator": args.ref_integrator, "seconds": args.ref_time,
                      "spp": args.ref_spp, "runs": runs, "nthreads": args.nthreads},
        "runs": records, "total_spp": sum(spp),
        "total_render_seconds": sum(r["render_seconds"] for r in records),
        "relmse_between_halves": pair, "noise": noise,
        "noise_method": "relMSE(half A, half B) / ((1/nA + 1/nB)(nA + nB)), eps 0.001"
                        if noise is not None else "one run: no estimate",
        "commit": git_commit(repo_root()),
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
    }
    with open(os.path.join(folder, "ref.json"), "w") as f:
        json.dump(info, f, indent=2)
    if not args.quiet:
        print("reference %s: %d spp in %d runs%s -> %s" % (
            scene.name, sum(spp), runs,
            (", estimated relMSE %.3g" % noise) if noise is not None else "", ref))
    return info


def _merge_or_copy(tools, out, paths, weights):
    if len(paths) == 1:
        shutil.copyfile(paths[0], out)
    else:
        tools.merge(out, paths, weights)
