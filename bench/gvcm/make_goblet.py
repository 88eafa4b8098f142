#!/usr/bin/env python3
"""goblet: the transport of the G-VCM paper's Bottle and Glasses scenes, in simple geometry.

A lathed glass goblet (IOR 1.5; bowl wall 2 mm, solid stem and foot; one closed
surface of revolution with smooth shading normals) on a rough metal table
(roughness 0.3) before a diffuse wall. One small sphere light in a short black tube, low
behind the camera, reaches the table at a grazing angle: the goblet throws its caustic
onto the wall behind it, which the camera sees through the bowl (four glass
faces: specular-diffuse-specular) and reflected in the table.

    bench/gvcm/make_goblet.py OUTDIR [--res 1280x720] [--spp 16]
writes OUTDIR/goblet.pbrt (pbrt-v3 format).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenegen as g  # noqa: E402

NAME = "goblet"
WALL = 0.002  # bowl wall thickness

TABLE = ('Material "metal" "rgb eta" [1.66 0.88 0.52] "rgb k" [9.2 6.3 4.8] '
         '"float roughness" [0.3] "bool remaproughness" "false"')
GLASS = 'Material "glass" "float index" [1.5]'


def goblet_profile():
    """(r, y) from the foot's centre on the axis round the outside, over the
    rim and down the inside to the bowl's inner bottom on the axis."""
    p = [(0, 0), (0.036, 0), (0.036, 0.0025)]
    # Foot's upper face sloping up to the stem.
    for k in range(1, 7):
        t = k / 6
        p.append((0.036 - (0.036 - 0.0045) * t, 0.0025 + 0.006 * t ** 2))
    p.append((0.0042, 0.02))
    p.append((0.0042, 0.062))
    # Bowl outer surface: the ellipse (a sin th, yc - b cos th).
    a, b, yc = 0.042, 0.075, 0.15
    th0 = math.asin(0.011 / a)
    p.append((0.0065, 0.0715))
    th1 = 2.0
    n = 36

    def ell(th, off):
        x, y = a * math.sin(th), yc - b * math.cos(th)
        # Outward normal of the ellipse at th: (sin th / a, -cos th / b) normalised... in (r, y):
        nx, ny = math.sin(th) / a, -math.cos(th) / b
        l = math.hypot(nx, ny)
        return (x - off * nx / l, y - off * ny / l)

    outer = [ell(th0 + (th1 - th0) * k / n, 0) for k in range(n + 1)]
    p += outer
    # Rim: a half circle from the outer to the inner rim point.
    o, i = ell(th1, 0), ell(th1, WALL)
    cxy = ((o[0] + i[0]) / 2, (o[1] + i[1]) / 2)
    ang0 = math.atan2(o[1] - cxy[1], o[0] - cxy[0])
    for k in range(1, 6):
        ang = ang0 + math.pi * k / 6
        p.append((cxy[0] + WALL / 2 * math.cos(ang), cxy[1] + WALL / 2 * math.sin(ang)))
    # Inner surface, back down to the axis.
    inner = [ell(th1 - th1 * k / n, WALL) for k in range(n + 1)]
    inner[-1] = (0, inner[-1][1])
    p += inner
    return p


def main():
    a = g.parse_args(NAME, __doc__)
    a.name, a.script = NAME, __file__
    s = g.header(a, [(0.07, 0.165, 0.52), (0.0, 0.095, -0.05), (0, 1, 0)], 26, 12, __doc__.split("\n\n")[1])
    # Diffuse wall behind (z = -0.13) and the metal table top (y = 0).
    s += g.block('Material "matte" "rgb Kd" [0.7 0.68 0.62]',
                 g.quad((-1.5, -0.04, -0.13), (1.5, -0.04, -0.13), (1.5, 1.2, -0.13), (-1.5, 1.2, -0.13), (0, 0, 1)))
    s += g.block(TABLE, g.box(-1.5, -0.04, -0.13, 1.5, 0, 0.9))
    s += g.block(GLASS, g.lathe(goblet_profile(), 128))
    # Small light, low behind the camera: ~8 degrees above the table at the goblet.
    # It sits at the closed end of a short black tube aimed at the goblet (a
    # beam of about 20 degrees half-angle), so that light paths reach the view.
    lx, ly, lz = 0.025, 0.12, 0.8
    tube = g.lathe([(0, 0), (0.016, 0), (0.016, 0.06)], 48)
    s += g.block('Material "matte" "rgb Kd" [0.03 0.03 0.03]', tube,
                 extra="Translate %s %s %s\nRotate -90 1 0 0\n" % (g.fmt(lx), g.fmt(ly), g.fmt(lz + 0.015)))
    s += g.sphere_light((lx, ly, lz), 0.004, (30000, 28000, 24000))
    s += "WorldEnd\n"
    g.write(a, s)


if __name__ == "__main__":
    main()
