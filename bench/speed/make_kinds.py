#!/usr/bin/python3
"""Scene kinds for the speed benchmark (issue "Fast on the scenes users bring").

  bench/speed/make_kinds.py OUT_DIR [--res W H] [--kinds a,b]

Writes, for every kind, OUT_DIR/<kind>/world.pbrt (the scene), its textures and
one OUT_DIR/<kind>/<kind>-<sampler>.pbrt per sampler pbrt-v3 names (header:
camera, film, sampler, integrator; then `Include "world.pbrt"`). Everything is
procedural and deterministic (fixed seeds); nothing is copied. The files are
plain pbrt-v3 syntax, so pbrt-v3 renders them as they are. Each kind stresses
what real scenes exercise and the Cornell box does not:

  env-interior  exporter-style interior lit through an opening by two lat-long
                maps (1024x512, 512x256) and a distant sun; uber, glass,
                substrate, plastic; 8-bit PNG image textures; named materials
  outdoor-sky   ground under a 2048x1024 sky map and a blackbody sun; 400
                instanced cubes (ObjectBegin/ObjectInstance); a loop-subdivided
                mesh
  many-lights   a room with 64 point lights, 8 spot lights and 8 sphere area
                lights; matte and plastic
  foggy-room    a room filled with homogeneous fog, a heterogeneous 32^3 smoke
                grid, a spot light, a glass sphere
  hair          20 000 cylinder curves with the hair material on a head-sized
                sphere; one area light, one distant light
  product       a studio shot: uber, plastic, substrate and metal; a
                loop-subdivided icosahedron (levels 4); a 131 072-triangle text
                mesh with normals and uv; two quad area lights
"""
import argparse
import math
import os
import random
import struct
import sys
import zlib

SAMPLERS = ["halton", "sobol", "02sequence", "maxmindist", "stratified", "random"]
KINDS = ["env-interior", "outdoor-sky", "many-lights", "foggy-room", "hair", "product"]
# The integrator each header names (the benchmark passes its own with --integrator).
INTEGRATOR = {"foggy-room": 'Integrator "volpath" "integer maxdepth" [10]'}


# -- images ------------------------------------------------------------------------

def write_pfm(path, w, h, pixel):
    """pixel(x, y) -> (r, g, b) with y = 0 the top row; PFM stores bottom row first."""
    rows = []
    for y in range(h - 1, -1, -1):
        row = []
        for x in range(w):
            row.extend(pixel(x, y))
        rows.append(struct.pack("<%df" % (3 * w), *row))
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(b"".join(rows))


def write_png(path, w, h, pixel):
    """8-bit RGB PNG; pixel(x, y) -> (r, g, b) codes 0..255."""
    raw = bytearray()
    for y in range(h):
        raw.append(0)
        for x in range(w):
            raw.extend(bytes(pixel(x, y)))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(bytes(raw), 6)))
        f.write(chunk(b"IEND", b""))


def sky(w, h, sun_dir, sun_power, tint=(1.0, 1.0, 1.0)):
    """A lat-long sky (pbrt-v3's mapping: +z up, phi around z): a gradient, a sun disc and
    cloud-like noise, so that the map's distribution is far from uniform."""
    rnd = random.Random(7)
    bumps = [(rnd.uniform(0, 2 * math.pi), rnd.uniform(0.2, 1.4), rnd.uniform(0.05, 0.3)) for _ in range(24)]
    sx, sy, sz = sun_dir

    def pixel(x, y):
        theta = math.pi * (y + 0.5) / h
        phi = 2 * math.pi * (x + 0.5) / w
        dx, dy, dz = math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)
        up = max(dz, 0.0)
        c = (0.25 + 0.5 * (1 - up), 0.35 + 0.45 * (1 - up), 0.9) if dz > 0 else (0.12, 0.1, 0.08)
        cloud = 0.0
        for p0, t0, s in bumps:
            d = (phi - p0 + math.pi) % (2 * math.pi) - math.pi
            cloud += math.exp(-(d * d + (theta - t0) ** 2) / (2 * s * s))
        cos_sun = dx * sx + dy * sy + dz * sz
        sun = sun_power if cos_sun > 0.9995 else 0.0
        return tuple(tint[i] * (c[i] + 0.6 * min(cloud, 1.5)) + sun for i in range(3))
    return pixel


def wood(w, h):
    rnd = random.Random(3)
    phase = [rnd.uniform(0, 6.3) for _ in range(8)]

    def pixel(x, y):
        u, v = x / w, y / h
        ring = math.sin(40 * u + 3 * math.sin(6 * v + phase[int(8 * v) % 8])) * 0.5 + 0.5
        plank = 0.85 if (int(8 * v) + int(2 * u + 0.5 * (int(8 * v) % 2))) % 2 else 1.0
        return (int(255 * plank * (0.45 + 0.25 * ring)), int(255 * plank * (0.28 + 0.15 * ring)),
                int(255 * plank * (0.14 + 0.08 * ring)))
    return pixel


def tiles(w, h, n=16):
    def pixel(x, y):
        gx, gy = (x * n) // w, (y * n) // h
        grout = (x * n) % w < w // (8 * n) or (y * n) % h < h // (8 * n)
        if grout:
            return (60, 60, 58)
        k = 200 if (gx + gy) % 2 else 170
        return (k, k - 10, k - 25)
    return pixel


# -- geometry ------------------------------------------------------------------------

def fmt(vals):
    return " ".join("%.6g" % v for v in vals)


def quad(p0, p1, p2, p3, uv=True):
    s = 'Shape "trianglemesh" "integer indices" [0 1 2 0 2 3] "point P" [%s]' % fmt(p0 + p1 + p2 + p3)
    if uv:
        s += ' "float uv" [0 0 1 0 1 1 0 1]'
    return s


def box(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    P = [x0, y0, z0, x1, y0, z0, x1, y1, z0, x0, y1, z0, x0, y0, z1, x1, y0, z1, x1, y1, z1, x0, y1, z1]
    idx = [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5]
    return 'Shape "trianglemesh" "integer indices" [%s] "point P" [%s]' % (" ".join(map(str, idx)), fmt(P))


def icosahedron(r):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
         3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1]
    n = math.sqrt(1 + t * t)
    P = [c * r / n for p in v for c in p]
    return P, f


def torus_mesh(R, r, nu, nv):
    """A bumpy torus as an indexed text mesh with normals and uv (2 nu nv triangles)."""
    P, N, UV, idx = [], [], [], []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            v = 2 * math.pi * j / nv
            rr = r * (1 + 0.06 * math.sin(7 * u) * math.sin(5 * v))
            cx, cy = math.cos(u), math.sin(u)
            nx, ny, nz = math.cos(v) * cx, math.cos(v) * cy, math.sin(v)
            P += [(R + rr * math.cos(v)) * cx, (R + rr * math.cos(v)) * cy, rr * math.sin(v)]
            N += [nx, ny, nz]
            UV += [i / nu, j / nv]
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            idx += [a, b, c, a, c, d]
    return P, N, UV, idx


def mesh_statement(P, idx, N=None, UV=None):
    lines = ['Shape "trianglemesh"', '  "integer indices" [']
    for k in range(0, len(idx), 24):
        lines.append("    " + " ".join(map(str, idx[k:k + 24])))
    lines.append("  ]")
    for name, vals, per in (("point P", P, 12), ("normal N", N, 12), ("float uv", UV, 16)):
        if vals is None:
            continue
        lines.append('  "%s" [' % name)
        for k in range(0, len(vals), per):
            lines.append("    " + fmt(vals[k:k + per]))
        lines.append("  ]")
    return "\n".join(lines)


# -- the kinds ------------------------------------------------------------------------

def env_interior(d):
    write_pfm(os.path.join(d, "sky-1024.pfm"), 1024, 512, sky(1024, 512, (0.5, -0.6, 0.62), 4000.0))
    write_pfm(os.path.join(d, "fill-512.pfm"), 512, 256, sky(512, 256, (-0.3, 0.8, 0.5), 0.0, (0.5, 0.45, 0.4)))
    write_png(os.path.join(d, "wood.png"), 512, 512, wood(512, 512))
    write_png(os.path.join(d, "tiles.png"), 256, 256, tiles(256, 256))
    w = ["# exporter-style interior: two lat-long maps through an opening, a sun, textures"]
    w.append('AttributeBegin\n  Rotate -90 1 0 0\n  LightSource "infinite" "string mapname" "sky-1024.pfm" '
             '"integer samples" [1]\nAttributeEnd')
    w.append('AttributeBegin\n  Rotate -90 1 0 0\n  LightSource "infinite" "string mapname" "fill-512.pfm" '
             '"rgb L" [0.3 0.3 0.3]\nAttributeEnd')
    w.append('LightSource "distant" "point from" [4 6 -3] "point to" [0 0 0] "rgb L" [3 2.8 2.5]')
    w.append('Texture "woodtex" "spectrum" "imagemap" "string filename" "wood.png" "float uscale" [4] '
             '"float vscale" [4] "bool trilinear" "true"')
    w.append('Texture "tiletex" "spectrum" "imagemap" "string filename" "tiles.png" "float uscale" [3] '
             '"float vscale" [3]')
    w.append('MakeNamedMaterial "Floor" "string type" "uber" "texture Kd" "woodtex" "rgb Ks" [0.04 0.04 0.04] '
             '"float roughness" [0.05] "rgb Kr" [0 0 0] "rgb Kt" [0 0 0] "float index" [1.5]')
    w.append('MakeNamedMaterial "Wall" "string type" "matte" "texture Kd" "tiletex"')
    w.append('MakeNamedMaterial "Glass" "string type" "glass" "float index" [1.5]')
    w.append('MakeNamedMaterial "Lacquer" "string type" "substrate" "rgb Kd" [0.5 0.1 0.08] "rgb Ks" [0.04 0.04 0.04] '
             '"float uroughness" [0.08] "float vroughness" [0.08]')
    w.append('MakeNamedMaterial "Plastic" "string type" "plastic" "rgb Kd" [0.1 0.3 0.5] "rgb Ks" [0.3 0.3 0.3] '
             '"float roughness" [0.1]')
    # room 6 x 3 x 6, opening in the wall at z = 3 and in the ceiling
    w.append('NamedMaterial "Floor"\n' + quad([-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]))
    w.append('NamedMaterial "Wall"')
    w.append(quad([-3, 0, -3], [-3, 3, -3], [3, 3, -3], [3, 0, -3]))
    w.append(quad([-3, 0, -3], [-3, 0, 3], [-3, 3, 3], [-3, 3, -3]))
    w.append(quad([3, 0, -3], [3, 3, -3], [3, 3, 3], [3, 0, 3]))
    w.append(quad([-3, 0, 3], [-1.5, 0, 3], [-1.5, 3, 3], [-3, 3, 3]))
    w.append(quad([1.5, 0, 3], [3, 0, 3], [3, 3, 3], [1.5, 3, 3]))
    w.append(quad([-1.5, 2.2, 3], [1.5, 2.2, 3], [1.5, 3, 3], [-1.5, 3, 3]))
    w.append(quad([-3, 3, -3], [-3, 3, 1], [3, 3, 1], [3, 3, -3]))
    w.append('NamedMaterial "Plastic"\n' + box([-1.2, 0, -1.0], [0.6, 0.75, 0.2]))
    w.append('AttributeBegin\n  NamedMaterial "Glass"\n  Translate -0.5 1.1 -0.4\n  Shape "sphere" "float radius" [0.35]\n'
             'AttributeEnd')
    w.append('AttributeBegin\n  NamedMaterial "Lacquer"\n  Translate 1.6 0.5 -1.5\n  Shape "sphere" "float radius" [0.5]\n'
             'AttributeEnd')
    return ("LookAt 0 1.5 -2.8  0 1.0 3  0 1 0\nCamera \"perspective\" \"float fov\" [70]", "\n".join(w))


def outdoor_sky(d):
    write_pfm(os.path.join(d, "sky-2048.pfm"), 2048, 1024, sky(2048, 1024, (0.35, 0.55, 0.76), 0.0))
    write_png(os.path.join(d, "ground.png"), 512, 512, tiles(512, 512, 32))
    w = ["# outdoor: a sky map, a blackbody sun, 400 instanced cubes, a subdivided mesh"]
    w.append('AttributeBegin\n  Rotate -90 1 0 0\n  LightSource "infinite" "string mapname" "sky-2048.pfm"\nAttributeEnd')
    w.append('LightSource "distant" "point from" [0.35 0.76 -0.55] "point to" [0 0 0] "blackbody L" [5500 4]')
    w.append('Texture "ground" "spectrum" "imagemap" "string filename" "ground.png" "float uscale" [20] '
             '"float vscale" [20]')
    w.append('Material "uber" "texture Kd" "ground" "rgb Ks" [0.02 0.02 0.02] "float roughness" [0.2]')
    w.append(quad([-50, 0, -50], [50, 0, -50], [50, 0, 50], [-50, 0, 50]))
    w.append('ObjectBegin "cube"\n  Material "plastic" "rgb Kd" [0.6 0.5 0.4] "rgb Ks" [0.2 0.2 0.2] '
             '"float roughness" [0.15]\n  ' + box([-0.3, 0, -0.3], [0.3, 0.6, 0.3]) + '\nObjectEnd')
    rnd = random.Random(11)
    for i in range(20):
        for j in range(20):
            w.append('AttributeBegin Translate %.4g 0 %.4g Rotate %.4g 0 1 0 Scale %.3g %.3g %.3g '
                     'ObjectInstance "cube" AttributeEnd' % (
                         -12 + 1.3 * i + rnd.uniform(-0.2, 0.2), 2 + 1.3 * j + rnd.uniform(-0.2, 0.2),
                         rnd.uniform(0, 90), 1, rnd.uniform(0.5, 3), 1))
    P, f = icosahedron(1.0)
    w.append('AttributeBegin\n  Translate -1.5 1 1\n  Material "metal" "float roughness" [0.05]\n'
             '  Shape "loopsubdiv" "integer levels" [3] "integer indices" [%s] "point P" [%s]\nAttributeEnd'
             % (" ".join(map(str, f)), fmt(P)))
    return ("LookAt 0 2.2 -6  0 1.2 4  0 1 0\nCamera \"perspective\" \"float fov\" [60]", "\n".join(w))


def many_lights(d):
    w = ["# a room with 64 point lights, 8 spot lights and 8 sphere area lights"]
    rnd = random.Random(5)
    for i in range(8):
        for j in range(8):
            c = [rnd.uniform(0.3, 1.0) for _ in range(3)]
            w.append('LightSource "point" "point from" [%.4g 2.7 %.4g] "rgb I" [%s]' % (
                -3.5 + i, -3.5 + j, fmt([0.4 * x for x in c])))
    for k in range(8):
        a = 2 * math.pi * k / 8
        w.append('LightSource "spot" "point from" [%.4g 2.9 %.4g] "point to" [%.4g 0 %.4g] "float coneangle" [20] '
                 '"rgb I" [6 5 4]' % (3.5 * math.cos(a), 3.5 * math.sin(a), 2 * math.cos(a), 2 * math.sin(a)))
    for k in range(8):
        w.append('AttributeBegin\n  Translate %.4g 0.4 %.4g\n  AreaLightSource "diffuse" "rgb L" [%s]\n'
                 '  Shape "sphere" "float radius" [0.06]\nAttributeEnd' % (
                     rnd.uniform(-3.5, 3.5), rnd.uniform(-3.5, 3.5), fmt([rnd.uniform(5, 30) for _ in range(3)])))
    w.append('Material "matte" "rgb Kd" [0.6 0.6 0.6]')
    w.append(quad([-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]))
    w.append(quad([-4, 3, -4], [-4, 3, 4], [4, 3, 4], [4, 3, -4]))
    w.append(quad([-4, 0, -4], [-4, 3, -4], [4, 3, -4], [4, 0, -4]))
    w.append(quad([-4, 0, 4], [4, 0, 4], [4, 3, 4], [-4, 3, 4]))
    w.append(quad([-4, 0, -4], [-4, 0, 4], [-4, 3, 4], [-4, 3, -4]))
    w.append(quad([4, 0, -4], [4, 3, -4], [4, 3, 4], [4, 0, 4]))
    for k in range(24):
        x, z = rnd.uniform(-3.3, 3.3), rnd.uniform(-3.3, 3.3)
        h = rnd.uniform(0.3, 1.2)
        if k % 2:
            w.append('Material "plastic" "rgb Kd" [%s] "rgb Ks" [0.25 0.25 0.25] "float roughness" [0.08]' %
                     fmt([rnd.uniform(0.1, 0.8) for _ in range(3)]))
        else:
            w.append('Material "matte" "rgb Kd" [%s]' % fmt([rnd.uniform(0.1, 0.8) for _ in range(3)]))
        w.append(box([x - 0.25, 0, z - 0.25], [x + 0.25, h, z + 0.25]))
    return ("LookAt 0 2.0 -3.8  0 0.8 1  0 1 0\nCamera \"perspective\" \"float fov\" [65]", "\n".join(w))


def foggy_room(d):
    n = 32
    rnd = random.Random(9)
    blobs = [(rnd.uniform(0.2, 0.8), rnd.uniform(0.2, 0.8), rnd.uniform(0.2, 0.8), rnd.uniform(0.08, 0.2))
             for _ in range(10)]
    dens = []
    for z in range(n):
        for y in range(n):
            for x in range(n):
                p = ((x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n)
                v = sum(math.exp(-((p[0] - bx) ** 2 + (p[1] - by) ** 2 + (p[2] - bz) ** 2) / (2 * s * s))
                        for bx, by, bz, s in blobs)
                dens.append(min(v, 2.0))
    header = ('LookAt 0 1.3 -3.4  0 1.0 0  0 1 0\nCamera "perspective" "float fov" [55]\n'
              'MakeNamedMedium "fog" "string type" "homogeneous" "rgb sigma_a" [0.02 0.02 0.02] '
              '"rgb sigma_s" [0.15 0.14 0.12] "float g" [0.3]\nMediumInterface "" "fog"')
    w = ["# a foggy room: homogeneous fog everywhere, a smoke grid, a spot light, a glass sphere"]
    w.append('MakeNamedMedium "smoke" "string type" "heterogeneous" "rgb sigma_a" [0.5 0.5 0.5] '
             '"rgb sigma_s" [3 3 3] "float g" [0.1] "point p0" [-1.6 0.01 0.2] "point p1" [-0.4 1.21 1.4] '
             '"integer nx" [%d] "integer ny" [%d] "integer nz" [%d] "float density" [' % (n, n, n))
    for k in range(0, len(dens), 16):
        w.append("  " + " ".join("%.4f" % v for v in dens[k:k + 16]))
    w.append("]")
    w.append('LightSource "spot" "point from" [0.3 2.45 0.4] "point to" [0 0 0.2] "float coneangle" [18] '
             '"float conedeltaangle" [4] "rgb I" [20 19 17]')
    w.append('AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [10 10 10]\n  MediumInterface "fog" "fog"\n  ' +
             quad([1.2, 2.49, -1.2], [1.2, 2.49, -0.8], [1.6, 2.49, -0.8], [1.6, 2.49, -1.2], uv=False) +
             '\nAttributeEnd')
    w.append('AttributeBegin\n  MediumInterface "fog" "fog"\n  Material "matte" "rgb Kd" [0.6 0.6 0.6]')
    for q in ([[-2, 0, -3.6], [2, 0, -3.6], [2, 0, 2], [-2, 0, 2]],
              [[-2, 2.5, -3.6], [-2, 2.5, 2], [2, 2.5, 2], [2, 2.5, -3.6]],
              [[-2, 0, 2], [2, 0, 2], [2, 2.5, 2], [-2, 2.5, 2]],
              [[-2, 0, -3.6], [-2, 0, 2], [-2, 2.5, 2], [-2, 2.5, -3.6]],
              [[2, 0, -3.6], [2, 2.5, -3.6], [2, 2.5, 2], [2, 0, 2]],
              [[-2, 0, -3.6], [-2, 2.5, -3.6], [2, 2.5, -3.6], [2, 0, -3.6]]):
        w.append("  " + quad(*q, uv=False))
    w.append("AttributeEnd")
    w.append('AttributeBegin\n  MediumInterface "smoke" "fog"\n  Material ""\n  ' +
             box([-1.6, 0.01, 0.2], [-0.4, 1.21, 1.4]) + "\nAttributeEnd")
    w.append('AttributeBegin\n  MediumInterface "" "fog"\n  Material "glass" "float index" [1.5]\n'
             '  Translate 0.8 0.6 0.4\n  Shape "sphere" "float radius" [0.45]\nAttributeEnd')
    return header, "\n".join(w)


def hair(d):
    rnd = random.Random(13)
    w = ["# 20 000 hair curves on a sphere"]
    w.append('AttributeBegin\n  Translate -2 3 -2\n  AreaLightSource "diffuse" "rgb L" [12 12 12]\n'
             '  Shape "sphere" "float radius" [0.4]\nAttributeEnd')
    w.append('LightSource "distant" "point from" [1 2 -1] "point to" [0 0 0] "rgb L" [1.5 1.5 1.5]')
    w.append('Material "matte" "rgb Kd" [0.5 0.5 0.5]')
    w.append(quad([-5, -1.2, -5], [5, -1.2, -5], [5, -1.2, 5], [-5, -1.2, 5], uv=False))
    w.append('AttributeBegin\n  Material "matte" "rgb Kd" [0.6 0.45 0.35]\n  Shape "sphere" "float radius" [1]\n'
             'AttributeEnd')
    w.append('Material "hair" "float eumelanin" [1.3] "float beta_m" [0.3] "float beta_n" [0.3]')
    for _ in range(20000):
        while True:  # upper hemisphere directions
            z = rnd.uniform(-0.2, 1.0)
            phi = rnd.uniform(0, 2 * math.pi)
            s = math.sqrt(1 - z * z)
            n = (s * math.cos(phi), z, s * math.sin(phi))
            if n[2] < 0.6:
                break
        L = rnd.uniform(0.5, 0.9)
        pts = []
        for k in range(4):
            t = k / 3
            droop = 0.6 * t * t * L
            pts += [n[0] * (1 + t * L * 0.7), n[1] * (1 + t * L * 0.7) - droop, n[2] * (1 + t * L * 0.7)]
        w.append('Shape "curve" "string type" "cylinder" "point P" [%s] "float width0" [0.004] "float width1" [0.002]'
                 % fmt(pts))
    return ("LookAt 0 0.8 -4  0 0.3 0  0 1 0\nCamera \"perspective\" \"float fov\" [40]", "\n".join(w))


def product(d):
    w = ["# a studio product shot: uber, plastic, substrate, metal; loop subdivision; a large text mesh"]
    w.append('AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [8 8 8]\n  ' +
             quad([-3, 4, -2], [-1, 4, -2], [-1, 4, 0], [-3, 4, 0], uv=False) + '\nAttributeEnd')
    w.append('AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [4 4 5]\n  ' +
             quad([3, 0.5, -3], [3, 3, -3], [3, 3, -1], [3, 0.5, -1], uv=False) + '\nAttributeEnd')
    w.append('LightSource "infinite" "rgb L" [0.15 0.15 0.17]')
    w.append('Material "uber" "rgb Kd" [0.7 0.7 0.7] "rgb Ks" [0.05 0.05 0.05] "float roughness" [0.3]')
    w.append(quad([-10, 0, -10], [10, 0, -10], [10, 0, 10], [-10, 0, 10]))
    w.append(quad([-10, 0, 4], [10, 0, 4], [10, 8, 4], [-10, 8, 4]))
    P, N, UV, idx = torus_mesh(0.8, 0.3, 256, 256)
    w.append('AttributeBegin\n  Translate 0 0.3 0\n  Rotate 90 1 0 0\n'
             '  Material "uber" "rgb Kd" [0.05 0.2 0.6] "rgb Ks" [0.3 0.3 0.3] "float roughness" [0.02] '
             '"rgb Kr" [0.1 0.1 0.1] "float index" [1.5]\n' + mesh_statement(P, idx, N, UV) + '\nAttributeEnd')
    P, f = icosahedron(0.6)
    w.append('AttributeBegin\n  Translate -1.8 0.6 0.5\n  Material "metal" "float roughness" [0.08]\n'
             '  Shape "loopsubdiv" "integer levels" [4] "integer indices" [%s] "point P" [%s]\nAttributeEnd'
             % (" ".join(map(str, f)), fmt(P)))
    w.append('AttributeBegin\n  Translate 1.7 0.5 0.3\n  Material "substrate" "rgb Kd" [0.6 0.1 0.1] '
             '"rgb Ks" [0.05 0.05 0.05] "float uroughness" [0.05] "float vroughness" [0.2]\n'
             '  Shape "sphere" "float radius" [0.5]\nAttributeEnd')
    w.append('AttributeBegin\n  Translate 0.6 0.25 -1.3\n  Material "plastic" "rgb Kd" [0.1 0.5 0.1] '
             '"rgb Ks" [0.4 0.4 0.4] "float roughness" [0.05]\n  Shape "sphere" "float radius" [0.25]\nAttributeEnd')
    return ("LookAt 0 1.8 -4.5  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]", "\n".join(w))


MAKERS = {"env-interior": env_interior, "outdoor-sky": outdoor_sky, "many-lights": many_lights,
          "foggy-room": foggy_room, "hair": hair, "product": product}


def sampler_line(name, spp):
    if name == "stratified":
        k = max(1, int(round(math.sqrt(spp))))
        return 'Sampler "stratified" "integer xsamples" [%d] "integer ysamples" [%d]' % (k, k)
    return 'Sampler "%s" "integer pixelsamples" [%d]' % (name, spp)


def write_kind(out, kind, res, spp):
    d = os.path.join(out, kind)
    os.makedirs(d, exist_ok=True)
    camera, world = MAKERS[kind](d)
    with open(os.path.join(d, "world.pbrt"), "w") as f:
        f.write(world + "\n")
    files = []
    for s in SAMPLERS:
        path = os.path.join(d, "%s-%s.pbrt" % (kind, s))
        with open(path, "w") as f:
            f.write("# bench/speed/make_kinds.py: %s, sampler %s\n%s\n" % (kind, s, camera))
            f.write('Film "image" "integer xresolution" [%d] "integer yresolution" [%d] "string filename" "%s.exr"\n'
                    % (res[0], res[1], kind))
            f.write(sampler_line(s, spp) + "\n")
            f.write('PixelFilter "gaussian"\n')
            f.write(INTEGRATOR.get(kind, 'Integrator "path" "integer maxdepth" [8]') + "\n")
            f.write('WorldBegin\nInclude "world.pbrt"\nWorldEnd\n')
        files.append(path)
    return files


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out")
    p.add_argument("--res", type=int, nargs=2, default=[320, 240], metavar=("W", "H"))
    p.add_argument("--spp", type=int, default=64, help="samples per pixel in the headers (default 64)")
    p.add_argument("--kinds", default=",".join(KINDS))
    a = p.parse_args(argv)
    for k in a.kinds.split(","):
        if k not in MAKERS:
            sys.exit("make_kinds.py: unknown kind %s (known: %s)" % (k, ", ".join(KINDS)))
        for f in write_kind(a.out, k, a.res, a.spp):
            print(f)


if __name__ == "__main__":
    main()
