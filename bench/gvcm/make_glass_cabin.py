#!/usr/bin/env python3
"""glass-cabin: the transport of the G-VCM paper's Car scene, in simple geometry.

A diffuse car-like body whose cabin has glass-slab windows (closed 6 mm slabs,
two parallel faces, IOR 1.5) in glossy metal frames (roughness 0.07), diffuse
seats inside, wheels with glossy metal hubs (roughness 0.05), one small bright
sphere light outside and a diffuse studio floor and walls. The camera stands
outside and looks through the windscreen: the seats are seen through glass and
lit mostly through glass (E S S D S S L: specular-diffuse-specular), the frames
and hub are glossy, the body, floor and walls large diffuse regions.

    bench/gvcm/make_glass_cabin.py OUTDIR [--res 1280x720] [--spp 16]
writes OUTDIR/glass-cabin.pbrt (pbrt-v3 format).
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenegen as g  # noqa: E402

NAME = "glass-cabin"

PAINT = 'Material "matte" "rgb Kd" [0.55 0.12 0.08]'
ROOF = 'Material "matte" "rgb Kd" [0.5 0.11 0.07]'
GLASS = 'Material "glass" "float index" [1.5]'
# Aluminium-like conductor; alpha given directly (no remapping).
FRAME = ('Material "metal" "rgb eta" [1.66 0.88 0.52] "rgb k" [9.2 6.3 4.8] '
         '"float roughness" [0.07] "bool remaproughness" "false"')
HUB = ('Material "metal" "rgb eta" [1.66 0.88 0.52] "rgb k" [9.2 6.3 4.8] '
       '"float roughness" [0.05] "bool remaproughness" "false"')
TIRE = 'Material "matte" "rgb Kd" [0.05 0.05 0.05]'

SLAB = 0.006     # glass thickness
BAR = 0.03       # frame bar width in the wall plane
BAR_DEPTH = 0.04  # frame bar depth across the wall
GAP = 0.001      # between glass edge and frame (no overlapping solids)


def wall_with_hole(axis, plane, u0, u1, v0, v1, hu0, hu1, hv0, hv1, out):
    """A zero-thickness wall in the plane axis = plane, spanning (u, v) in
    [u0, u1] x [v0, v1] (u, v: the other two axes in x, y, z order), with the
    rectangular hole [hu0, hu1] x [hv0, hv1]: four quads."""
    def P(u, v):
        if axis == 0:
            return (plane, u, v)
        if axis == 1:
            return (u, plane, v)
        return (u, v, plane)
    strips = [(u0, u1, v0, hv0), (u0, u1, hv1, v1), (u0, hu0, hv0, hv1), (hu1, u1, hv0, hv1)]
    ms = []
    for a0, a1, b0, b1 in strips:
        if a1 - a0 > 1e-9 and b1 - b0 > 1e-9:
            ms.append(g.quad(P(a0, b0), P(a1, b0), P(a1, b1), P(a0, b1), out))
    return ms


def window(axis, plane, hu0, hu1, hv0, hv1):
    """Frame bars and glass slab filling the hole [hu0, hu1] x [hv0, hv1] of a
    wall in the plane axis = plane (u, v as in wall_with_hole)."""
    def B(u0, u1, v0, v1, w0, w1):
        if axis == 0:
            return g.box(w0, u0, v0, w1, u1, v1)
        if axis == 1:
            return g.box(u0, w0, v0, u1, w1, v1)
        return g.box(u0, v0, w0, u1, v1, w1)
    d = BAR_DEPTH / 2
    bars = [
        B(hu0, hu1, hv0, hv0 + BAR, plane - d, plane + d),
        B(hu0, hu1, hv1 - BAR, hv1, plane - d, plane + d),
        B(hu0, hu0 + BAR, hv0 + BAR, hv1 - BAR, plane - d, plane + d),
        B(hu1 - BAR, hu1, hv0 + BAR, hv1 - BAR, plane - d, plane + d),
    ]
    e = BAR + GAP
    glass = B(hu0 + e, hu1 - e, hv0 + e, hv1 - e, plane - SLAB / 2, plane + SLAB / 2)
    return bars, glass


def seat(x0, x1, z0, z1, floor, colour):
    """Cushion, backrest (towards -z) and headrest boxes."""
    cushion = g.box(x0, floor, z0, x1, floor + 0.2, z1)
    back = g.box(x0, floor + 0.2, z0 - 0.1, x1, floor + 0.5, z0)
    head = g.box(x0 + 0.12, floor + 0.52, z0 - 0.09, x1 - 0.12, floor + 0.64, z0 - 0.01)
    return g.block('Material "matte" "rgb Kd" [%s]' % colour, cushion, back, head)


def wheel(x, y, z, side):
    """Tyre (closed ring) and hub (closed shallow dome) about the x axis; side
    +1 / -1: the hub faces +x / -x."""
    tyre = g.lathe([(0.2, -0.11), (0.31, -0.11), (0.33, -0.08), (0.33, 0.08), (0.31, 0.11),
                    (0.2, 0.11), (0.2, -0.11)], 64, smooth=False)
    prof = [(0, 0.1), (0.19, 0.1), (0.19, 0.118)]
    for k in range(1, 9):
        t = k / 8
        prof.append((0.19 * (1 - t) ** 0.5 if k < 8 else 0, 0.118 + 0.03 * (1 - (1 - t) ** 2)))
    hub = g.lathe(prof, 64)
    xf = "Translate %s %s %s\nRotate %d 0 0 1\n" % (g.fmt(x), g.fmt(y), g.fmt(z), -90 if side > 0 else 90)
    return g.block(TIRE, tyre, extra=xf) + g.block(HUB, hub, extra=xf)


def main():
    a = g.parse_args(NAME, __doc__)
    a.name, a.script = NAME, __file__
    s = g.header(a, [(-3.0, 1.85, 4.1), (0.15, 0.82, -0.1), (0, 1, 0)], 34, 10, __doc__.split("\n\n")[1])
    # Studio: floor, back wall, right wall.
    s += g.block('Material "matte" "rgb Kd" [0.55 0.55 0.52]',
                 g.quad((-12, 0, -7), (12, 0, -7), (12, 0, 12), (-12, 0, 12), (0, 1, 0)))
    s += g.block('Material "matte" "rgb Kd" [0.6 0.62 0.65]',
                 g.quad((-12, 0, -7), (12, 0, -7), (12, 8, -7), (-12, 8, -7), (0, 0, 1)),
                 g.quad((7, 0, -7), (7, 0, 12), (7, 8, 12), (7, 8, -7), (-1, 0, 0)))
    # Lower body (closed box; its top is the cabin floor) and dashboard.
    s += g.block(PAINT, g.box(-0.9, 0.3, -2.2, 0.9, 0.85, 2.2))
    s += g.block('Material "matte" "rgb Kd" [0.12 0.12 0.13]', g.box(-0.8, 0.85, 0.62, 0.8, 1.02, 0.88))
    # Cabin: x in [-0.85, 0.85], y in [0.85, 1.55], z in [-1.2, 0.9]; windows
    # from y 1.0 to 1.45; zero-thickness diffuse walls and roof.
    X, Y0, Y1, Z0, Z1 = 0.85, 0.85, 1.55, -1.2, 0.9
    W0, W1 = 1.0, 1.45
    walls = []
    walls += wall_with_hole(2, Z1, -X, X, Y0, Y1, -0.75, 0.75, W0, W1, (0, 0, 1))    # front
    walls += wall_with_hole(2, Z0, -X, X, Y0, Y1, -0.75, 0.75, W0, W1, (0, 0, -1))   # rear
    glassy = []
    for side in (-1, 1):
        # Side walls (axis x): u = y, v = z; two windows split by a pillar.
        xs = side * X
        out = (side, 0, 0)
        walls += wall_with_hole(0, xs, Y0, Y1, Z0, -0.15, W0, W1, -1.1, -0.2, out)
        walls += wall_with_hole(0, xs, Y0, Y1, -0.15, Z1, W0, W1, -0.1, 0.8, out)
        for v0, v1 in ((-1.1, -0.2), (-0.1, 0.8)):
            glassy.append(window(0, xs, W0, W1, v0, v1))
    s += g.block(PAINT, *walls)
    s += g.block(ROOF, g.quad((-X, Y1, Z0), (X, Y1, Z0), (X, Y1, Z1), (-X, Y1, Z1), (0, 1, 0)))
    glassy.append(window(2, Z1, -0.75, 0.75, W0, W1))
    glassy.append(window(2, Z0, -0.75, 0.75, W0, W1))
    s += g.block(FRAME, *[b for bars, _ in glassy for b in bars])
    s += g.block(GLASS, *[gl for _, gl in glassy])
    # Seats: two front seats, a rear bench.
    s += seat(-0.7, -0.15, 0.0, 0.5, Y0, "0.62 0.5 0.32")
    s += seat(0.15, 0.7, 0.0, 0.5, Y0, "0.62 0.5 0.32")
    s += seat(-0.75, 0.75, -1.05, -0.6, Y0, "0.3 0.42 0.58")
    # Wheels with hubs.
    for x in (-0.92, 0.92):
        for z in (-1.4, 1.4):
            s += wheel(x, 0.34, z, 1 if x > 0 else -1)
    # Small bright light outside, above the front right: it shines through the
    # windscreen and the right windows onto the seats.
    s += g.sphere_light((2.6, 3.3, 2.4), 0.07, (4000, 3800, 3400))
    s += "WorldEnd\n"
    g.write(a, s)


if __name__ == "__main__":
    main()
