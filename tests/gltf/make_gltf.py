#!/usr/bin/env python3
"""Writes the glTF test files of tests/gltf into a directory (stdlib only).

Usage: make_gltf.py OUTDIR

Valid files (also listed in OUTDIR/valid.txt, for the validator test):
  cornell.gltf (+ cornell.bin), cornell.glb: scenes/cornell-box.pbrt from the
      same numbers; cornell-gltfpbr.pbrt: the same box in pbrt syntax with the
      "gltfpbr" materials the loader makes of the glTF materials.
  hierarchy.gltf, instancing.gltf, indices.gltf, quantized.gltf, sparse.gltf,
  strip_fan.gltf, texture.gltf, lights.gltf, mask.gltf, defaults.gltf
Malformed files (bad-*.gltf, bad-*.glb; listed in OUTDIR/malformed.txt).
The numbers the tests check are the constants below (the tests repeat them).
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

# Component types and modes (glTF 2.0, 3.6.2 and 3.7.2).
BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
FMT = {BYTE: "b", UBYTE: "B", SHORT: "h", USHORT: "H", UINT: "I", FLOAT: "f"}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
STRIP, FAN = 5, 6
NEAREST, LINEAR = 9728, 9729
REPEAT, CLAMP, MIRROR = 10497, 33071, 33648


class Asset:
    """A glTF document with one binary buffer built up accessor by accessor."""

    def __init__(self):
        self.doc = {"asset": {"version": "2.0", "generator": "gradus tests/gltf/make_gltf.py"}}
        self.bin = bytearray()

    def add(self, key, obj):
        self.doc.setdefault(key, []).append(obj)
        return len(self.doc[key]) - 1

    def view(self, data, target=None, stride=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            v["target"] = target
        if stride:
            v["byteStride"] = stride
        self.bin += data
        return self.add("bufferViews", v)

    def accessor(self, values, ctype, atype, normalized=False, target=None, minmax=False, extra=None):
        """values: flat list; written tightly packed into a new buffer view."""
        n = NCOMP[atype]
        assert len(values) % n == 0
        data = struct.pack("<%d%s" % (len(values), FMT[ctype]), *values)
        # Elements of 1- and 2-byte vertex attributes must be 4-byte aligned (3.6.2.4).
        stride = None
        elem = len(data) // (len(values) // n) if values else 0
        if target == ARRAY_BUFFER and elem % 4:
            stride = elem + (-elem) % 4
            padded = bytearray()
            size = struct.calcsize(FMT[ctype])
            for i in range(len(values) // n):
                padded += data[i * n * size:(i + 1) * n * size] + bytes(stride - elem)
            data = bytes(padded)
        a = {"bufferView": self.view(data, target, stride), "componentType": ctype,
             "count": len(values) // n, "type": atype}
        if normalized:
            a["normalized"] = True
        if minmax:
            a["min"] = [min(values[i::n]) for i in range(n)]
            a["max"] = [max(values[i::n]) for i in range(n)]
        if extra:
            a.update(extra)
        return self.add("accessors", a)

    def positions(self, pts):
        return self.accessor(pts, FLOAT, "VEC3", target=ARRAY_BUFFER, minmax=True)

    def indices(self, idx, ctype=USHORT):
        return self.accessor(idx, ctype, "SCALAR", target=ELEMENT_ARRAY_BUFFER)

    def mesh(self, prims, name=None):
        m = {"primitives": prims}
        if name:
            m["name"] = name
        return self.add("meshes", m)

    def node(self, **kw):
        return self.add("nodes", kw)

    def scene(self, roots):
        self.doc["scenes"] = [{"nodes": roots}]
        self.doc["scene"] = 0

    def use(self, ext, required=False):
        self.doc.setdefault("extensionsUsed", [])
        if ext not in self.doc["extensionsUsed"]:
            self.doc["extensionsUsed"].append(ext)
        if required:
            self.doc.setdefault("extensionsRequired", [])
            if ext not in self.doc["extensionsRequired"]:
                self.doc["extensionsRequired"].append(ext)

    def _buffer(self, uri=None):
        b = {"byteLength": len(self.bin)}
        if uri:
            b["uri"] = uri
        return b

    def gltf_text(self, uri):
        doc = dict(self.doc)
        if self.bin:
            doc["buffers"] = [self._buffer(uri)]
        return json.dumps(doc, indent=1) + "\n"

    def write_gltf(self, path, external_bin=None):
        """Buffer as a data URI, or in `external_bin` (a file beside `path`)."""
        if not self.bin:
            uri = None
        elif external_bin:
            with open(os.path.join(os.path.dirname(path), external_bin), "wb") as f:
                f.write(self.bin)
            uri = external_bin
        else:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.bin)).decode()
        with open(path, "w") as f:
            f.write(self.gltf_text(uri))

    def glb_bytes(self):
        doc = dict(self.doc)
        if self.bin:
            doc["buffers"] = [self._buffer()]
        js = json.dumps(doc, indent=1).encode()
        js += b" " * ((-len(js)) % 4)
        binc = bytes(self.bin) + bytes((-len(self.bin)) % 4)
        out = struct.pack("<II", len(js), 0x4E4F534A) + js
        if self.bin:
            out += struct.pack("<II", len(binc), 0x004E4942) + binc
        return struct.pack("<4sII", b"glTF", 2, 12 + len(out)) + out


def png_rgba(width, height, texels):
    """8-bit RGBA PNG of rows of (r, g, b, a) tuples (filter 0, zlib)."""
    raw = bytearray()
    for y in range(height):
        raw.append(0)
        for x in range(width):
            raw += bytes(texels[y][x])

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw))) + chunk(b"IEND", b"")


def quat_y(deg):
    h = math.radians(deg) / 2
    return [0.0, math.sin(h), 0.0, math.cos(h)]


TRI = [0, 0, 0, 1, 0, 0, 0, 1, 0]

# ---------------------------------------------------------------- Cornell box
# scenes/cornell-box.pbrt's numbers.
WHITE, RED, GREEN = [0.73, 0.72, 0.69], [0.62, 0.07, 0.05], [0.13, 0.46, 0.10]
LIGHT_L = [14.0, 11.0, 7.0]
FOV = 38.0
QUAD = [0, 1, 2, 0, 2, 3]
FLOOR = [-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1]
CEILING = [-1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1]
BACK = [-1, 0, -1, 1, 0, -1, 1, 2, -1, -1, 2, -1]
GREEN_WALL = [-1, 0, -1, -1, 2, -1, -1, 2, 1, -1, 0, 1]
RED_WALL = [1, 0, -1, 1, 0, 1, 1, 2, 1, 1, 2, -1]
CUBE_P = [-.5, -.5, -.5, .5, -.5, -.5, .5, .5, -.5, -.5, .5, -.5,
          -.5, -.5, .5, .5, -.5, .5, .5, .5, .5, -.5, .5, .5]
CUBE_I = [0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
          3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5]
LIGHT_P = [-0.25, 1.99, -0.2, 0.25, 1.99, -0.2, 0.25, 1.99, 0.2, -0.25, 1.99, 0.2]
BOXES = [  # translation, rotation about y (degrees), scale
    ([-0.35, 0.6, -0.3], 18.0, [0.55, 1.2, 0.55]),
    ([0.35, 0.3, 0.3], -17.0, [0.6, 0.6, 0.6]),
]


def diffuse_material(name, rgb):
    return {"name": name, "pbrMetallicRoughness": {"baseColorFactor": rgb + [1.0], "metallicFactor": 0.0,
                                                   "roughnessFactor": 1.0}}


def cornell():
    a = Asset()
    white = a.add("materials", diffuse_material("white", WHITE))
    red = a.add("materials", diffuse_material("red", RED))
    green = a.add("materials", diffuse_material("green", GREEN))
    # Emission normalised to a factor <= 1 and a strength (KHR_materials_emissive_strength).
    strength = max(LIGHT_L)
    light = diffuse_material("light", [0.0, 0.0, 0.0])
    light["emissiveFactor"] = [c / strength for c in LIGHT_L]
    light["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
    light = a.add("materials", light)
    a.use("KHR_materials_emissive_strength")

    def quads(*qs):
        pts, idx = [], []
        for q in qs:
            idx += [4 * (len(pts) // 12) + i for i in QUAD]
            pts += q
        return {"attributes": {"POSITION": a.positions(pts)}, "indices": a.indices(idx)}

    w = quads(FLOOR, CEILING, BACK)
    w["material"] = white
    g = quads(GREEN_WALL)
    g["material"] = green
    r = quads(RED_WALL)
    r["material"] = red
    walls = a.mesh([w, g, r], "walls")
    cube = a.mesh([{"attributes": {"POSITION": a.positions(CUBE_P)}, "indices": a.indices(CUBE_I, UBYTE),
                    "material": white}], "cube")
    lq = quads(LIGHT_P)
    lq["material"] = light
    lmesh = a.mesh([lq], "ceiling light")
    children = [a.node(name="walls", mesh=walls), a.node(name="light", mesh=lmesh)]
    for i, (t, deg, s) in enumerate(BOXES):
        children.append(a.node(name=["tall box", "short box"][i], mesh=cube, translation=t, rotation=quat_y(deg),
                               scale=s))
    # pbrt-v3's LookAt view is mirrored relative to glTF's camera: the geometry
    # sits under a mirror so that the image matches scenes/cornell-box.pbrt.
    root = a.node(name="mirror", scale=[-1.0, 1.0, 1.0], children=children)
    a.add("cameras", {"name": "view", "type": "perspective",
                      "perspective": {"yfov": math.radians(FOV), "aspectRatio": 1.0, "znear": 0.01}})
    cam = a.node(name="camera", camera=0, translation=[0.0, 1.0, 3.6])
    a.scene([root, cam])
    return a


def cornell_pbrt():
    strength = max(LIGHT_L)
    L = [(c / strength) * strength for c in LIGHT_L]  # as the loader computes it

    def rgb(v):
        return " ".join(repr(float(x)) for x in v)

    def mat(name, c):
        return ('MakeNamedMaterial "%s" "string type" [ "gltfpbr" ] "rgb basecolor" [ %s ]\n'
                '    "float metallic" [ 0 ] "float roughness" [ 1 ]\n' % (name, rgb(c)))

    def mesh(p, idx):
        return ('Shape "trianglemesh" "integer indices" [ %s ]\n    "point P" [ %s ]\n'
                % (" ".join(map(str, idx)), rgb(p)))

    out = ["# Generated by tests/gltf/make_gltf.py: cornell.gltf in pbrt syntax with the\n"
           "# \"gltfpbr\" materials the glTF loader makes (scenes/cornell-box.pbrt's numbers).\n",
           "LookAt 0 1 3.6   0 1 0   0 1 0\n",
           'Camera "perspective" "float fov" [ %r ]\n' % FOV,
           'Film "image" "integer xresolution" [ 480 ] "integer yresolution" [ 480 ]\n'
           '    "string filename" [ "cornell-gltfpbr.exr" ]\n',
           "WorldBegin\n", mat("white", WHITE), mat("red", RED), mat("green", GREEN),
           'NamedMaterial "white"\n', mesh(FLOOR, QUAD), mesh(CEILING, QUAD), mesh(BACK, QUAD),
           'NamedMaterial "green"\n', mesh(GREEN_WALL, QUAD), 'NamedMaterial "red"\n', mesh(RED_WALL, QUAD),
           'NamedMaterial "white"\n']
    for t, deg, s in BOXES:
        out.append("AttributeBegin\n  Translate %s\n  Rotate %r 0 1 0\n  Scale %s\n  %sAttributeEnd\n"
                   % (rgb(t), deg, rgb(s), mesh(CUBE_P, CUBE_I)))
    out.append('AttributeBegin\n  AreaLightSource "diffuse" "rgb L" [ %s ]\n'
               '  Material "gltfpbr" "rgb basecolor" [ 0 0 0 ] "float metallic" [ 0 ] "float roughness" [ 1 ]\n'
               '  %sAttributeEnd\nWorldEnd\n' % (rgb(L), mesh(LIGHT_P, QUAD)))
    return "".join(out)


# ---------------------------------------------------------------- unit-test files
# hierarchy.gltf: root A (matrix) > B (TRS) > C (TRS), B > D (matrix); each node its own
# one-triangle mesh (mesh i = node i), so shapes come in node order.
HIER_A_MATRIX = [0.0, 0.0, -2.0, 0.0, 0.0, 3.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 5.0, -1.0, 2.0, 1.0]  # column-major
HIER_B = {"translation": [1.0, 2.0, 3.0], "rotation": [0.0, 0.0, math.sin(0.35), math.cos(0.35)],
          "scale": [2.0, 0.5, 1.5]}
HIER_C = {"translation": [-0.5, 0.25, 4.0], "rotation": [0.5, 0.5, 0.5, 0.5], "scale": [1.0, -2.0, 1.0]}
HIER_D_MATRIX = [0.0, 1.5, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 7.0, 0.0, 1.0]


def hierarchy():
    a = Asset()
    meshes = [a.mesh([{"attributes": {"POSITION": a.positions(TRI)}}]) for _ in range(4)]
    d = a.node(name="D", mesh=meshes[3], matrix=HIER_D_MATRIX)
    c = a.node(name="C", mesh=meshes[2], **HIER_C)
    b = a.node(name="B", mesh=meshes[1], children=[c, d], **HIER_B)
    root = a.node(name="A", mesh=meshes[0], matrix=HIER_A_MATRIX, children=[b])
    a.scene([root])
    return a


INST_T = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, -1.0]]


def instancing():
    a = Asset()
    m = a.mesh([{"attributes": {"POSITION": a.positions(TRI)}}])
    a.scene([a.node(mesh=m, translation=t) for t in INST_T])
    return a


# indices.gltf: mesh 0 non-indexed, meshes 1-3 indexed with u8, u16, u32.
IDX_P = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 2, 0]
IDX_I = [0, 1, 2, 0, 2, 3, 3, 2, 4]


def indices():
    a = Asset()
    prims = [{"attributes": {"POSITION": a.positions(TRI + [1, 1, 1, 2, 1, 1, 1, 2, 1])}}]
    for ct in (UBYTE, USHORT, UINT):
        prims.append({"attributes": {"POSITION": a.positions(IDX_P)}, "indices": a.indices(IDX_I, ct)})
    a.scene([a.node(mesh=a.mesh([p])) for p in prims])
    return a


# quantized.gltf (KHR_mesh_quantization): POSITION as i16 (plain integers), NORMAL as
# normalized i8, TEXCOORD_0 as normalized u16; mesh 1: POSITION as normalized u8.
Q_POS = [0, 0, 0, 1000, 0, 0, 0, -1000, 300]
Q_NRM = [0, 0, 127, 0, -128, 0, -127, 0, 0]
Q_UV = [0, 0, 65535, 0, 32768, 65535]
Q_POS2 = [0, 0, 0, 255, 0, 0, 0, 51, 255]


def quantized():
    a = Asset()
    a.use("KHR_mesh_quantization", required=True)
    p = {"attributes": {"POSITION": a.accessor(Q_POS, SHORT, "VEC3", target=ARRAY_BUFFER, minmax=True),
                        "NORMAL": a.accessor(Q_NRM, BYTE, "VEC3", normalized=True, target=ARRAY_BUFFER),
                        "TEXCOORD_0": a.accessor(Q_UV, USHORT, "VEC2", normalized=True, target=ARRAY_BUFFER)}}
    p2 = {"attributes": {"POSITION": a.accessor(Q_POS2, UBYTE, "VEC3", normalized=True, target=ARRAY_BUFFER,
                                                minmax=True)}}
    a.scene([a.node(mesh=a.mesh([p])), a.node(mesh=a.mesh([p2]))])
    return a


# sparse.gltf: mesh 0's POSITION = SPARSE_BASE with elements SPARSE_IDX replaced by
# SPARSE_VAL (u16 sparse indices); mesh 1's POSITION has no bufferView (zeros) and
# u8 sparse indices.
SPARSE_BASE = [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 2, 0, 3, 3, 0]
SPARSE_IDX = [1, 4]
SPARSE_VAL = [5, 0, 0, -1, -2, 0.5]
SPARSE2_IDX = [1, 2]
SPARSE2_VAL = [0, 0, 1, 0, 1, 1]


def sparse():
    a = Asset()

    def minmax(vals):
        return {"min": [min(vals[i::3]) for i in range(3)], "max": [max(vals[i::3]) for i in range(3)]}

    final = list(SPARSE_BASE)
    for k, i in enumerate(SPARSE_IDX):
        final[3 * i:3 * i + 3] = SPARSE_VAL[3 * k:3 * k + 3]
    pos = a.positions(SPARSE_BASE)
    acc = a.doc["accessors"][pos]
    acc.update(minmax(final))
    acc["sparse"] = {"count": len(SPARSE_IDX),
                     "indices": {"bufferView": a.view(struct.pack("<2H", *SPARSE_IDX)), "componentType": USHORT},
                     "values": {"bufferView": a.view(struct.pack("<6f", *SPARSE_VAL))}}
    final2 = [0.0] * 9
    for k, i in enumerate(SPARSE2_IDX):
        final2[3 * i:3 * i + 3] = SPARSE2_VAL[3 * k:3 * k + 3]
    iv = a.view(struct.pack("<2B", *SPARSE2_IDX))
    vv = a.view(struct.pack("<6f", *SPARSE2_VAL))
    pos2 = a.add("accessors", dict(componentType=FLOAT, count=3, type="VEC3", **minmax(final2),
                                   sparse={"count": 2, "indices": {"bufferView": iv, "componentType": UBYTE},
                                           "values": {"bufferView": vv}}))
    a.scene([a.node(mesh=a.mesh([{"attributes": {"POSITION": pos}, "indices": a.indices([0, 1, 2, 3, 4, 5])}])),
             a.node(mesh=a.mesh([{"attributes": {"POSITION": pos2}}]))])
    return a


# strip_fan.gltf: mesh 0 a non-indexed strip of 6 vertices; mesh 1 an indexed fan.
STRIP_P = [0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0, 2, 1, 0]
FAN_P = [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 1, 0]
FAN_I = [0, 1, 2, 3, 4]


def strip_fan():
    a = Asset()
    s = a.mesh([{"attributes": {"POSITION": a.positions(STRIP_P)}, "mode": STRIP}])
    f = a.mesh([{"attributes": {"POSITION": a.positions(FAN_P)}, "indices": a.indices(FAN_I), "mode": FAN}])
    a.scene([a.node(mesh=s), a.node(mesh=f)])
    return a


# texture.gltf: one 4x2 RGBA PNG (TEXELS, top row first); materials 0-4 read it as
# baseColorTexture through SAMPLERS[i] (wrapS, wrapT, magFilter); material 3 adds
# KHR_texture_transform TT; material 4's baseColorFactor is TEX_FACTOR.
TEXELS = [[(255, 0, 0, 255), (0, 255, 0, 128), (0, 0, 255, 64), (255, 255, 255, 0)],
          [(10, 20, 30, 200), (40, 50, 60, 100), (70, 80, 90, 50), (100, 110, 120, 25)]]
SAMPLERS = [(REPEAT, REPEAT, NEAREST), (CLAMP, CLAMP, LINEAR), (MIRROR, MIRROR, LINEAR), (REPEAT, CLAMP, LINEAR),
            (MIRROR, REPEAT, NEAREST)]
TT = {"offset": [0.25, -0.5], "rotation": 0.3, "scale": [2.0, 0.5]}
TEX_FACTOR = [0.5, 0.25, 1.0, 1.0]


def texture_file():
    a = Asset()
    png = png_rgba(4, 2, TEXELS)
    a.add("images", {"mimeType": "image/png", "bufferView": a.view(png)})
    a.use("KHR_texture_transform")
    uv = a.accessor([0, 0, 1, 0, 0, 1], FLOAT, "VEC2", target=ARRAY_BUFFER)
    pos = a.positions(TRI)
    prims = []
    for i, (ws, wt, mag) in enumerate(SAMPLERS):
        a.add("samplers", {"wrapS": ws, "wrapT": wt, "magFilter": mag, "minFilter": mag})
        a.add("textures", {"source": 0, "sampler": i})
        info = {"index": i}
        if i == 3:
            info["extensions"] = {"KHR_texture_transform": TT}
        pbr = {"baseColorTexture": info, "metallicFactor": 0.0}
        if i == 4:
            pbr["baseColorFactor"] = TEX_FACTOR
        a.add("materials", {"pbrMetallicRoughness": pbr})
        prims.append({"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": i})
    a.scene([a.node(mesh=a.mesh(prims))])
    return a


# lights.gltf (KHR_lights_punctual): point at (0, 2, 0); spot at (0, 3, 0) pointing
# down (-90 degrees about x turns -Z to -Y); directional along the node's -Z turned
# by LIGHT_DIR_Q.
LIGHT_COLOR = [1.0, 0.5, 0.25]
POINT_I, SPOT_I, DIR_I = 20.0, 50.0, 3.0
SPOT_INNER, SPOT_OUTER = 0.3, 0.6
LIGHT_DIR_Q = [math.sin(0.4), 0.0, 0.0, math.cos(0.4)]


def lights():
    a = Asset()
    a.use("KHR_lights_punctual")
    ls = [{"type": "point", "color": LIGHT_COLOR, "intensity": POINT_I, "name": "point"},
          {"type": "spot", "color": LIGHT_COLOR, "intensity": SPOT_I, "name": "spot",
           "spot": {"innerConeAngle": SPOT_INNER, "outerConeAngle": SPOT_OUTER}},
          {"type": "directional", "color": LIGHT_COLOR, "intensity": DIR_I, "name": "sun"}]
    a.doc["extensions"] = {"KHR_lights_punctual": {"lights": ls}}
    h = math.sqrt(0.5)

    def ext(i):
        return {"KHR_lights_punctual": {"light": i}}

    a.scene([a.node(name="point", translation=[0.0, 2.0, 0.0], extensions=ext(0)),
             a.node(name="spot", translation=[0.0, 3.0, 0.0], rotation=[-h, 0.0, 0.0, h], extensions=ext(1)),
             a.node(name="sun", rotation=LIGHT_DIR_Q, extensions=ext(2))])
    return a


# mask.gltf: material 0 MASK (cutoff MASK_CUTOFF) with a texture with alpha; material 1
# MASK with a constant alpha below the default cutoff 0.5; material 2 BLEND.
MASK_CUTOFF = 0.4


def mask():
    a = Asset()
    png = png_rgba(4, 2, TEXELS)
    a.add("images", {"mimeType": "image/png", "bufferView": a.view(png)})
    a.add("textures", {"source": 0})
    a.add("materials", {"alphaMode": "MASK", "alphaCutoff": MASK_CUTOFF,
                        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    a.add("materials", {"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.2]}})
    a.add("materials", {"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5]}})
    uv = a.accessor([0, 0, 1, 0, 0, 1], FLOAT, "VEC2", target=ARRAY_BUFFER)
    pos = a.positions(TRI)
    prims = [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "material": i} for i in range(3)]
    a.scene([a.node(mesh=a.mesh(prims))])
    return a


def defaults():
    a = Asset()
    a.scene([a.node(mesh=a.mesh([{"attributes": {"POSITION": a.positions(TRI)}}]))])
    return a


# ---------------------------------------------------------------- malformed files
def small():
    """A valid one-triangle document to break."""
    a = Asset()
    a.scene([a.node(mesh=a.mesh([{"attributes": {"POSITION": a.positions(TRI)},
                                  "indices": a.indices([0, 1, 2])}]))])
    return a


def malformed(out):
    files = {}
    glb = small().glb_bytes()
    # Header length larger than the file.
    files["bad-length.glb"] = glb[:8] + struct.pack("<I", len(glb) + 16) + glb[12:]
    # Cut inside the JSON chunk, header length fixed to the cut size.
    cut = 20 + 10
    files["bad-cut-json.glb"] = glb[:8] + struct.pack("<I", cut) + glb[12:cut]
    # Cut inside the BIN chunk, header length fixed to the cut size.
    cut = len(glb) - 8
    files["bad-cut-bin.glb"] = glb[:8] + struct.pack("<I", cut) + glb[12:cut]

    def broken(name, edit):
        a = small()
        edit(a.doc)
        files[name] = a.gltf_text("data:application/octet-stream;base64," + base64.b64encode(bytes(a.bin)).decode())

    broken("bad-count.gltf", lambda d: d["accessors"][0].update(count=1000))
    broken("bad-componenttype.gltf", lambda d: d["accessors"][0].update(componentType=5130))
    broken("bad-type.gltf", lambda d: d["accessors"][0].update(type="VEC2"))
    # Index 7 in a 3-vertex primitive: the index buffer is rewritten below.
    a = small()
    view = a.doc["bufferViews"][a.doc["accessors"][1]["bufferView"]]
    a.bin[view["byteOffset"]:view["byteOffset"] + 6] = struct.pack("<3H", 0, 7, 2)
    files["bad-index.gltf"] = a.gltf_text("data:application/octet-stream;base64," +
                                          base64.b64encode(bytes(a.bin)).decode())
    a = small()
    files["bad-missing-buffer.gltf"] = a.gltf_text("missing-buffer.bin")
    broken("bad-extension.gltf", lambda d: d.update(extensionsUsed=["EXT_not_a_real_extension"],
                                                    extensionsRequired=["EXT_not_a_real_extension"]))

    def cycle(d):
        d["nodes"].append({"name": "loop", "children": [0]})
        d["nodes"][0]["children"] = [1]
    broken("bad-cycle.gltf", cycle)
    text = small().gltf_text(None)
    files["bad-json.gltf"] = text[:text.index('"nodes"')] + '"nodes": [ { "mesh": 0, } ,\n' + text[text.index('"nodes"'):]
    for name, data in files.items():
        mode = "wb" if isinstance(data, bytes) else "w"
        with open(os.path.join(out, name), mode) as f:
            f.write(data)
    return sorted(files)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make_gltf.py OUTDIR")
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    box = cornell()
    box.write_gltf(os.path.join(out, "cornell.gltf"), external_bin="cornell.bin")
    with open(os.path.join(out, "cornell.glb"), "wb") as f:
        f.write(box.glb_bytes())
    with open(os.path.join(out, "cornell-gltfpbr.pbrt"), "w") as f:
        f.write(cornell_pbrt())
    valid = ["cornell.gltf", "cornell.glb"]
    for name, make in [("hierarchy", hierarchy), ("instancing", instancing), ("indices", indices),
                       ("quantized", quantized), ("sparse", sparse), ("strip_fan", strip_fan),
                       ("texture", texture_file), ("lights", lights), ("mask", mask), ("defaults", defaults)]:
        make().write_gltf(os.path.join(out, name + ".gltf"))
        valid.append(name + ".gltf")
    bad = malformed(out)
    with open(os.path.join(out, "valid.txt"), "w") as f:
        f.write("\n".join(valid) + "\n")
    with open(os.path.join(out, "malformed.txt"), "w") as f:
        f.write("\n".join(bad) + "\n")


if __name__ == "__main__":
    main()
