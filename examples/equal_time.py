#!/usr/bin/python3
"""Two integrators at equal time: relMSE against render time, plotted.

    PYTHONPATH=build/python /usr/bin/python3 examples/equal_time.py
    PYTHONPATH=build/python /usr/bin/python3 examples/equal_time.py --integrators path,gbdpt \
        --times 0.5,1,2,4 --out equal_time.png

Renders the scene with each integrator at each wall-clock budget (render(time=T)),
measures the relMSE (the papers' definition) of each image against a reference
and plots error against the seconds each render took, log-log, one line per
integrator. The default scene is the Cornell box at 64 x 64 with its stored
reference (scenes/references/cornell-box-64.exr, path tracing at 8192 spp);
without --reference another scene's reference is rendered first (bdpt, 4x the
largest budget).
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import gradus  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "cornell-box.pbrt"))
    p.add_argument("--resolution", default="64x64", help="WxH (default 64x64)")
    p.add_argument("--reference", help="reference EXR (default: the stored one for the default scene)")
    p.add_argument("--integrators", default="path,gbdpt", help="two or more names (default path,gbdpt)")
    p.add_argument("--times", default="0.25,0.5,1,2", help="budgets in seconds (default 0.25,0.5,1,2)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="equal_time.png", help="the plot (PNG)")
    args = p.parse_args()

    w, h = (int(v) for v in args.resolution.split("x"))
    times = [float(t) for t in args.times.split(",")]
    names = args.integrators.split(",")
    scene = gradus.load_scene(args.scene, resolution=(w, h))

    reference = args.reference
    if reference is None and os.path.samefile(args.scene, os.path.join(ROOT, "scenes", "cornell-box.pbrt")) \
            and (w, h) == (64, 64):
        reference = os.path.join(ROOT, "scenes", "references", "cornell-box-64.exr")
    if reference:
        ref = gradus.read_image(reference).image
    else:
        print("rendering a reference: bdpt, %.1f s" % (4 * max(times)))
        ref = scene.render(integrator="bdpt", time=4 * max(times), seed=12345).image

    curves = {}
    print("%-10s %8s %8s %6s %12s" % ("integrator", "budget", "seconds", "spp", "relMSE"))
    for name in names:
        points = []
        for t in times:
            r = scene.render(integrator=name, time=t, seed=args.seed)
            m = gradus.metrics(r.image, ref)
            seconds = r.metadata["render_seconds"]
            points.append((seconds, m["relmse"]))
            print("%-10s %8.2f %8.2f %6d %12.5g" % (name, t, seconds, r.stats["spp"], m["relmse"]))
        curves[name] = points

    fig, ax = plt.subplots(figsize=(5, 4))
    for name, points in curves.items():
        ax.loglog([s for s, _ in points], [e for _, e in points], marker="o", label=name)
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("relMSE")
    ax.set_title("%s, %dx%d" % (os.path.basename(args.scene), w, h))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
