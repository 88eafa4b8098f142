#!/usr/bin/env python3
"""Writes scenes/torus-in-glass.pbrt: the G-MLT paper's TORUS setting (a non-specular
object embedded in a solid glass cube) in the room of scenes/glass-cube.pbrt, with a
diffuse torus (a smooth-shaded triangle mesh, tilted 30 degrees) in place of the sphere.

    python3 bench/gmlt/make_torus_scene.py > scenes/torus-in-glass.pbrt
"""
import math
import sys

ROOM = open(__file__.replace("bench/gmlt/make_torus_scene.py", "scenes/glass-cube.pbrt")).read()


def torus(major=0.24, minor=0.085, nu=48, nv=18, tilt_deg=30.0, centre=(0.0, 0.41, 0.0)):
    """Vertices, normals and triangles of a torus around the y axis, tilted about x."""
    ct, st = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))

    def place(x, y, z, translate):
        y, z = ct * y - st * z, st * y + ct * z
        if translate:
            return (x + centre[0], y + centre[1], z + centre[2])
        return (x, y, z)

    P, N, idx = [], [], []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            n = (math.cos(v) * math.cos(u), math.sin(v), math.cos(v) * math.sin(u))
            p = ((major + minor * math.cos(v)) * math.cos(u), minor * math.sin(v),
                 (major + minor * math.cos(v)) * math.sin(u))
            P.append(place(*p, True))
            N.append(place(*n, False))
    for i in range(nu):
        for j in range(nv):
            a = i * nv + j
            b = ((i + 1) % nu) * nv + j
            c = ((i + 1) % nu) * nv + (j + 1) % nv
            d = i * nv + (j + 1) % nv
            idx += [a, d, c, a, c, b]  # outward-facing (counter-clockwise seen from outside)
    return P, N, idx


def main():
    P, N, idx = torus()
    lines = ROOM.splitlines()
    head = [
        "# Torus in glass (Gradus; bench/gmlt/make_torus_scene.py writes it): the G-MLT paper's",
        "# TORUS setting, a non-specular object embedded in a solid glass cube, in the room of",
        "# scenes/glass-cube.pbrt: a diffuse torus sealed in the cube, seen and lit only through",
        "# the glass (E S D S ... paths), the cube's caustic on the floor. Inline geometry only.",
    ]
    out = head
    for line in lines:
        if line.startswith("# the sealed diffuse sphere"):
            break
        if line.startswith("#") and not line.startswith("# room") and not line.startswith("# the glass"):
            continue
        if line.startswith("Film"):
            line = line.replace('"glass-cube.exr"', '"torus-in-glass.exr"')
        out.append(line)
    out.append("# the sealed diffuse torus (major radius 0.24, minor 0.085, tilted 30 degrees about x)")
    out.append("AttributeBegin")
    out.append('Material "matte" "rgb Kd" [0.8 0.45 0.15]')
    fmt = lambda t: " ".join("%.6g" % c for c in t)
    out.append('Shape "trianglemesh" "integer indices" [' + " ".join(map(str, idx)) + "]")
    out.append('  "point P" [' + "  ".join(fmt(p) for p in P) + "]")
    out.append('  "normal N" [' + "  ".join(fmt(n) for n in N) + "]")
    out.append("AttributeEnd")
    out.append("WorldEnd")
    sys.stdout.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
