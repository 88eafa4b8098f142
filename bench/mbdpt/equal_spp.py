#!/usr/bin/python3
"""Equal-spp relMSE of BDPT and M-BDPT variants against a reference (not timing-sensitive).

Every configuration renders the scene at SPP samples per pixel with seeds 1..N; imgtool diff
gives the relMSE against the reference (and the image mean is printed beside it, as a bias
check). One table row per configuration: mean relMSE over the seeds (and each seed's), the
ratio to the first configuration's (> 1: better than it), and the image mean relative to the
reference's.

  bench/mbdpt/equal_spp.py SCENE.pbrt REF.exr --spp 16 --seeds 2 \\
      --args "--resolution 320x180 --nthreads 2" \\
      bdpt mbdpt mbdpt:matrixrows=all bdpt:rrdepth=-1 mbdpt:rrdepth=-1
Environment: GRADUS_BIN (directory of gradus and imgtool, default build/bin).
"""
import argparse
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
ap.add_argument("--seeds", type=int, default=2)
ap.add_argument("--args", default="", help="more gradus options for every render")
ap.add_argument("--outdir", default=os.path.join(os.environ.get("TMPDIR", "/tmp"), "mbdpt-equal-spp"))
ap.add_argument("--reuse", action="store_true", help="keep renders already in --outdir")
a = ap.parse_args()
os.makedirs(a.outdir, exist_ok=True)


ref_mean = json.loads(subprocess.run([os.path.join(BIN, "imgtool"), "diff", a.ref, a.ref, "--json"],
                                     check=True, capture_output=True, text=True).stdout)["mean_reference"]
base = os.path.splitext(os.path.basename(a.scene))[0]
rows = []
for spec in a.configs:
    name, _, ps = spec.partition(":")
    params = [x for p in ps.split(",") if p for x in ("--param", p)]
    rel, means = [], []
    for seed in range(1, a.seeds + 1):
        tag = "%s-%s-%dspp-%d" % (base, spec.replace(":", "_").replace("=", "_").replace(",", "_"), a.spp, seed)
        out = os.path.join(a.outdir, tag + ".exr")
        if not (a.reuse and os.path.exists(out)):
            subprocess.run([os.path.join(BIN, "gradus"), a.scene, "--integrator", name, *params,
                            "--spp", str(a.spp), "--seed", str(seed), *a.args.split(), "--quiet",
                            "--outfile", out], check=True)
        d = json.loads(subprocess.run([os.path.join(BIN, "imgtool"), "diff", out, a.ref, "--json"],
                                      check=True, capture_output=True, text=True).stdout)
        rel.append(d["relmse"])
        means.append(d["mean_image"])
    rows.append((spec, sum(rel) / len(rel), rel, sum(means) / len(means) / ref_mean - 1))
print("%s, %d spp, seeds 1..%d, reference %s (mean %.4g)\n" % (a.scene, a.spp, a.seeds, a.ref, ref_mean))
print("| configuration | relMSE (mean) | per seed | %s / this | mean vs ref |" % rows[0][0])
print("|---|---|---|---|---|")
for spec, m, rel, dm in rows:
    print("| %s | %.4g | %s | %.2f | %+.2f%% |" % (spec, m, " ".join("%.3g" % r for r in rel), rows[0][1] / m, 100 * dm))
