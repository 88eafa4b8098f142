#!/usr/bin/env python3
"""Renders every pbrt-v3 reference scene (../shared/references/<name>/ref.pbrt)
with a Gradus integrator at growing sample counts and prints the table
(scene, spp, seconds, relMSE, relMSE - reference noise, mean difference).

Unbiased rendering shows relMSE falling roughly as 1/spp down to the
reference's own noise (ref.noise).

usage: bench/coverage/reference_table.py [--integrator path] [--spp 4,16,64]
       [--scenes a,b] [--bin build/bin] [--out DIR] [--nthreads N]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--integrator", default="path")
    ap.add_argument("--spp", default="4,16,64")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--refs", default=os.path.join(ROOT, "..", "shared", "references"))
    ap.add_argument("--out", default="")
    ap.add_argument("--nthreads", default="0")
    ap.add_argument("--seed", default="1")
    args = ap.parse_args()
    if not os.path.isdir(args.refs):
        sys.exit(f"no references at {args.refs}")
    scenes = args.scenes.split(",") if args.scenes else sorted(
        d for d in os.listdir(args.refs) if os.path.exists(os.path.join(args.refs, d, "ref.pbrt")))
    out = args.out or tempfile.mkdtemp(prefix="gradus_table_")
    os.makedirs(out, exist_ok=True)
    rows = []
    print(f"{'scene':15s} {'spp':>5s} {'seconds':>8s} {'relMSE':>10s} {'minus noise':>11s} {'mean diff %':>11s}")
    for scene in scenes:
        d = os.path.join(args.refs, scene)
        ref = os.path.join(d, "ref.exr")
        noise = float(open(os.path.join(d, "ref.noise")).read().split()[0]) if os.path.exists(
            os.path.join(d, "ref.noise")) else 0.0
        for spp in [int(s) for s in args.spp.split(",")]:
            img = os.path.join(out, f"{scene}-{args.integrator}-{spp}.exr")
            cmd = [os.path.join(args.bin, "gradus"), os.path.join(d, "ref.pbrt"), "--integrator", args.integrator,
                   "--spp", str(spp), "--seed", args.seed, "--outfile", img, "--quiet", "--nthreads", args.nthreads]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0:
                print(f"{scene:15s} {spp:5d}  FAILED: {r.stderr.strip()}")
                rows.append({"scene": scene, "spp": spp, "error": r.stderr.strip()})
                continue
            info = json.loads(subprocess.run([os.path.join(args.bin, "imgtool"), "info", img, "--json"],
                                             capture_output=True, text=True, check=True).stdout)
            secs = float(info["metadata"]["render_seconds"])
            diff = json.loads(subprocess.run([os.path.join(args.bin, "imgtool"), "diff", img, ref, "--json"],
                                             capture_output=True, text=True, check=True).stdout)
            row = {"scene": scene, "integrator": args.integrator, "spp": spp, "seconds": secs,
                   "relmse": diff["relmse"], "ref_noise": noise, "mean_rel_diff": diff["mean_rel_diff"]}
            rows.append(row)
            print(f"{scene:15s} {spp:5d} {secs:8.2f} {row['relmse']:10.4g} {row['relmse'] - noise:11.4g} "
                  f"{100 * row['mean_rel_diff']:11.3f}", flush=True)
    with open(os.path.join(out, "table.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print(f"images and table.json in {out}")


if __name__ == "__main__":
    main()
