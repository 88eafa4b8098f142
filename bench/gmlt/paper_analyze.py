#!/usr/bin/python3
"""Scores the runs of bench/gmlt/paper_bench.sh (issue 58, item 4).

    python3 bench/gmlt/paper_analyze.py OUTDIR [--csv FILE]

Per run: relMSE against the scene's reference, (X-R)^2 / (R^2 + 0.001) averaged over pixels and
channels (imgtool's definition), untrimmed and with the 50 worst pixels discarded; the image mean
against the reference's; mutations (spp) per pixel and cpu seconds from the EXR's metadata.
Per scene and integrator over the seeds:
  - relMSE mean over seeds, and net of the reference's own estimated relMSE (ref.noise);
  - the seed-pair variance, mean over pairs of (A - B)^2 / (2 (R^2 + 0.001)): the variance part of
    relMSE without the reference's noise (E (A - B)^2 = Var A + Var B for independent seeds; the
    reference only normalises). A biased estimator's bias is not in it: compare with the relMSE.
References: door-560 and torus-560 in bench/gmlt/paper/refs/<scene>/ (bench/run --make-reference);
veach-ajar-640 against the shared pbrt-v3 reference (320 x 180, triangle filter) after a 2 x 2 box
average of the render: a filter mismatch that puts the same floor under every integrator.
"""
import argparse
import glob
import json
import os
import re
import subprocess
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EPS = 0.001
DISCARD = 50
LAYERS = {"gmlt": ["", "reconstructed_l1"], "gbdpt": ["", "reconstructed_l1"]}


def refpath(scene):
    if scene.startswith("veach-ajar"):
        d = os.path.join(ROOT, "..", "shared", "references", "veach-ajar")
    else:
        d = os.path.join(ROOT, "bench", "gmlt", "paper", "refs", scene)
    noise = os.path.join(d, "ref.noise")
    return os.path.join(d, "ref.exr"), float(open(noise).read().split()[0]) if os.path.exists(noise) else 0.0


def read(path, layer, imgtool):
    with tempfile.TemporaryDirectory() as tmp:
        pfm = os.path.join(tmp, "x.pfm")
        cmd = [imgtool, "convert", path, pfm] + (["--layer", layer] if layer else [])
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(pfm, "rb") as f:
            assert f.readline().strip() == b"PF"
            w, h = map(int, f.readline().split())
            scale = float(f.readline())
            data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(h, w, 3)[::-1].astype(np.float64)


def meta(path, imgtool):
    out = subprocess.run([imgtool, "info", path, "--json"], check=True, capture_output=True, text=True).stdout
    return json.loads(out)["metadata"]


def box2(img, ref):
    if img.shape == ref.shape:
        return img
    h, w = ref.shape[:2]
    return img.reshape(h, img.shape[0] // h, w, img.shape[1] // w, 3).mean(axis=(1, 3))


def relmse(x, r):
    e = ((x - r) ** 2 / (r ** 2 + EPS)).mean(axis=2).ravel()
    trimmed = np.sort(e)[:-DISCARD] if e.size > DISCARD else e
    return e.mean(), trimmed.mean()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("--csv")
    ap.add_argument("--imgtool", default=os.path.join(ROOT, "build", "bin", "imgtool"))
    args = ap.parse_args()
    runs = {}
    for exr in sorted(glob.glob(os.path.join(args.outdir, "*.exr"))):
        m = re.match(r"(.+)-(\w+)-s(\d+)\.exr$", os.path.basename(exr))
        if m:
            runs.setdefault((m.group(1), m.group(2)), []).append((int(m.group(3)), exr))
    rows = []
    refs = {}
    for (scene, integ), seeds in sorted(runs.items()):
        if scene not in refs:
            rp, noise = refpath(scene)
            refs[scene] = (read(rp, "", args.imgtool), noise)
        ref, noise = refs[scene]
        for layer in LAYERS.get(integ, [""]):
            imgs, per = [], []
            for seed, exr in sorted(seeds):
                x = box2(read(exr, layer, args.imgtool), ref)
                md = meta(exr, args.imgtool)
                raw, trim = relmse(x, ref)
                per.append(dict(seed=seed, relmse=raw, trimmed=trim, mean=x.mean() / ref.mean() - 1,
                                spp=md.get("spp"), cpu=md.get("cpu_seconds")))
                imgs.append(x)
            pairs = [(a, b) for i, a in enumerate(imgs) for b in imgs[i + 1:]]
            pvar = np.mean([((a - b) ** 2 / (2 * (ref ** 2 + EPS))).mean() for a, b in pairs]) if pairs else float("nan")
            mean_rel = np.mean([p["relmse"] for p in per])
            row = dict(scene=scene, integrator=integ + ("/" + layer if layer else ""), seeds=len(per),
                       relmse=mean_rel, net=mean_rel - noise, ref_noise=noise,
                       trimmed=np.mean([p["trimmed"] for p in per]), pair_variance=pvar,
                       spp=[p["spp"] for p in per], cpu=[round(p["cpu"] or 0) for p in per],
                       means=["%+.2f%%" % (100 * p["mean"]) for p in per],
                       per_seed=["%.4g" % p["relmse"] for p in per])
            rows.append(row)
            print("%-15s %-22s n=%d relMSE %.4g (net %.4g, ref %.3g) trimmed %.4g pair-var %.4g spp %s cpu %s means %s per-seed %s"
                  % (scene, row["integrator"], row["seeds"], row["relmse"], row["net"], noise, row["trimmed"],
                     pvar, row["spp"], row["cpu"], " ".join(row["means"]), " ".join(row["per_seed"])))
    # Ratios of the goals: pmlt / gmlt (>= 2.5), gbdpt / pmlt and gbdpt / gmlt (>= 1.5),
    # by the raw relMSE, net of the reference and by the seed-pair variance; and per mutation
    # (relMSE x mutations per pixel, lower is better) with the mutation cost ratio.
    by = {(r["scene"], r["integrator"]): r for r in rows}
    for scene in sorted({r["scene"] for r in rows}):
        def ratio(a, b, key):
            ra, rb = by.get((scene, a)), by.get((scene, b))
            return ra[key] / rb[key] if ra and rb and rb[key] > 0 else float("nan")
        line = [scene]
        for a, b in (("pmlt", "gmlt"), ("gbdpt", "pmlt"), ("gbdpt", "gmlt")):
            line.append("%s/%s raw %.2f net %.2f pair-var %.2f" % (a, b, ratio(a, b, "relmse"), ratio(a, b, "net"),
                                                                   ratio(a, b, "pair_variance")))
        p, g = by.get((scene, "pmlt")), by.get((scene, "gmlt"))
        if p and g:
            mp, mg = np.mean(p["spp"]), np.mean(g["spp"])
            line.append("mutations pmlt/gmlt %.2f; relMSE x mpp (net) pmlt %.3g gmlt %.3g (%.2fx)"
                        % (mp / mg, p["net"] * mp, g["net"] * mg, p["net"] * mp / (g["net"] * mg)))
        print("; ".join(line))
    if args.csv:
        import csv
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            for r in rows:
                w.writerow({k: (" ".join(map(str, v)) if isinstance(v, list) else v) for k, v in r.items()})


if __name__ == "__main__":
    main()
