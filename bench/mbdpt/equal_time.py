#!/usr/bin/python3
"""Equal-time relMSE of M-BDPT against BDPT.

Renders each scene with `gradus --time T` for both integrators and several
seeds, measures relMSE against the scene's reference with `imgtool diff`, and
prints a table: mean relMSE per integrator (minus the reference's own noise
where known), samples per pixel reached, and the ratio BDPT / M-BDPT (> 1:
M-BDPT is better at equal time).

Scenes: door (scenes/door/door.pbrt, reference made by --make-door-ref, kept
outside git), veach-ajar and cornell-box (shared pbrt-v3 references).

  bench/mbdpt/equal_time.py --time 20 --seeds 2 --threads 2
  bench/mbdpt/equal_time.py --make-door-ref 1200      # long BDPT render -> /tmp/gradus-door-ref.exr
  bench/mbdpt/equal_time.py --mbdpt-params '"integer connections" 2'
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def scenes(args):
    shared = args.shared
    return {
        "door": (os.path.join(ROOT, "scenes/door/door.pbrt"), args.door_ref, 0.0),
        "veach-ajar": (os.path.join(shared, "references/veach-ajar/ref.pbrt"),
                       os.path.join(shared, "references/veach-ajar/ref.exr"),
                       read_noise(os.path.join(shared, "references/veach-ajar/ref.noise"))),
        "cornell-box": (os.path.join(shared, "references/cornell-box/ref.pbrt"),
                        os.path.join(shared, "references/cornell-box/ref.exr"),
                        read_noise(os.path.join(shared, "references/cornell-box/ref.noise"))),
    }


def read_noise(path):
    try:
        with open(path) as f:
            return float(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return 0.0


def scene_with_integrator(path, integrator, params, tmpdir):
    """Copy of the scene in tmpdir with the integrator line replaced (maxdepth kept) and
    relative asset file names made absolute."""
    d = os.path.dirname(os.path.abspath(path))
    with open(path) as f:
        text = f.read()

    def absolute(m):
        name = m.group(2)
        return m.group(1) + (name if os.path.isabs(name) else os.path.join(d, name)) + '"'
    text = re.sub(r'("string filename"\s*\[?\s*")([^"]*)"', absolute, text)
    out, done = [], False
    for line in text.split("\n"):
        if not done and line.lstrip().startswith("Integrator"):
            m = re.search(r'"integer maxdepth"\s*\[?\s*(\d+)', line)
            depth = '"integer maxdepth" [%s]' % m.group(1) if m else ""
            line = 'Integrator "%s" %s %s' % (integrator, depth, params)
            done = True
        out.append(line)
    fd, name = tempfile.mkstemp(suffix=".pbrt", dir=tmpdir)
    with os.fdopen(fd, "w") as f:
        f.write("\n".join(out))
    return name


def render(args, scene, integrator, params, seconds, seed, out, spp=None):
    tmp = scene_with_integrator(scene, integrator, params, os.path.dirname(os.path.abspath(out)))
    cmd = [args.gradus, tmp, "--outfile", out, "--seed", str(seed), "--nthreads", str(args.threads), "--quiet"]
    if seconds:
        cmd += ["--time", str(seconds)]
    if spp:
        cmd += ["--spp", str(spp)]
    try:
        subprocess.run(cmd, check=True)
    finally:
        os.unlink(tmp)


def image_meta(args, path):
    r = subprocess.run([args.imgtool, "info", path], capture_output=True, text=True)
    meta = {}
    for line in r.stdout.splitlines():
        if " = " in line:
            k, v = line.split(" = ", 1)
            meta[k.strip()] = v.strip()
    return meta


def relmse(args, image, ref):
    r = subprocess.run([args.imgtool, "diff", image, ref, "--json"], capture_output=True, text=True, check=True)
    return json.loads(r.stdout)["relmse"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gradus", default=os.path.join(ROOT, "build/bin/gradus"))
    ap.add_argument("--imgtool", default=os.path.join(ROOT, "build/bin/imgtool"))
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"))
    ap.add_argument("--door-ref", default="/tmp/gradus-door-ref.exr")
    ap.add_argument("--make-door-ref", type=float, default=0, metavar="SECONDS",
                    help="render the door reference with BDPT for this many seconds and exit")
    ap.add_argument("--scenes", default="door,veach-ajar,cornell-box")
    ap.add_argument("--time", type=float, default=20)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--mbdpt-params", default="")
    ap.add_argument("--out", default=None, help="directory for the renders (default: a temp dir)")
    args = ap.parse_args()
    sc = scenes(args)
    if args.make_door_ref:
        render(args, sc["door"][0], "bdpt", "", args.make_door_ref, 987654, args.door_ref)
        print("wrote", args.door_ref)
        return 0
    out = args.out or tempfile.mkdtemp(prefix="gradus-mbdpt-bench-")
    os.makedirs(out, exist_ok=True)
    print("renders in", out)
    print("%-12s %-7s %6s %6s %12s %12s" % ("scene", "integr.", "time", "spp", "relMSE", "relMSE-noise"))
    rows = []
    for name in args.scenes.split(","):
        scene, ref, noise = sc[name]
        if not os.path.exists(ref):
            print("%s: no reference %s (make it with --make-door-ref)" % (name, ref), file=sys.stderr)
            continue
        res = {}
        for integ, params in (("bdpt", ""), ("mbdpt", args.mbdpt_params)):
            errs, spps, secs = [], [], []
            for s in range(args.seeds):
                img = os.path.join(out, "%s_%s_%d.exr" % (name, integ, s))
                render(args, scene, integ, params, args.time, 100 + s, img)
                errs.append(relmse(args, img, ref))
                meta = image_meta(args, img)
                spps.append(meta.get("spp", "?"))
                secs.append(meta.get("render_seconds", "?"))
            e = sum(errs) / len(errs)
            res[integ] = e - noise
            res[integ + "_sec"] = sum(float(x) for x in secs if x != "?") / max(1, len(secs))
            print("%-12s %-7s %6s %6s %12.5g %12.5g" % (name, integ, secs[0][:6], "/".join(spps), e, e - noise))
            sys.stdout.flush()
        ratio = res["bdpt"] / res["mbdpt"] if res["mbdpt"] > 0 else float("inf")
        # The first iteration always completes, so with short budgets the two renders may
        # not take equal time: the efficiency ratio normalises by the render seconds
        # (relMSE ~ 1 / time for an unbiased estimator).
        eff = ratio * res["bdpt_sec"] / res["mbdpt_sec"] if res["mbdpt_sec"] > 0 else float("nan")
        rows.append((name, res["bdpt"], res["bdpt_sec"], res["mbdpt"], res["mbdpt_sec"], ratio, eff))
        print("%-12s relMSE(BDPT)/relMSE(M-BDPT) = %.3g, time-normalised %.3g" % (name, ratio, eff))
    print("\n| scene | BDPT relMSE | s | M-BDPT relMSE | s | ratio | time-normalised ratio |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print("| %s | %.4g | %.1f | %.4g | %.1f | %.2f | %.2f |" % r)
    return 0


if __name__ == "__main__":
    sys.exit(main())
