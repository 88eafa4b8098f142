#!/usr/bin/python3
"""Equal-spp or equal-time relMSE of BDPT and M-BDPT variants against a reference.

Every configuration renders the scene with seeds 1..N, either at SPP samples per pixel
(--spp, not timing-sensitive) or for T seconds of wall time (--time: `gradus --time`);
imgtool diff gives the relMSE against the reference (and the image mean is printed beside
it, as a bias check). One table row per configuration: mean relMSE over the seeds (and
each seed's), the same with the reference's own estimated relMSE subtracted (--ref-noise;
E[MSE(image, ref)] = MSE(image) + Var(ref) for an independent reference), the ratio to the
first configuration's (> 1: better than it), the spp reached (equal time) and the image
mean relative to the reference's.

  bench/mbdpt/equal_spp.py SCENE.pbrt REF.exr --spp 16 --seeds 2 \\
      --args "--resolution 320x180 --nthreads 2" \\
      bdpt mbdpt mbdpt:matrixrows=all bdpt:rrdepth=-1 mbdpt:rrdepth=-1
  bench/mbdpt/equal_spp.py SCENE.pbrt REF.exr --time 20 --seeds 4 --jobs 2 \\
      --args "--nthreads 1" bdpt mbdpt mbdpt:configuration=paper
--jobs J runs J renders at a time (give each --nthreads 1 on a J-core machine: every
render then shares the machine with J - 1 others, whatever its configuration).
Environment: GRADUS_BIN (directory of gradus and imgtool, default build/bin).
"""
import argparse
import concurrent.futures
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.environ.get("GRADUS_BIN", os.path.join(ROOT, "build/bin"))

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("scene")
ap.add_argument("ref")
ap.add_argument("configs", nargs="+", help="INTEGRATOR[:PARAM=VALUE,...]")
ap.add_argument("--spp", type=int, default=16)
ap.add_argument("--time", type=float, default=0, help="seconds per render (equal time; --spp ignored)")
ap.add_argument("--seeds", type=int, default=2)
ap.add_argument("--first-seed", type=int, default=1)
ap.add_argument("--jobs", type=int, default=1, help="renders at a time")
ap.add_argument("--ref-noise", type=float, default=0, help="the reference's estimated relMSE")
ap.add_argument("--args", default="", help="more gradus options for every render")
ap.add_argument("--outdir", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "mbdpt-equal-spp"))
ap.add_argument("--reuse", action="store_true", help="keep renders already in --outdir")
a = ap.parse_args()
os.makedirs(a.outdir, exist_ok=True)


def imgtool(*args):
    return subprocess.run([os.path.join(BIN, "imgtool"), *args], check=True, capture_output=True, text=True).stdout


ref_mean = json.loads(imgtool("diff", a.ref, a.ref, "--json"))["mean_reference"]
base = os.path.splitext(os.path.basename(a.scene))[0]
budget = "%gs" % a.time if a.time else "%dspp" % a.spp
seeds = list(range(a.first_seed, a.first_seed + a.seeds))


def output(spec, seed):
    tag = "%s-%s-%s-%d" % (base, spec.replace(":", "_").replace("=", "_").replace(",", "_"), budget, seed)
    return os.path.join(a.outdir, tag + ".exr")


def render(spec, seed):
    out = output(spec, seed)
    if a.reuse and os.path.exists(out):
        return
    name, _, ps = spec.partition(":")
    params = [x for p in ps.split(",") if p for x in ("--param", p)]
    count = ["--time", str(a.time)] if a.time else ["--spp", str(a.spp)]
    subprocess.run([os.path.join(BIN, "gradus"), a.scene, "--integrator", name, *params, *count,
                    "--seed", str(seed), *a.args.split(), "--quiet", "--outfile", out], check=True)


# Seeds outermost: with --jobs, each configuration meets the same mix of neighbours.
work = [(spec, seed) for seed in seeds for spec in a.configs]
with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as ex:
    for f in [ex.submit(render, *w) for w in work]:
        f.result()

rows = []
for spec in a.configs:
    rel, means, spps = [], [], []
    for seed in seeds:
        out = output(spec, seed)
        d = json.loads(imgtool("diff", out, a.ref, "--json"))
        rel.append(d["relmse"])
        means.append(d["mean_image"])
        meta = dict(l.split(" = ", 1) for l in (x.strip() for x in imgtool("info", out).splitlines()) if " = " in l)
        spps.append(int(meta.get("spp", "0")))
    m = sum(rel) / len(rel)
    rows.append((spec, m, m - a.ref_noise, rel, sum(spps) / len(spps), sum(means) / len(means) / ref_mean - 1))
print("%s, %s, seeds %s, reference %s (mean %.4g, estimated relMSE %g)\n" %
      (a.scene, budget, ",".join(map(str, seeds)), a.ref, ref_mean, a.ref_noise))
print("| configuration | relMSE (mean) | per seed | minus the reference's | %s / this | spp | mean vs ref |" % rows[0][0])
print("|---|---|---|---|---|---|---|")
for spec, m, mc, rel, spp, dm in rows:
    print("| %s | %.4g | %s | %.4g | %.2f (%.2f) | %.1f | %+.2f%% |" %
          (spec, m, " ".join("%.3g" % r for r in rel), mc, rows[0][1] / m, rows[0][2] / mc if mc > 0 else float("nan"),
           spp, 100 * dm))
