#!/usr/bin/python3
"""Cost of an M-BDPT iteration against a BDPT pass, whole renders and the marginal iteration.

Each pair MBDPT:BDPT (configurations as INTEGRATOR[:PARAM=VALUE,...]) renders SCENE at --spp LO
and --spp HI, alternating the two sides, for --rounds rounds; prints per round the ratio of the
render seconds at HI spp (what a short render costs: first-touch page faults of the stored
subpaths and the scene's setup included) and of the marginal seconds per iteration
(T_HI - T_LO) / (HI - LO), the steady-state cost of one more iteration.

  bench/mbdpt/cost.py SCENE.pbrt --args "--resolution 320x180 --nthreads 2" \\
      mbdpt:bdpt mbdpt:configuration=paper:bdpt:rrdepth=-1
Pairs are written A/B: "mbdpt/bdpt", "mbdpt:configuration=paper/bdpt:rrdepth=-1".
Environment: GRADUS_BIN (directory of gradus and imgtool, default build/bin).
"""
import argparse
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.environ.get("GRADUS_BIN", os.path.join(ROOT, "build/bin"))

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scene")
ap.add_argument("pairs", nargs="+", help="A/B, each INTEGRATOR[:PARAM=VALUE,...]")
ap.add_argument("--lo", type=int, default=4)
ap.add_argument("--hi", type=int, default=12)
ap.add_argument("--rounds", type=int, default=2)
ap.add_argument("--seed", type=int, default=1)
ap.add_argument("--args", default="")
a = ap.parse_args()
tmp = tempfile.mkdtemp(prefix="mbdpt-cost-")


def seconds(spec, spp):
    name, _, ps = spec.partition(":")
    params = [x for p in ps.split(",") if p for x in ("--param", p)]
    out = os.path.join(tmp, "c.exr")
    subprocess.run([os.path.join(BIN, "gradus"), a.scene, "--integrator", name, *params, "--spp", str(spp),
                    "--seed", str(a.seed), *a.args.split(), "--quiet", "--outfile", out], check=True)
    info = subprocess.run([os.path.join(BIN, "imgtool"), "info", out], check=True, capture_output=True,
                          text=True).stdout
    for line in info.splitlines():
        if line.strip().startswith("render_seconds = "):
            return float(line.split("=", 1)[1])
    raise RuntimeError("no render_seconds in " + out)


print("%s, %s, spp %d and %d\n" % (a.scene, a.args, a.lo, a.hi))
print("| pair | round | A s at %d spp | B s | A / B at %d spp | A / B per marginal iteration |" % (a.hi, a.hi))
print("|---|---|---|---|---|---|")
for pair in a.pairs:
    A, B = pair.split("/")
    for r in range(a.rounds):
        t = {}
        for side in ((A, B) if r % 2 == 0 else (B, A)):  # alternate which side runs first
            t[side] = (seconds(side, a.lo), seconds(side, a.hi))
        (alo, ahi), (blo, bhi) = t[A], t[B]
        marg = ((ahi - alo) / (bhi - blo)) if bhi > blo else float("nan")
        print("| %s | %d | %.2f | %.2f | %.3f | %.3f |" % (pair, r + 1, ahi, bhi, ahi / bhi, marg), flush=True)
