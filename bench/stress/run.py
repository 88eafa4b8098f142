#!/usr/bin/env python3
"""Numerical stress suite: every registered integrator on generated stress scenes.

    bench/stress/run [--out DIR] [--integrators a,b] [--scenes pattern,...] [--quick]

The scenes (scenes.py) are written to the results directory (default: a new temp
dir; --out DIR to choose) and rendered one by one with `gradus`, each under a
subprocess timeout (a hang is reported as TIMEOUT and killed, never waited for).
For every (scene, integrator) cell the suite records the exit status, the wall
time, the NaN/Inf samples the film guard discarded (`nonfinite_discarded`), the
values clamped to +-FLT_MAX, the NaN/Inf values in every output layer (imgtool
info), and, where the scene has an expected value, the energy ratio and its z.
The table is printed and written as results.md / results.csv / results.json.

The check of a cell depends on what its integrator estimates (scenes.check_for):
pbrt-v3's classic integrators (whitted, directlighting: direct light and specular
recursion only; ambientocclusion: occlusion, no radiance) have their own
expectations per scene, documented in README.md. Integrators without a maxdepth
parameter (gradus --describe) get none in the scene file.

A cell FAILS on: non-zero exit, timeout, a NaN/Inf value in any layer, or an
energy check beyond noise. Discarded or clamped samples are reported, not failed.
A scene's known limitations (scenes.Scene limits: integrator spec -> reason, see
README.md) turn that integrator's energy verdicts there into notes ("known" in the
table); crash, timeout and NaN/Inf still fail.
The exit status is 1 if any cell fails.

Energy checks, decided per checked layer (the main R,G,B; for gradient
integrators also `primal` and `reconstructed_l2`):
  * per pixel, the statistic v is the channel mean of pixel / expectation
    (Exact, Bound, Map; target 1) or of pixel - reference pixel (Same, Sum;
    target 0, the reference being the other scenes' renders of the same
    integrator);
  * SE, the standard error of the mean of v over the checked pixels, comes from
    the per-pixel spread of the same statistic on the noise layer (the layer
    itself, or `primal` for gradient integrators, whose reconstructions are
    smooth but carry the primal's noise in their mean): the larger of
    sd(pixels)/sqrt(n) and sd(8x8 block means)/sqrt(blocks) (the block form
    covers correlation between nearby pixels, e.g. light-tracing splats), with
    a floor of 1e-5 of the reference level in quadrature for float32 output and
    the float reconstruction solver; for Bound scenes, whose expectation varies
    over the image, from the difference to an independent second render
    ("~twin") divided by sqrt(2);
  * z = (mean(v) - target) / SE. "Energy gain" is z > 5 (5 sigma: about 3e-7
    false alarms per side and check under the normal approximation); Exact, Map, Same and
    Sum also fail on "loss", z < -5; Bound fails only on gain. Zero fails on any
    non-zero pixel.
The checks always use the same seeds (--seed), so a run is reproducible.
"""

import argparse
import array
import csv
import fnmatch
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import zlib
from concurrent.futures import ThreadPoolExecutor

sys.dont_write_bytecode = True  # leave no __pycache__ in the source tree
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import scenes as stress_scenes  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(HERE))
Z_FAIL = 5.0
REL_FLOOR = 1e-5
BLOCK = 8
GRADIENT_LAYERS = ("primal", "reconstructed_l2")


# ---------------------------------------------------------------- images

def read_pfm(path):
    """(width, height, rows) with rows[y][x] = (r, g, b), top row first."""
    with open(path, "rb") as f:
        data = f.read()
    parts = []
    pos = 0
    while len(parts) < 4:  # magic, width, height, scale, each followed by whitespace
        while data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        parts.append(data[start:pos].decode())
    pos += 1
    kind, w, h, scale = parts[0], int(parts[1]), int(parts[2]), float(parts[3])
    nc = 3 if kind == "PF" else 1
    vals = array.array("f")
    vals.frombytes(data[pos:pos + w * h * nc * 4])
    if (scale < 0) != (sys.byteorder == "little"):
        vals.byteswap()
    rows = []
    for y in range(h):
        src = (h - 1 - y) * w * nc  # PFM rows run bottom to top
        row = []
        for x in range(w):
            p = vals[src + x * nc: src + x * nc + nc]
            row.append(tuple(p) if nc == 3 else (p[0],) * 3)
        rows.append(row)
    return w, h, rows


class Render:
    """One finished render: metadata, per-layer NaN/Inf counts and cached layers."""

    def __init__(self, exr, imgtool, tmpdir):
        self.exr, self.imgtool, self.tmpdir = exr, imgtool, tmpdir
        out = subprocess.run([imgtool, "info", exr, "--json"], capture_output=True, text=True,
                             timeout=120)
        if out.returncode != 0:
            raise RuntimeError("imgtool info: " + out.stderr.strip())
        info = json.loads(out.stdout)
        self.meta = info.get("metadata", {})
        self.layers = {l["name"]: l["nan"] + l["inf"] for l in info["layers"]}
        self._cache = {}

    def layer(self, name):
        """rows of layer `name` ("" = the main R,G,B)."""
        if name not in self._cache:
            pfm = os.path.join(self.tmpdir, "layer-%d.pfm" % os.getpid())
            cmd = [self.imgtool, "convert", self.exr, pfm] + (["--layer", name] if name else [])
            out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
            if out.returncode != 0:
                raise RuntimeError("imgtool convert: " + out.stderr.strip())
            self._cache[name] = read_pfm(pfm)[2]
            os.remove(pfm)
        return self._cache[name]


# ---------------------------------------------------------------- statistics

def finite(v):
    return not (math.isnan(v) or math.isinf(v))


def mean_se(stat, w, h):
    """Mean of the checked pixels of stat[y][x] (None = not checked) and its standard
    error: max(pixel spread / sqrt(n), 8x8-block-mean spread / sqrt(blocks))."""
    vals = [v for row in stat for v in row if v is not None and finite(v)]
    n = len(vals)
    if n == 0:
        return float("nan"), float("nan")
    m = sum(vals) / n
    se_pix = math.sqrt(sum((v - m) ** 2 for v in vals) / max(1, n - 1) / n) if n > 1 else 0.0
    blocks = []
    for by in range(0, h, BLOCK):
        for bx in range(0, w, BLOCK):
            b = [stat[y][x] for y in range(by, min(h, by + BLOCK)) for x in range(bx, min(w, bx + BLOCK))
                 if stat[y][x] is not None and finite(stat[y][x])]
            if len(b) * 2 >= min(BLOCK, h - by) * min(BLOCK, w - bx):  # at least half checked
                blocks.append(sum(b) / len(b))
    se_blk = 0.0
    if len(blocks) >= 4:
        bm = sum(blocks) / len(blocks)
        se_blk = math.sqrt(sum((b - bm) ** 2 for b in blocks) / (len(blocks) - 1) / len(blocks))
    return m, max(se_pix, se_blk)


def image_mean(rows):
    vals = [sum(p) / 3 for row in rows for p in row if all(finite(c) for c in p)]
    return sum(vals) / len(vals) if vals else float("nan")


def check_layer(check, rend, layer, noise_layer, refs, twin):
    """Energy check of one layer. Returns dict(ratio, z, verdict, detail)."""
    S = stress_scenes
    img = rend.layer(layer)
    h, w = len(img), len(img[0])
    if isinstance(check, S.Zero):
        peak = max(abs(c) for row in img for p in row for c in p)
        return dict(ratio=None, z=None, peak=peak, verdict="ok" if peak == 0 else "gain",
                    detail="max abs(pixel) %.3g" % peak)
    if isinstance(check, (S.Exact, S.Bound, S.Map)):
        def stat(im):
            out = []
            for y in range(h):
                row = []
                for x in range(w):
                    e = check.fn(x, y, w, h) if isinstance(check, S.Map) else check.value
                    row.append(None if e is None else sum(im[y][x][c] / e[c] for c in range(3)) / 3)
                out.append(row)
            return out
        target, level = 1.0, 1.0
        m, _ = mean_se(stat(img), w, h)
        ratio = m
        if isinstance(check, S.Bound):
            # The expectation varies over the image: the noise is the spread of the
            # difference to an independent render (twin), scaled to one render.
            if twin is None:
                return dict(ratio=ratio, z=None, verdict="n/a", detail="twin render missing")
            a, b = stat(rend.layer(noise_layer)), stat(twin.layer(noise_layer))
            noise = [[None if a[y][x] is None else (a[y][x] - b[y][x]) / math.sqrt(2) for x in range(w)]
                     for y in range(h)]
        else:
            noise = stat(rend.layer(noise_layer))
    else:  # Same / Sum: difference to the other scenes' renders with the same integrator
        if any(r is None for r in refs):
            return dict(ratio=None, z=None, verdict="n/a", detail="reference render missing")

        def diff(name, im):
            rs = [r.layer(name) for r in refs]
            if any(len(r) != h or len(r[0]) != w for r in rs):
                raise RuntimeError("reference size differs")
            return [[sum(im[y][x][c] - sum(r[y][x][c] for r in rs) for c in range(3)) / 3
                     for x in range(w)] for y in range(h)], rs
        d, rs_img = diff(layer, img)
        noise, _ = diff(noise_layer, rend.layer(noise_layer))
        m, _ = mean_se(d, w, h)
        ref_mean = sum(image_mean(r) for r in rs_img)
        target, level = 0.0, abs(ref_mean)
        ratio = (ref_mean + m) / ref_mean if ref_mean != 0 else float("nan")
    _, se = mean_se(noise, w, h)
    se = math.sqrt(se ** 2 + (REL_FLOOR * level) ** 2)
    z = (m - target) / se if se > 0 else (0.0 if m == target else math.copysign(math.inf, m - target))
    if not finite(m):
        verdict = "n/a"
    elif z > Z_FAIL:
        verdict = "gain"
    elif z < -Z_FAIL and not isinstance(check, S.Bound):
        verdict = "loss"
    else:
        verdict = "ok"
    return dict(ratio=ratio, z=z, verdict=verdict, detail="ratio %.6g z %.2f" % (ratio, z))


# ---------------------------------------------------------------- running

def list_integrators(gradus):
    out = subprocess.run([gradus, "--list-integrators"], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        sys.exit("stress: %s --list-integrators failed: %s" % (gradus, out.stderr.strip()))
    return [l.split()[0] for l in out.stdout.splitlines() if l.strip()]


def git_commit():
    try:
        out = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10)
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return out.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


TWIN = "~twin"  # suffix of the independent second render of Bound scenes


def check_of(scene, integ):
    """The scene's check for integrator spec `integ` (NAME or NAME[P=V;...])."""
    return scene.check_for(parse_spec(integ)[0])


def has_maxdepth(gradus, name):
    """Whether integrator `name` takes a maxdepth parameter (gradus --describe)."""
    out = subprocess.run([gradus, "--describe", name], capture_output=True, text=True, timeout=60)
    if out.returncode != 0:
        sys.exit("stress: %s --describe %s failed: %s" % (gradus, name, out.stderr.strip()))
    return any(l.split()[:1] == ["maxdepth"] for l in out.stdout.splitlines())


def seed_of(base, name):
    """Independent seeds per scene (and for a twin), fixed for reproducibility."""
    return base + zlib.crc32(name.encode()) % 100000


def parse_spec(spec):
    """'mlt[largestepmis=true;chains=10]' -> ('mlt', ['largestepmis=true', 'chains=10'])."""
    m = re.fullmatch(r"([A-Za-z0-9_]+)(?:\[(.*)\])?", spec)
    if not m:
        sys.exit("stress: bad integrator %r (NAME or NAME[P=V;...])" % spec)
    params = [p for p in (m.group(2) or "").split(";") if p]
    for p in params:
        if "=" not in p:
            sys.exit("stress: bad parameter %r in %r (P=V)" % (p, spec))
    return m.group(1), params


def render_cell(args, gradus, scene, integ, outdir, twin=False, maxdepth=True):
    name = scene.name + (TWIN if twin else "")
    base = os.path.join(outdir, "%s__%s" % (name, re.sub(r"[^A-Za-z0-9_.=-]", "_", integ)))
    pbrt, exr = base + ".pbrt", base + ".exr"
    spp = args.spp
    integ_name, params = parse_spec(integ)
    with open(pbrt, "w") as f:
        f.write(scene.text(integ_name, args.size, spp, maxdepth))
    cmd = [gradus, pbrt, "--outfile", exr, "--spp", str(spp), "--seed", str(seed_of(args.seed, name)),
           "--nthreads", str(args.nthreads), "--quiet"]
    for p in params:
        cmd += ["--param", p]
    t0 = time.monotonic()
    cell = dict(scene=name, integrator=integ, pbrt=pbrt, exr=exr, spp=spp)
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        rc = proc.returncode
        cell["exit"] = rc if rc >= 0 else signal.Signals(-rc).name  # killed by a signal: its name
        err = proc.stderr.strip().splitlines()[-1] if rc != 0 and proc.stderr.strip() else ""
        cell["error"] = err if len(err) <= 200 else err[:100] + " ... " + err[-95:]
    except subprocess.TimeoutExpired:  # subprocess.run has killed it
        cell["exit"] = "timeout"
        cell["error"] = "no result after %g s" % args.timeout
    cell["seconds"] = time.monotonic() - t0
    return cell


def evaluate(cells, scenes_by_name, imgtool, tmpdir):
    renders = {}
    for key, c in cells.items():
        if c["exit"] == 0 and os.path.exists(c["exr"]):
            try:
                renders[key] = Render(c["exr"], imgtool, tmpdir)
            except (RuntimeError, subprocess.SubprocessError, ValueError) as e:
                c["exit"] = "unreadable"
                c["error"] = str(e)
    for (sname, integ), c in cells.items():
        if sname.endswith(TWIN):
            continue
        fails, notes = [], []
        check = check_of(scenes_by_name[sname], integ) if sname in scenes_by_name else None
        if isinstance(check, stress_scenes.Refused):
            # Hostile input: a clear located error is the right answer, a render or a crash is not.
            err = c.get("error", "")
            if not (c["exit"] == 1 and re.search(r"\.pbrt:\d+:\d+: ", err) and check.reason in err):
                fails.append("expected a located error mentioning %r, got exit %s: %s" % (check.reason, c["exit"], err))
            c["fails"], c["notes"], c["energy"] = fails, notes, {}
            continue
        if c["exit"] == "timeout":
            fails.append("TIMEOUT after %.0f s" % c["seconds"])
        elif c["exit"] != 0:
            fails.append("exit %s: %s" % (c["exit"], c.get("error", "")))
        r = renders.get((sname, integ))
        c["energy"] = {}
        if r is None:
            c["fails"], c["notes"] = fails, notes
            continue
        c["discarded"] = int(r.meta.get("nonfinite_discarded", "0"))
        c["clamped"] = int(r.meta.get("output_values_clamped", "0"))
        c["render_seconds"] = float(r.meta.get("render_seconds", "nan"))
        c["nonfinite_layers"] = {k: v for k, v in r.layers.items() if v}
        if c["nonfinite_layers"]:
            fails.append("NaN/Inf in " + ", ".join("%s:%d" % (k or "main", v)
                                                   for k, v in sorted(c["nonfinite_layers"].items())))
        if c["discarded"]:
            notes.append("%d non-finite samples discarded" % c["discarded"])
        if c["clamped"]:
            notes.append("%d values clamped" % c["clamped"])
        if check is not None:
            layers = [""] + [l for l in GRADIENT_LAYERS if l in r.layers]
            noise_layer = "primal" if "primal" in r.layers else ""
            others = check.others if isinstance(check, stress_scenes.Sum) else (
                [check.other] if isinstance(check, stress_scenes.Same) else [])
            refs = [renders.get((o, integ)) for o in others]
            twin = renders.get((sname + TWIN, integ))
            limit = scenes_by_name[sname].limits.get(integ)
            for layer in layers:
                try:
                    e = check_layer(check, r, layer, noise_layer, refs, twin)
                except (RuntimeError, subprocess.SubprocessError, ValueError, ZeroDivisionError) as ex:
                    e = dict(ratio=None, z=None, verdict="n/a", detail="check failed: %s" % ex)
                c["energy"][layer or "main"] = e
                if e["verdict"] in ("gain", "loss") and limit:
                    notes.append("known limitation, energy %s (%s) not failed: %s; %s"
                                 % (e["verdict"], layer or "main", e["detail"], limit))
                elif e["verdict"] in ("gain", "loss"):
                    fails.append("energy %s (%s): %s" % (e["verdict"], layer or "main", e["detail"]))
                elif e["verdict"] == "n/a":
                    notes.append("energy check n/a (%s): %s" % (layer or "main", e["detail"]))
        c["fails"], c["notes"] = fails, notes


# ---------------------------------------------------------------- tables

def energy_text(c):
    parts = []
    for layer, e in c.get("energy", {}).items():
        if e.get("ratio") is not None:
            parts.append("%s %.5g (z %+.1f)" % (layer, e["ratio"], e["z"]))
        elif "peak" in e:
            parts.append("%s max %.3g" % (layer, e["peak"]))
        else:
            parts.append("%s n/a" % layer)
    return "; ".join(parts)


def status_text(c):
    if c["fails"]:
        return "FAIL"
    return "known" if any(n.startswith("known limitation") for n in c["notes"]) else "ok"


def short_reasons(c):
    """'timeout', 'exit 1', 'NaN/Inf', 'gain main', ... for the matrix."""
    out = []
    for f in c["fails"]:
        if f.startswith("energy "):
            verdict, layer = f.split()[1], f.split("(")[1].split(")")[0]
            out.append("%s %s" % (verdict, {"reconstructed_l2": "l2"}.get(layer, layer)))
        else:
            out.append(f.split(":")[0].split(" after")[0].split(" in ")[0].replace("TIMEOUT", "timeout"))
    return ", ".join(out)


COLUMNS = ["scene", "integrator", "status", "exit", "seconds", "spp", "discarded", "clamped",
           "nan_inf_values", "expected", "energy", "failures", "notes"]


def row_of(c, scene):
    check = check_of(scene, c["integrator"])
    return dict(scene=c["scene"], integrator=c["integrator"], status=status_text(c), exit=c["exit"],
                seconds="%.2f" % c["seconds"], spp=c["spp"], discarded=c.get("discarded", ""),
                clamped=c.get("clamped", ""),
                nan_inf_values=(", ".join("%s:%d" % (k or "main", v) for k, v in sorted(c["nonfinite_layers"].items()))
                                or "0") if "nonfinite_layers" in c else "",
                expected=check.describe() if check else "", energy=energy_text(c),
                failures="; ".join(c["fails"]), notes="; ".join(c["notes"]), short=short_reasons(c))


def markdown(rows, integrators, scene_list, header):
    md = [header, ""]
    md.append("| scene | " + " | ".join(integrators) + " |")
    md.append("|---|" + "---|" * len(integrators))
    by = {(r["scene"], r["integrator"]): r for r in rows}
    for s in scene_list:
        cells = []
        for i in integrators:
            r = by.get((s.name, i))
            cells.append("" if r is None else ("**FAIL** (%s)" % r["short"] if r["status"] == "FAIL" else r["status"]))
        md.append("| %s | %s |" % (s.name, " | ".join(cells)))
    md += ["", "| scene | integrator | status | exit | s | NaN/Inf discarded | NaN/Inf values | expected | energy ratio (z) | failures / notes |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        fn = "; ".join(x for x in (r["failures"], r["notes"]) if x).replace("|", "\\|")
        md.append("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r["scene"], r["integrator"], "**FAIL**" if r["status"] == "FAIL" else r["status"], r["exit"], r["seconds"],
            r["discarded"], r["nan_inf_values"], r["expected"], r["energy"], fn))
    return "\n".join(md) + "\n"


def print_table(rows):
    line = "%-18s %-8s %-4s %-7s %6s %5s  %s"
    print(line % ("scene", "integr.", "", "exit", "s", "disc", "NaN/Inf | energy ratio (z) | failures"))
    for r in rows:
        extra = " | ".join(x for x in (r["nan_inf_values"], r["energy"], r["failures"]) if x)
        print(line % (r["scene"][:18], r["integrator"][:8], r["status"], str(r["exit"])[:7], r["seconds"],
                      r["discarded"], extra))


# ---------------------------------------------------------------- main

def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="See bench/stress/README.md.")
    p.add_argument("--bin", default=os.environ.get("GRADUS_BIN", os.path.join(ROOT, "build", "bin")),
                   help="folder with gradus and imgtool (default $GRADUS_BIN, else build/bin)")
    p.add_argument("--out", help="results folder (default: a new temp dir)")
    p.add_argument("--integrators", help="comma list of NAME or NAME[P=V;...] (integrator parameters; "
                   "default: every registered integrator)")
    p.add_argument("--scenes", help="comma list of names or fnmatch patterns (default: all)")
    p.add_argument("--size", type=int, default=32, help="film width in pixels (default 32)")
    p.add_argument("--spp", type=int, default=16, help="samples per pixel (default 16)")
    p.add_argument("--timeout", type=float, default=60, help="seconds per render (default 60)")
    p.add_argument("--nthreads", type=int, default=2, help="gradus --nthreads (default 2)")
    p.add_argument("--jobs", type=int, default=1, help="renders at a time (default 1)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    p.add_argument("--quick", action="store_true",
                   help="smallest configuration: 16 px, 4 spp, 30 s timeout (the ctest entry)")
    p.add_argument("--list", action="store_true", help="list the scenes and exit")
    args = p.parse_args(argv)
    if args.quick:
        args.size, args.spp, args.timeout = 16, 4, 30

    scene_list = stress_scenes.all_scenes()
    if args.list:
        for s in scene_list:
            print("%-20s %-28s %s" % (s.name, s.check.describe() if s.check else "-", s.about))
            for kind in ("direct", "occlusion"):
                if s.checks[kind] is not s.check:
                    print("%-20s %-28s %s" % ("", s.checks[kind].describe() if s.checks[kind] else "-",
                                              "(%s: %s)" % (kind, ", ".join(
                                                  n for n, k in stress_scenes.ESTIMATE_KIND.items() if k == kind))))
        return 0
    if args.scenes:
        pats = args.scenes.split(",")
        wanted = {s.name for s in scene_list if any(fnmatch.fnmatch(s.name, q) for q in pats)}
        # References of Same/Sum checks are rendered too.
        for s in scene_list:
            for check in s.checks.values() if s.name in wanted else ():
                if isinstance(check, stress_scenes.Same):
                    wanted.add(check.other)
                if isinstance(check, stress_scenes.Sum):
                    wanted.update(check.others)
        scene_list = [s for s in scene_list if s.name in wanted]
        if not scene_list:
            sys.exit("stress: no scene matches %s (see --list)" % args.scenes)
    gradus, imgtool = os.path.join(args.bin, "gradus"), os.path.join(args.bin, "imgtool")
    for exe in (gradus, imgtool):
        if not os.access(exe, os.X_OK):
            sys.exit("stress: %s not found (build first, or pass --bin)" % exe)
    registered = list_integrators(gradus)
    integrators = args.integrators.split(",") if args.integrators else registered
    unknown = [i for i in integrators if parse_spec(i)[0] not in registered]
    if unknown:
        sys.exit("stress: unknown integrator(s) %s (registered: %s)" % (",".join(unknown), ",".join(registered)))

    out = os.path.abspath(args.out) if args.out else tempfile.mkdtemp(prefix="gradus-stress-")
    renders = os.path.join(out, "renders")
    os.makedirs(renders, exist_ok=True)
    commit = git_commit()
    print("stress: %d scenes x %d integrators (%s), %d px, %d spp, timeout %g s; results in %s"
          % (len(scene_list), len(integrators), ",".join(integrators), args.size, args.spp, args.timeout, out),
          flush=True)
    maxdepth = {n: has_maxdepth(gradus, n) for n in {parse_spec(i)[0] for i in integrators}}
    jobs = [(s, i, False) for s in scene_list for i in integrators]
    jobs += [(s, i, True) for s in scene_list for i in integrators
             if isinstance(check_of(s, i), stress_scenes.Bound)]
    cells = {}
    t0 = time.monotonic()

    def work(job):
        s, i, twin = job
        c = render_cell(args, gradus, s, i, renders, twin, maxdepth[parse_spec(i)[0]])
        print("  %-26s %-8s exit %-7s %6.2f s" % (c["scene"], i, c["exit"], c["seconds"]), flush=True)
        return c

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for c in pool.map(work, jobs):
            cells[(c["scene"], c["integrator"])] = c
    by_name = {s.name: s for s in scene_list}
    evaluate(cells, by_name, imgtool, out)

    rows = [row_of(cells[(s.name, i)], s) for s in scene_list for i in integrators]
    nfail = sum(r["status"] == "FAIL" for r in rows)
    header = ("Stress suite, %s, commit %s: %d scenes x %d integrators, %d px wide, %d spp, timeout %g s, "
              "seed %d; %d of %d cells fail (%.0f s)."
              % (time.strftime("%Y-%m-%d"), commit, len(scene_list), len(integrators), args.size, args.spp,
                 args.timeout, args.seed, nfail, len(rows), time.monotonic() - t0))
    print()
    print_table(rows)
    print()
    print(header)
    with open(os.path.join(out, "results.csv"), "w", newline="") as f:
        wr = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        wr.writeheader()
        wr.writerows(rows)
    with open(os.path.join(out, "results.md"), "w") as f:
        f.write(markdown(rows, integrators, scene_list, header))
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(dict(commit=commit, date=time.strftime("%Y-%m-%d %H:%M:%S"), args=vars(args),
                       integrators=integrators, cells=[dict(c, energy=c.get("energy")) for c in cells.values()]),
                  f, indent=1, default=str)
    print("stress: wrote %s/results.{md,csv,json}" % out)
    return 1 if nfail else 0


if __name__ == "__main__":
    sys.exit(main())
