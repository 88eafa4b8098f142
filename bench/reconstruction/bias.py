#!/usr/bin/python3
"""Energy bias of the gradient-domain reconstructions against references.

Usage: bench/reconstruction/bias.py RUN_DIR [--bin-dir DIR] [--shared-dir DIR]

RUN_DIR is a `bench/run` output whose renders/<scene>/<integrator>-t<T>-s<seed>.exr
hold a gradient integrator's layers (primal, dx, dy, reconstructed_l1,
reconstructed_l2, reconstructed_hybrid). For every render it prints, per
reconstruction, against <shared>/references/<scene>/ref.exr:
  mean      image mean / reference mean - 1 (the energy lost or gained)
  tile16    RMS over 16x16-pixel tiles of (tile mean / reference tile mean - 1),
            tiles whose reference mean is below 1% of the image mean left out
  relMSE    mean of (X - R)^2 / (R^2 + 0.001), the papers' metric, without the
            0.01% worst pixels (the G-BDPT paper's trimming)
Besides the layers in the file it evaluates, from the file's own L1 and L2
layers and its primal, the hybrids I_L1 + G_s * (S - I_L1) for S = the L2
solution or the primal and s = 2, 4, 8, 16 pixels ("h-l2-s4", "h-p-s8", ...),
and the weighted reconstruction (through the reconstruct tool).
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.dont_write_bytecode = True
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "bench"))
from harness.images import read_pfm  # noqa: E402


def layer(imgtool, exr, name, tmp):
    out = os.path.join(tmp, name.replace("/", "_") + ".pfm")
    args = [imgtool, "convert", exr, out] + (["--layer", name] if name else [])
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    return read_pfm(out).astype(np.float64)


def gauss_blur(img, sigma):
    """Separable Gaussian, half-sample symmetric borders (as CombineScales)."""
    r = max(1, int(np.ceil(3 * sigma)))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = img
    for axis in (0, 1):
        n = out.shape[axis]
        idx = np.arange(-r, n + r)
        p = 2 * n
        idx = np.mod(idx, p)
        idx = np.where(idx < n, idx, p - 1 - idx)
        padded = np.take(out, idx, axis=axis)
        acc = np.zeros_like(out)
        for j in range(2 * r + 1):
            acc += k[j] * np.take(padded, np.arange(j, j + n), axis=axis)
        out = acc
    return out


def metrics(x, ref):
    lx, lr = x.mean(axis=2), ref.mean(axis=2)
    mean = lx.mean() / lr.mean() - 1
    H, W = lr.shape
    t = 16
    tx = lx[: H // t * t, : W // t * t].reshape(H // t, t, W // t, t).mean(axis=(1, 3))
    tr = lr[: H // t * t, : W // t * t].reshape(H // t, t, W // t, t).mean(axis=(1, 3))
    keep = tr > 0.01 * lr.mean()
    tile = np.sqrt(np.mean((tx[keep] / tr[keep] - 1) ** 2))
    e = np.sort(((x - ref) ** 2 / (ref ** 2 + 0.001)).mean(axis=2).ravel())
    rel = e[: len(e) - int(len(e) * 1e-4)].mean()
    return mean, tile, rel


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir")
    ap.add_argument("--bin-dir", default=os.path.join(ROOT, "build", "bin"))
    ap.add_argument("--shared-dir", default=os.path.join(ROOT, "..", "shared"))
    ap.add_argument("--no-weighted", action="store_true")
    ap.add_argument("--summary", help="also write a Markdown table of the means over seeds to this file")
    a = ap.parse_args()
    imgtool = os.path.join(a.bin_dir, "imgtool")
    reconstruct = os.path.join(a.bin_dir, "reconstruct")
    rows = []
    for exr in sorted(glob.glob(os.path.join(a.run_dir, "renders", "*", "*.exr"))):
        scene = os.path.basename(os.path.dirname(exr))
        ref_exr = os.path.join(a.shared_dir, "references", scene, "ref.exr")
        if not os.path.exists(ref_exr):
            continue
        with tempfile.TemporaryDirectory() as tmp:
            ref = layer(imgtool, ref_exr, "", tmp)
            try:
                l1 = layer(imgtool, exr, "reconstructed_l1", tmp)
            except subprocess.CalledProcessError:
                continue  # not a gradient render
            l2 = layer(imgtool, exr, "reconstructed_l2", tmp)
            primal = layer(imgtool, exr, "primal", tmp)
            cands = {"primal": primal, "l1": l1, "l2": l2}
            for s in (2, 4, 8, 16):
                cands["h-l2-s%d" % s] = l1 + gauss_blur(l2 - l1, s)
                cands["h-p-s%d" % s] = l1 + gauss_blur(primal - l1, s)
            if not a.no_weighted:
                w = os.path.join(tmp, "w.exr")
                subprocess.run([reconstruct, exr, "--outfile", w, "--norm", "weighted", "--no-png"], check=True,
                               stdout=subprocess.DEVNULL)
                cands["weighted"] = layer(imgtool, w, "", tmp)
            name = os.path.basename(exr)[:-4]
            for k, v in cands.items():
                m, t, r = metrics(v, ref)
                rows.append((scene, name, k, m, t, r))
                print("%-12s %-16s %-9s mean %+7.2f%%  tile16 %6.2f%%  relMSE %.4g" % (scene, name, k, 100 * m,
                                                                                       100 * t, r), flush=True)
    if a.summary:
        write_summary(rows, a.summary)
    return 0


def write_summary(rows, path):
    """Mean over seeds per (scene, integrator, time, reconstruction)."""
    groups = {}
    for scene, name, k, m, t, r in rows:
        integ, tpart = name.split("-t")[0], name.split("-t")[1].split("-s")[0]
        groups.setdefault((scene, integ, int(tpart)), {}).setdefault(k, []).append((m, t, r))
    order = ["primal", "l1", "l2", "weighted", "h-p-s4", "h-p-s8", "h-p-s16", "h-l2-s8"]
    with open(path, "w") as f:
        f.write("| scene | integrator | s | " + " | ".join(order) + " |\n")
        f.write("|" + "---|" * (3 + len(order)) + "\n")
        for (scene, integ, t), ks in sorted(groups.items()):
            cells = []
            for k in order:
                v = ks.get(k)
                if not v:
                    cells.append("-")
                    continue
                m = np.mean([x[0] for x in v]) * 100
                tile = np.mean([x[1] for x in v]) * 100
                r = np.mean([x[2] for x in v])
                cells.append("%+.1f%% / %.1f%% / %.3g" % (m, tile, r))
            f.write("| %s | %s | %d | %s |\n" % (scene, integ, t, " | ".join(cells)))


if __name__ == "__main__":
    sys.exit(main())
