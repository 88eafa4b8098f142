"""Small helpers for the G-VCM benchmark scene generators (bench/gvcm/make_*.py).

Writes pbrt-v3 scene text: closed triangle meshes with outward-facing triangles
(right-handed winding seen from outside, so pbrt-v3's and Gradus's geometric
normals point out of glass solids), surfaces of revolution with per-vertex
normals, and the command line every generator shares (OUTDIR, --res WxH).
"""

import argparse
import math
import os


def parse_args(name, doc):
    ap = argparse.ArgumentParser(description=doc)
    ap.add_argument("outdir", help="directory the scene is written to (created if missing)")
    ap.add_argument("--res", default="1280x720", help="film resolution WxH (default 1280x720)")
    ap.add_argument("--spp", type=int, default=16, help="the Sampler's pixelsamples (default 16)")
    a = ap.parse_args()
    try:
        w, h = (int(v) for v in a.res.lower().split("x"))
        if w <= 0 or h <= 0:
            raise ValueError
    except ValueError:
        ap.error("--res must be WxH with positive integers, got %r" % a.res)
    a.width, a.height = w, h
    a.path = os.path.join(a.outdir, name + ".pbrt")
    return a


def fmt(x):
    s = "%.6f" % x
    s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(a):
    l = math.sqrt(dot(a, a))
    return (a[0] / l, a[1] / l, a[2] / l)


class Mesh:
    """Indexed triangles; add_tri orients each triangle so that its
    right-handed normal agrees with `out` (a direction pointing outside)."""

    def __init__(self):
        self.P = []
        self.N = []
        self.idx = []

    def vertex(self, p, n=None):
        self.P.append(tuple(p))
        if n is not None:
            self.N.append(tuple(n))
        return len(self.P) - 1

    def add_tri(self, a, b, c, out):
        pa, pb, pc = self.P[a], self.P[b], self.P[c]
        n = cross(sub(pb, pa), sub(pc, pa))
        if dot(n, n) <= 1e-30:
            return  # degenerate (a pole's zero-length edge)
        if dot(n, out) < 0:
            b, c = c, b
        self.idx += [a, b, c]

    def text(self):
        s = ['Shape "trianglemesh" "integer indices" [%s]\n' % " ".join(str(i) for i in self.idx)]
        s.append('  "point P" [%s]\n' % "  ".join(" ".join(fmt(c) for c in p) for p in self.P))
        if self.N:
            assert len(self.N) == len(self.P)
            s.append('  "normal N" [%s]\n' % "  ".join(" ".join(fmt(c) for c in n) for n in self.N))
        return "".join(s)


def box(x0, y0, z0, x1, y1, z1):
    """A closed axis-aligned box, 12 outward triangles (watertight)."""
    m = Mesh()
    lo, hi = (min(x0, x1), min(y0, y1), min(z0, z1)), (max(x0, x1), max(y0, y1), max(z0, z1))
    c = [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    for p in c:
        m.vertex(p)
    centre = tuple((lo[i] + hi[i]) / 2 for i in range(3))
    faces = [(0, 2, 6, 4), (1, 3, 7, 5), (0, 1, 5, 4), (2, 3, 7, 6), (0, 1, 3, 2), (4, 5, 7, 6)]
    for f in faces:
        fc = tuple(sum(c[i][k] for i in f) / 4 for k in range(3))
        out = sub(fc, centre)
        m.add_tri(f[0], f[1], f[2], out)
        m.add_tri(f[0], f[2], f[3], out)
    return m


def quad(p0, p1, p2, p3, out):
    """A planar quad (two triangles) facing `out`."""
    m = Mesh()
    for p in (p0, p1, p2, p3):
        m.vertex(p)
    m.add_tri(0, 1, 2, out)
    m.add_tri(0, 2, 3, out)
    return m


def lathe(profile, segments, centre=(0, 0, 0), smooth=True, corner_deg=50):
    """Surface of revolution about the +y axis through `centre`.

    profile: [(r, y), ...] in order such that the solid lies to the left of the
    direction of travel in the (r, y) half-plane (e.g. from the axis at the
    bottom outwards, up the outside, back down the inside to the axis). If the
    first and last points lie on the axis (r = 0) the surface is closed
    (watertight): those rings collapse to single pole vertices. Per-vertex
    normals (smooth), split at profile corners sharper than corner_deg.
    """
    cx, cy, cz = centre
    n = len(profile)
    seg_n = []
    for i in range(n - 1):
        (r0, y0), (r1, y1) = profile[i], profile[i + 1]
        dr, dy = r1 - r0, y1 - y0
        l = math.hypot(dr, dy)
        seg_n.append((dy / l, -dr / l))  # outward normal in the (r, y) plane
    m = Mesh()
    rings = []  # per profile point: list of (vertex index for the segment before, for the segment after)

    def ring(r, y, nr, ny):
        if r == 0:
            v = m.vertex((cx, cy + y, cz), (0, 1 if ny > 0 else -1, 0) if smooth else None)
            return [v] * segments
        out = []
        for k in range(segments):
            phi = 2 * math.pi * k / segments
            cp, sp = math.cos(phi), math.sin(phi)
            nn = (nr * cp, ny, nr * sp) if smooth else None
            out.append(m.vertex((cx + r * cp, cy + y, cz + r * sp), nn))
        return out

    for i, (r, y) in enumerate(profile):
        before = seg_n[i - 1] if i > 0 else seg_n[0]
        after = seg_n[i] if i < n - 1 else seg_n[-1]
        cosang = before[0] * after[0] + before[1] * after[1]
        if cosang < math.cos(math.radians(corner_deg)) and r > 0:
            rings.append((ring(r, y, *before), ring(r, y, *after)))
        else:
            a = (before[0] + after[0], before[1] + after[1])
            l = math.hypot(*a)
            a = (a[0] / l, a[1] / l) if l > 0 else after
            shared = ring(r, y, *a)
            rings.append((shared, shared))
    for i in range(n - 1):
        A, B = rings[i][1], rings[i + 1][0]
        nr, ny = seg_n[i]
        rm = (profile[i][0] + profile[i + 1][0]) / 2
        for k in range(segments):
            k1 = (k + 1) % segments
            phi = 2 * math.pi * (k + 0.5) / segments
            out = (nr * math.cos(phi), ny, nr * math.sin(phi))
            if rm == 0:
                continue
            m.add_tri(A[k], A[k1], B[k1], out)
            m.add_tri(A[k], B[k1], B[k], out)
    return m


def header(a, lookat, fov, integrator_depth, comment):
    lines = ["# " + l for l in comment.strip().splitlines()]
    lines += [
        '# Written by bench/gvcm/%s; regenerate rather than edit.' % os.path.basename(a.script),
        'Integrator "bdpt" "integer maxdepth" [%d]' % integrator_depth,
        'Sampler "sobol" "integer pixelsamples" [%d]' % a.spp,
        'PixelFilter "box"',
        'Film "image" "integer xresolution" [%d] "integer yresolution" [%d] "string filename" ["%s.exr"]'
        % (a.width, a.height, a.name),
        'LookAt %s' % "  ".join(" ".join(fmt(c) for c in v) for v in lookat),
        'Camera "perspective" "float fov" [%s]' % fmt(fov),
        'WorldBegin',
    ]
    return "\n".join(lines) + "\n"


def block(material, *meshes, extra=""):
    s = "AttributeBegin\n" + extra + material + "\n"
    for m in meshes:
        s += m.text()
    return s + "AttributeEnd\n"


def sphere_light(centre, radius, L):
    return ("AttributeBegin\n"
            "Translate %s\n" % " ".join(fmt(c) for c in centre) +
            'AreaLightSource "diffuse" "rgb L" [%s]\n' % " ".join(fmt(c) for c in L) +
            'Material "matte" "rgb Kd" [0 0 0]\n'
            'Shape "sphere" "float radius" [%s]\n' % fmt(radius) +
            "AttributeEnd\n")


def write(a, text):
    os.makedirs(a.outdir, exist_ok=True)
    with open(a.path, "w") as f:
        f.write(text)
    print(a.path)
