#!/usr/bin/python3
"""bench/media/smoke_variants.py OUT: variants of bench/speed/make_kinds.py's foggy-room smoke
grid (32^3, density up to 2, sigma_t 3.5) for comparing Gradus's path/bdpt with pbrt-v3's
volpath/bdpt term by term (random sampler, box filter, 160x120; see RESULTS.md, 2026-12-07).

  room       the foggy room with its fog removed (the smoke box alone in vacuum; walls,
             lights and glass kept): the scene of the +1.5-1.9% finding
  room-lift  the same with the smoke box and its grid lifted 0.01 off the floor, whose
             plane the box's bottom face shared
  tr         transmittance only: a pure absorber (sigma_s 0) before an emitting wall, maxdepth 1
  distant1   the smoke box lit by a distant light, single scattering (maxdepth 1)
  distant    the same, multiple scattering (maxdepth 50)
"""
import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("make_kinds", os.path.join(HERE, "..", "speed", "make_kinds.py"))
mk = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mk)

CAMERA = 'LookAt 0 1.3 -3.4  0 1.0 0  0 1 0\nCamera "perspective" "float fov" [55]\n'
BOX = mk.box([-1.6, 0, 0.2], [-0.4, 1.2, 1.4])
LIFTED = mk.box([-1.6, 0.01, 0.2], [-0.4, 1.21, 1.4])
GRID = '"point p0" [-1.6 0 0.2] "point p1" [-0.4 1.2 1.4]'
GRID_LIFTED = '"point p0" [-1.6 0.01 0.2] "point p1" [-0.4 1.21 1.4]'


def write(out, name, integrator, world, spp):
    with open(os.path.join(out, name + ".pbrt"), "w") as f:
        f.write(CAMERA + 'Film "image" "integer xresolution" [160] "integer yresolution" [120] '
                '"string filename" "%s.exr"\nSampler "random" "integer pixelsamples" [%d]\nPixelFilter "box"\n'
                '%s\nWorldBegin\n%s\nWorldEnd\n' % (name, spp, integrator, world))


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    _, world = mk.foggy_room(out)
    room = (world.replace('MediumInterface "fog" "fog"\n', '')
            .replace('MediumInterface "smoke" "fog"', 'MediumInterface "smoke" ""')
            .replace('MediumInterface "" "fog"\n', ''))
    assert '"fog"' not in room and BOX in room and GRID in room
    volpath = 'Integrator "volpath" "integer maxdepth" [%d]'
    write(out, "room", volpath % 10, room, 512)
    write(out, "room-lift", volpath % 10, room.replace(BOX, LIFTED).replace(GRID, GRID_LIFTED), 512)
    lines = world.split("\n")
    i0 = next(i for i, l in enumerate(lines) if l.startswith('MakeNamedMedium "smoke"'))
    i1 = next(i for i in range(i0, len(lines)) if lines[i] == "]")
    smoke = "\n".join(lines[i0:i1 + 1])
    box = 'AttributeBegin\n  MediumInterface "smoke" ""\n  Material ""\n  ' + BOX + "\nAttributeEnd"
    absorber = smoke.replace('"rgb sigma_a" [0.5 0.5 0.5] "rgb sigma_s" [3 3 3]',
                             '"rgb sigma_a" [3.5 3.5 3.5] "rgb sigma_s" [0 0 0]')
    assert absorber != smoke
    wall = ('AttributeBegin\n  Material "matte" "rgb Kd" [0 0 0]\n  AreaLightSource "diffuse" "rgb L" [1 1 1]\n  ' +
            mk.quad([-4, -2, 3], [-4, 4, 3], [4, 4, 3], [4, -2, 3], uv=False) + "\nAttributeEnd")
    write(out, "tr", volpath % 1, "\n".join([absorber, wall, box]), 64)
    distant = 'LightSource "distant" "point from" [1 3 -1] "point to" [0 0 0] "rgb L" [3 3 3]'
    write(out, "distant1", volpath % 1, "\n".join([smoke, distant, box]), 256)
    write(out, "distant", volpath % 50, "\n".join([smoke, distant, box]), 256)
    for n in ("room", "room-lift", "tr", "distant1", "distant"):
        print(os.path.join(out, n + ".pbrt"))


if __name__ == "__main__":
    main()
