#!/usr/bin/env python3
"""cabinet-lamp: the transport of the G-VCM paper's Bookshelf scene, in simple geometry.

A closed diffuse room with a table and a cabinet. Above the table hangs a small
sphere light in an open lamp shade (diffuse, closed at the top): it throws a
light pool on the table; a glossy metal sphere (roughness 0.06) stands in the
pool. Beside the table a diffuse cabinet holds books, a vase and a ball behind
a glass door (a closed 8 mm slab, IOR 1.5): they are seen through the glass and
lit by the pool and the room through the glass (specular-diffuse-specular).

    bench/gvcm/make_cabinet_lamp.py OUTDIR [--res 1280x720] [--spp 16]
writes OUTDIR/cabinet-lamp.pbrt (pbrt-v3 format). Book sizes and colours come
from a fixed seed.
"""

import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scenegen as g  # noqa: E402

NAME = "cabinet-lamp"
SEED = 59

WOOD = 'Material "matte" "rgb Kd" [0.5 0.36 0.22]'
CABINET = 'Material "matte" "rgb Kd" [0.55 0.42 0.3]'
GLASS = 'Material "glass" "float index" [1.5]'
SPHERE = ('Material "metal" "rgb eta" [0.14 0.37 1.44] "rgb k" [3.98 2.38 1.6] '
          '"float roughness" [0.06] "bool remaproughness" "false"')
SHADE = 'Material "matte" "rgb Kd" [0.8 0.74 0.6]'
PALETTE = ["0.6 0.12 0.1", "0.12 0.3 0.55", "0.15 0.45 0.2", "0.7 0.6 0.3", "0.35 0.2 0.4",
           "0.75 0.72 0.68", "0.2 0.2 0.22", "0.65 0.35 0.15"]


def main():
    a = g.parse_args(NAME, __doc__)
    a.name, a.script = NAME, __file__
    rnd = random.Random(SEED)
    s = g.header(a, [(0.05, 1.4, 3.7), (-0.05, 0.88, 0.4), (0, 1, 0)], 42, 10, __doc__.split("\n\n")[1])
    # Room: x in [-2.2, 2.2], y in [0, 2.6], z in [0, 4.4]; walls face inwards.
    X, H, Z = 2.2, 2.6, 4.4
    s += g.block('Material "matte" "rgb Kd" [0.45 0.42 0.38]',
                 g.quad((-X, 0, 0), (X, 0, 0), (X, 0, Z), (-X, 0, Z), (0, 1, 0)))
    s += g.block('Material "matte" "rgb Kd" [0.7 0.7 0.68]',
                 g.quad((-X, H, 0), (X, H, 0), (X, H, Z), (-X, H, Z), (0, -1, 0)),
                 g.quad((-X, 0, Z), (X, 0, Z), (X, H, Z), (-X, H, Z), (0, 0, -1)))
    s += g.block('Material "matte" "rgb Kd" [0.62 0.6 0.52]',
                 g.quad((-X, 0, 0), (X, 0, 0), (X, H, 0), (-X, H, 0), (0, 0, 1)),
                 g.quad((-X, 0, 0), (-X, 0, Z), (-X, H, Z), (-X, H, 0), (1, 0, 0)),
                 g.quad((X, 0, 0), (X, 0, Z), (X, H, Z), (X, H, 0), (-1, 0, 0)))
    # Table: top x in [-1.6, -0.2], z in [0.3, 1.3], y in [0.72, 0.76]; legs.
    legs = [g.box(x, 0, z, x + 0.05, 0.72, z + 0.05) for x in (-1.57, -0.28) for z in (0.33, 1.22)]
    s += g.block(WOOD, g.box(-1.6, 0.72, 0.3, -0.2, 0.76, 1.3), *legs)
    # Glossy sphere in the light pool.
    s += ("AttributeBegin\nTranslate -0.72 0.85 0.88\n" + SPHERE +
          '\nShape "sphere" "float radius" [0.09]\nAttributeEnd\n')
    # Pendant lamp above (-0.95, ., 0.8): shade closed at the top, open below;
    # the light inside; a cord to the ceiling.
    cx, cz = -0.95, 0.8
    shade = g.lathe([(0, 1.5), (0.07, 1.5), (0.1, 1.42), (0.16, 1.2)], 64, centre=(cx, 0, cz))
    s += g.block(SHADE, shade)
    s += g.block('Material "matte" "rgb Kd" [0.1 0.1 0.1]', g.box(cx - 0.004, 1.5, cz - 0.004, cx + 0.004, H, cz + 0.004))
    s += g.sphere_light((cx, 1.42, cz), 0.02, (3600, 3200, 2500))
    # Cabinet against the back wall: x in [0.2, 1.4], y in [0, 1.8], z in [0.02, 0.42].
    x0, x1, y1, z0, z1, t = 0.2, 1.4, 1.8, 0.02, 0.42, 0.02
    panels = [g.box(x0, 0, z0, x0 + t, y1, z1), g.box(x1 - t, 0, z0, x1, y1, z1),  # sides
              g.box(x0 + t, y1 - t, z0, x1 - t, y1, z1), g.box(x0 + t, 0, z0, x1 - t, 0.06, z1),  # top, plinth
              g.box(x0 + t, 0.06, z0, x1 - t, y1 - t, z0 + t)]  # back
    shelves = [0.06, 0.62, 1.2]
    for y in shelves[1:]:
        panels.append(g.box(x0 + t, y, z0 + t, x1 - t, y + t, z1 - 0.01))
    s += g.block(CABINET, *panels)
    # Books on each shelf (fixed seed), leaving room for a vase and a ball.
    books = {}
    for k, y in enumerate(shelves):
        base = y + (0 if k == 0 else t)
        x = x0 + t + 0.01
        end = x1 - t - (0.3 if k != 1 else 0.02)
        while True:
            w = rnd.uniform(0.025, 0.055)
            if x + w > end:
                break
            h = rnd.uniform(0.2, 0.34)
            d = rnd.uniform(0.17, 0.25)
            col = rnd.choice(PALETTE)
            books.setdefault(col, []).append(g.box(x, base, z1 - 0.02 - d, x + w, base + h, z1 - 0.02))
            x += w + rnd.uniform(0.0, 0.008)
    for col, ms in sorted(books.items()):
        s += g.block('Material "matte" "rgb Kd" [%s]' % col, *ms)
    vase = g.lathe([(0, 0), (0.05, 0), (0.07, 0.06), (0.075, 0.12), (0.05, 0.2), (0.035, 0.25),
                    (0.045, 0.28), (0, 0.28)], 48, centre=(1.2, 0.06, 0.24))
    s += g.block('Material "matte" "rgb Kd" [0.7 0.55 0.35]', vase)
    s += ('AttributeBegin\nTranslate 1.2 %s 0.25\nMaterial "matte" "rgb Kd" [0.75 0.75 0.72]\n'
          'Shape "sphere" "float radius" [0.08]\nAttributeEnd\n' % g.fmt(1.2 + t + 0.08))
    # Glass door: a closed slab in front of the opening.
    s += g.block(GLASS, g.box(x0 + 0.005, 0.065, z1 + 0.004, x1 - 0.005, y1 - 0.005, z1 + 0.012))
    s += "WorldEnd\n"
    g.write(a, s)


if __name__ == "__main__":
    main()
