"""Stress scenes of bench/stress/run.py, generated as pbrt-v3 text.

Every scene is small (width `size`, default 32 px) and has a check (see run.py):
  Exact(v)      every pixel's expectation is v (per channel), e.g. a furnace
  Bound(v)      every pixel's expectation is at most v (energy conservation)
  Zero()        every pixel is exactly 0 (nothing can reach the camera)
  Map(f)        pixel (x, y) expects f(x, y, w, h) (None: not checked)
  Same(name)    same image expectation as scene `name`
  Sum(names)    expectation is the sum of the scenes `names` (lights are additive)
  None          only the crash / timeout / NaN-Inf checks

pbrt-v3's classic integrators do not estimate full light transport, so a scene
holds one check per kind of estimate (check_for):
  full       every other integrator: the scene's `check`
  direct     whitted, directlighting: emission seen directly or through specular
             chains plus direct light (one scattering vertex), at any maxdepth
             (theirs bounds the specular recursion only)
  occlusion  ambientocclusion: per pixel integral of V(wi) cos over the hemisphere
             of the first hit (pi unoccluded, 0 for a camera ray that escapes);
             no radiance at all, so only what occlusion alone decides is checked

"White furnace" scenes: a uniform environment of radiance 1 and only lossless
surfaces (matte Kd 1, smooth glass): radiance 1 everywhere is the solution of
the rendering equation, so every pixel expects exactly 1 whatever the
geometry or the camera (up to paths still bouncing at maxdepth 100, which the
open geometry here makes negligible).
"""

import math


class Exact:
    def __init__(self, value, note=""):
        self.value = value if isinstance(value, (list, tuple)) else [value] * 3
        self.note = note

    def describe(self):
        v = self.value
        s = "%.6g" % v[0] if v[0] == v[1] == v[2] else "[%s]" % " ".join("%.6g" % x for x in v)
        return ("= %s %s" % (s, self.note)).strip()


class Bound:
    def __init__(self, value, note=""):
        self.value = [value] * 3
        self.note = note

    def describe(self):
        return ("<= %.6g %s" % (self.value[0], self.note)).strip()


class Zero:
    def describe(self):
        return "= 0 (every pixel)"


class Map:
    def __init__(self, fn, note):
        self.fn = fn
        self.note = note

    def describe(self):
        return self.note


class Same:
    def __init__(self, other):
        self.other = other

    def describe(self):
        return "= %s" % self.other


class Sum:
    def __init__(self, others):
        self.others = list(others)

    def describe(self):
        return "= " + " + ".join(self.others)


class Refused:
    """Hostile input outside the renderer's range: expected to fail with exit 1
    and a located error (file:line:col) whose text contains `reason`."""

    def __init__(self, reason):
        self.reason = reason

    def describe(self):
        return "refused: %s" % self.reason


# Integrators whose estimate is not full light transport: name -> kind (see above).
ESTIMATE_KIND = {"whitted": "direct", "directlighting": "direct", "ambientocclusion": "occlusion"}
AO_BOUND = Bound(math.pi, "(occlusion: integral of V cos <= pi)")
DIRECT_BOUND = Bound(1, "(direct light only, white furnace)")
KEEP = object()  # Scene(direct=...): the same check as for full transport


def default_occlusion_check(check):
    """Occlusion keeps the checks decided by geometry alone: nothing visible (Zero),
    refused input, and Same (occlusion is scale-invariant); otherwise it is only
    bounded by pi. Exact radiance, strip radiance (Map) and light sums (Sum) are
    radiance statements and do not apply."""
    if check is None or isinstance(check, (Zero, Refused, Same)):
        return check
    return AO_BOUND


class Scene:
    """One stress scene. `world(size)` returns the text between WorldBegin and
    WorldEnd; the header (camera, film, sampler, integrator) is made here.
    `direct` / `occlusion`: the checks for those kinds of estimate (check_for)."""

    def __init__(self, name, about, world, check=None, maxdepth=5, eye=(0, 0, 0), look=(0, 0, 1),
                 up=(0, 1, 0), fov=60, lens=None, width=None, height=None, direct=KEEP, occlusion=KEEP,
                 limits=None):
        self.name = name
        self.about = about
        self.world = world
        self.check = check
        self.checks = dict(full=check, direct=check if direct is KEEP else direct,
                           occlusion=default_occlusion_check(check) if occlusion is KEEP else occlusion)
        # Known limitations: integrator spec (exactly, parameters included) -> why its energy
        # check cannot pass here; the cell still fails on a crash, timeout or NaN/Inf.
        self.limits = dict(limits or {})
        self.maxdepth = maxdepth
        self.eye, self.look, self.up, self.fov = eye, look, up, fov
        self.lens = lens  # (lensradius, focaldistance)
        self.width, self.height = width, height  # fixed film size (None: size x size)

    def resolution(self, size):
        return (self.width or size), (self.height or size)

    def check_for(self, integrator):
        """The check for integrator NAME (parameters stripped)."""
        return self.checks[ESTIMATE_KIND.get(integrator, "full")]

    def text(self, integrator, size, spp, maxdepth=True):
        """maxdepth False: the integrator has no maxdepth parameter (it is left out)."""
        w, h = self.resolution(size)
        cam = '"float fov" [ %s ]' % num(self.fov)
        if self.lens:
            cam += ' "float lensradius" [ %s ] "float focaldistance" [ %s ]' % (num(self.lens[0]),
                                                                                 num(self.lens[1]))
        return "\n".join([
            "# bench/stress scene %s: %s" % (self.name, self.about),
            "LookAt %s  %s  %s" % (vec(self.eye), vec(self.look), vec(self.up)),
            'Camera "perspective" %s' % cam,
            'Sampler "random" "integer pixelsamples" [ %d ]' % spp,
            # Box filter of half-width 0.5: a sample counts in its own pixel only, so pixels are
            # independent and the per-pixel spread gives the noise of a mean.
            'PixelFilter "box" "float xwidth" [ 0.5 ] "float ywidth" [ 0.5 ]',
            'Film "image" "integer xresolution" [ %d ] "integer yresolution" [ %d ] '
            '"string filename" [ "%s.exr" ]' % (w, h, self.name),
            ('Integrator "%s" "integer maxdepth" [ %d ]' % (integrator, self.maxdepth) if maxdepth
             else 'Integrator "%s"' % integrator),
            "WorldBegin",
            self.world(size).strip(),
            "WorldEnd",
            ""])


def num(x):
    return repr(float(x)) if not float(x).is_integer() or abs(x) >= 1e15 else str(int(x))


def vec(v):
    return " ".join(num(x) for x in v)


def rgb(v):
    v = v if isinstance(v, (list, tuple)) else [v] * 3
    return "[ %s ]" % vec(v)


def quad(p0, p1, p2, p3):
    """Two triangles p0 p1 p2, p0 p2 p3 (normal by the right-hand rule)."""
    return ('Shape "trianglemesh" "integer indices" [ 0 1 2 0 2 3 ] "point P" [ %s ]'
            % "  ".join(vec(p) for p in (p0, p1, p2, p3)))


def matte(kd):
    return 'Material "matte" "rgb Kd" %s' % rgb(kd)


ENV = 'LightSource "infinite" "rgb L" [ 1 1 1 ]'
WHITE = matte(1)
GROUND = 'Shape "disk" "float radius" [ 100000 ]'  # z = 0, normal +z


def attr(*lines):
    return "\n".join(["AttributeBegin"] + ["  " + l for l in lines] + ["AttributeEnd"])


# ---------------------------------------------------------------- furnace

def furnace(depth, le, rho):
    """Camera inside a closed sphere that is a diffuse emitter Le with albedo rho:
    every pixel expects Le * sum_{k=0}^{maxdepth} rho^k (maxdepth = bounces)."""
    le3 = le if isinstance(le, list) else [le] * 3
    rho3 = rho if isinstance(rho, list) else [rho] * 3
    value = [l * sum(r ** k for k in range(depth + 1)) for l, r in zip(le3, rho3)]
    # Direct light only: Le seen plus Le rho reflected once, whatever maxdepth.
    direct = [l * (1 + r) for l, r in zip(le3, rho3)]

    def world(size):
        return attr("ReverseOrientation", 'AreaLightSource "diffuse" "rgb L" %s' % rgb(le3),
                    matte(rho3), 'Shape "sphere" "float radius" [ 1 ]')

    return Scene("furnace_d%d" % depth,
                 "closed emitting sphere, Le=%s, albedo %s, maxdepth %d" % (le, rho, depth), world,
                 Exact(value, "(Le sum rho^k)"), maxdepth=depth, eye=(0.3, 0.2, -0.4),
                 look=(0.5, -0.3, 1), direct=Exact(direct, "(Le (1 + rho), direct only)"),
                 occlusion=Zero())  # closed: every occlusion ray hits the sphere


# ---------------------------------------------------------------- white furnace scenes

def sphere_on_ground(extra=""):
    def world(size):
        return "\n".join([ENV, WHITE, GROUND,
                          attr("Translate 0 0 0.5", 'Shape "sphere" "float radius" [ 0.5 ]'), extra])
    return world


def glass_world(index, roughness=None):
    params = '"float index" [ %s ]' % num(index)
    if roughness is not None:
        params += (' "float uroughness" [ %s ] "float vroughness" [ %s ] "bool remaproughness" "false"'
                   % (num(roughness), num(roughness)))

    def world(size):
        return "\n".join([ENV, WHITE, GROUND,
                          attr('Material "glass" %s' % params, "Translate 0 0 0.6",
                               'Shape "sphere" "float radius" [ 0.5 ]')])
    return world


def metal_world(roughness):
    def world(size):
        return "\n".join([ENV, WHITE, GROUND,
                          attr('Material "metal" "float roughness" [ %s ] "bool remaproughness" "false"'
                               % num(roughness), "Translate 0 0 0.5",
                               'Shape "sphere" "float radius" [ 0.5 ]')])
    return world


def degenerate_world(size):
    tris = [
        # collinear (zero area), coincident vertices, a 1e-9-wide needle, a 1e-12 triangle
        "0 0 0.5  0.5 0 0.5  1 0 0.5",
        "-0.5 0.2 0.3  -0.5 0.2 0.3  -0.5 0.2 0.3",
        "-0.6 -0.2 0.2  0.6 -0.2 0.2  0 -0.2 0.200000001",
        "0.1 0.1 0.4  0.100000000001 0.1 0.4  0.1 0.100000000001 0.4",
    ]
    lines = [ENV, WHITE, GROUND]
    for t in tris:
        lines.append('Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point P" [ %s ]' % t)
    # One mesh mixing a proper triangle with degenerate ones (shared vertices).
    lines.append('Shape "trianglemesh" "integer indices" [ 0 1 2  0 0 1  2 2 2  0 1 3 ] '
                 '"point P" [ -0.3 0.4 0.1  0.3 0.4 0.1  0 0.4 0.6  0.6 0.4 0.1 ]')
    # Zero-area emitters (collinear, and all vertices equal): no power, no visible area.
    lines.append(attr('AreaLightSource "diffuse" "rgb L" [ 1000000 1000000 1000000 ]',
                      'Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point P" [ -1 0.5 0.3  0 0.5 0.3  1 0.5 0.3 ]',
                      'Shape "trianglemesh" "integer indices" [ 0 1 2 ] "point P" [ 0.2 -0.5 0.3  0.2 -0.5 0.3  0.2 -0.5 0.3 ]'))
    return "\n".join(lines)


def coincident_world(size):
    q = lambda z, flip=False: quad(*([(-0.5, -0.5, z), (0.5, -0.5, z), (0.5, 0.5, z), (-0.5, 0.5, z)][::(-1 if flip else 1)]))
    return "\n".join([
        ENV, WHITE, GROUND,
        # A quad on the ground, two coincident quads of opposite winding, and quads 1e-7 and 1e-4 above.
        q(0), q(0.3), q(0.3, flip=True), q(0.3 + 1e-7), q(0.3 + 1e-4),
        # Coincident spheres and one 1e-6 larger around them.
        attr("Translate 0.8 0.6 0.4", 'Shape "sphere" "float radius" [ 0.3 ]',
             'Shape "sphere" "float radius" [ 0.3 ]', 'Shape "sphere" "float radius" [ 0.300001 ]'),
    ])


def closed_box_world(size):
    return "\n".join([
        ENV, WHITE,
        'Shape "trianglemesh" "point P" [ -1 -1 -1  1 -1 -1  1 1 -1  -1 1 -1  -1 -1 1  1 -1 1  1 1 1  -1 1 1 ] '
        '"integer indices" [ 0 2 1  0 3 2  4 5 6  4 6 7  0 1 5  0 5 4  3 6 2  3 7 6  0 4 7  0 7 3  1 2 6  1 6 5 ]'])


def closed_sphere_world(size):
    return "\n".join([ENV, WHITE, 'Shape "sphere" "float radius" [ 1 ]'])


# ---------------------------------------------------------------- emitters side by side

BAND_RADIANCE = [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e9, 1e12]
BAND_ROWS = 4  # film rows per band; the film is 32 x (7 * 4): wider than high, so fov spans y


def bands_world(size):
    # Camera at the origin looking at +z with fov 90 on the 28 rows: the wall z = 1
    # spans y in [-1, 1]; band i (from the top) covers rows 4i .. 4i+3.
    n = len(BAND_RADIANCE)
    lines = []
    for i, le in enumerate(BAND_RADIANCE):
        y1 = 1 - 2.0 * i / n
        y0 = 1 - 2.0 * (i + 1) / n
        # Normal -z, towards the camera.
        lines.append(attr('AreaLightSource "diffuse" "rgb L" %s' % rgb(le), matte(0.5),
                          quad((-4, y0, 1), (-4, y1, 1), (4, y1, 1), (4, y0, 1))))
    return "\n".join(lines)


def bands_expect(x, y, w, h):
    band, row = divmod(y, BAND_ROWS)
    if row in (0, BAND_ROWS - 1):
        return None  # boundary rows: samples near the band edge; not checked
    return [BAND_RADIANCE[band]] * 3


# ---------------------------------------------------------------- tiny bright and huge dim light

def lights_world(tiny, huge):
    def world(size):
        # Black emitters: light reflected between the two lights would break additivity.
        lines = [matte(0.5), quad((-10, -10, 0), (10, -10, 0), (10, 10, 0), (-10, 10, 0)), matte(0)]
        if tiny:  # radius 1e-3, radiance 1e5: intensity pi * 1e-1
            lines.append(attr('AreaLightSource "diffuse" "rgb L" [ 100000 100000 100000 ]',
                              "Translate 0.2 0.1 1", 'Shape "sphere" "float radius" [ 0.001 ]'))
        if huge:  # 100 x 100 at height 10, radiance 1e-3
            lines.append(attr('AreaLightSource "diffuse" "rgb L" [ 0.001 0.001 0.001 ] "bool twosided" "true"',
                              quad((-50, -50, 10), (50, -50, 10), (50, 50, 10), (-50, 50, 10))))
        return "\n".join(lines)
    return world


# ---------------------------------------------------------------- extreme scales

def scaled_box(scale):
    def world(size):
        s = num(scale)
        return "\n".join([
            "Scale %s %s %s" % (s, s, s),
            matte([0.7, 0.7, 0.7]),
            quad((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)),      # floor
            quad((-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)),      # ceiling
            quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)),    # back
            attr(matte([0.6, 0.1, 0.1]), quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1))),
            attr(matte([0.1, 0.5, 0.1]), quad((-1, 0, -1), (-1, 2, -1), (-1, 2, 1), (-1, 0, 1))),
            attr('Material "metal" "float roughness" [ 0.05 ]', "Translate -0.4 0.4 -0.2",
                 'Shape "sphere" "float radius" [ 0.4 ]'),
            attr('Material "glass"', "Translate 0.45 0.3 0.3", 'Shape "sphere" "float radius" [ 0.3 ]'),
            attr('AreaLightSource "diffuse" "rgb L" [ 4 4 4 ]', matte(0),
                 quad((-0.5, 1.99, -0.5), (0.5, 1.99, -0.5), (0.5, 1.99, 0.5), (-0.5, 1.99, 0.5))),
        ])
    return world


def scale_scene(scale, label):
    check = None if scale == 1 else Same("scale_1")
    return Scene("scale_%s" % label, "box with area light, metal and glass spheres at scene units %s" % label,
                 scaled_box(scale), check, eye=(0, scale * 1.6, scale * 3),
                 look=(0, scale * 0.6, 0), fov=45)  # the light is out of view


# ---------------------------------------------------------------- the list

def empty_world(size):
    return ""


def env_only_world(size):
    return ENV


# Metropolis with pbrt-v3's estimator on strips 1e-6 .. 1e12: unbiased, but the per-pixel
# ratio statistic weighs the 1e-6 strip 1e18 times the 1e12 one, and a strip gets its
# expectation almost only from chain states on it, whose stationary probability is about
# its share of the image luminance (1e-3 / 7 for the 1e9 strip, 1e-18 / 7 for the dimmest).
# Without such states a dim strip receives only the large-step proposals, weighted by the
# bright current state: p_large / 7 = 0.043 of its radiance (measured: 0.03 .. 0.05). No
# feasible run visits them, and the pixel spread cannot show the missing mass, so the z is
# meaningless. gmlt's reconstructions also spread the bright strip's Metropolis noise (pixels
# 1e11 .. 2e12 at 4 spp) into the dim strips (1e9 .. 3e10 absolute) with the primal's exact
# image mean. pmlt is the same Metropolis case (0.33 .. 0.66, z -1.0 .. -5.0 over seeds).
# mlt[largestepmis=true] (large steps also as independent samples) is checked.
METROPOLIS_STRIPS = {
    "mlt": "pbrt-v3's Metropolis estimator: dim strips need chain states of probability down "
           "to 1e-18 (README.md, known limitations)",
    "pmlt": "path-space Metropolis, the same as mlt's (README.md, known limitations)",
    "gmlt": "Metropolis primal as mlt's, reconstructions spread the 1e12 strip's noise into the "
            "dim strips (README.md, known limitations)",
}

SPHERE_VIEW = dict(eye=(0, -3, 1.2), look=(0, 0, 0.4), up=(0, 0, 1), fov=50)


def all_scenes():
    wf = "(white furnace)"
    scenes = [
        furnace(0, 0.5, 0.5),
        furnace(1, 0.5, 0.5),
        furnace(5, [1.0, 0.5, 0.25], [0.8, 0.5, 0.3]),
        furnace(1000, 0.5, 0.5),
        Scene("empty", "no shapes, no lights", empty_world, Zero()),
        Scene("empty_env", "no shapes, uniform environment 1", env_only_world, Exact(1, wf), occlusion=Zero()),
        Scene("grazing", "camera 1e-5 above a 1e5-radius ground, looking along it; an edge-on quad",
              lambda size: "\n".join([ENV, WHITE, GROUND,
                                      quad((3, 0, 0), (8, 0, 0), (8, 0, 2), (3, 0, 2))]),
              Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, eye=(0, 0, 1e-5), look=(1, 0, 1e-5), up=(0, 0, 1), fov=30),
        Scene("env_1e36", "white furnace in an environment of radiance 1e36 (float max 3.4e38)",
              lambda size: sphere_on_ground()(size).replace(ENV, 'LightSource "infinite" "rgb L" [ 1e36 1e36 1e36 ]'),
              Exact(1e36, wf), maxdepth=100, direct=Bound(1e36, "(direct light only, white furnace)"),
              **SPHERE_VIEW),
        Scene("far_camera", "camera 1e19 away from a unit sphere (Embree takes |ray origin| < 1.8e18)",
              sphere_on_ground(), Refused("1e15 scene units"), maxdepth=100, eye=(0, -1e19, 0.5), look=(0, 0, 0.5),
              up=(0, 0, 1), fov=30),
        Scene("degenerate_tris", "zero-area, coincident-vertex, needle and 1e-12 triangles; zero-area emitters",
              degenerate_world, Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, eye=(0.2, -2.5, 1.2), look=(0, 0, 0.3),
              up=(0, 0, 1), fov=50),
        Scene("coincident", "coincident and 1e-7/1e-4-apart quads, coincident and 1e-6-apart spheres",
              coincident_world, Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, eye=(0.3, -2.2, 1.5), look=(0.2, 0.2, 0.3),
              up=(0, 0, 1), fov=55),
        Scene("lens_zero", "thin lens, lensradius 0 (pinhole), focaldistance 1e-6",
              sphere_on_ground(), Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, lens=(0, 1e-6), **SPHERE_VIEW),
        Scene("lens_tiny", "thin lens, lensradius 1e-12, focaldistance 3.2",
              sphere_on_ground(), Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, lens=(1e-12, 3.2), **SPHERE_VIEW),
        Scene("lens_huge", "thin lens, lensradius 1e3, focaldistance 3.2",
              sphere_on_ground(), Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, lens=(1e3, 3.2), **SPHERE_VIEW),
        Scene("lens_focus_near", "thin lens, lensradius 0.5, focaldistance 1e-6",
              sphere_on_ground(), Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, lens=(0.5, 1e-6), **SPHERE_VIEW),
        Scene("lens_focus_far", "thin lens, lensradius 0.5, focaldistance 1e200",
              sphere_on_ground(), Refused("focaldistance"), maxdepth=100, lens=(0.5, 1e200), **SPHERE_VIEW),
    ]
    for label, index in (("1", 1.0), ("1.0001", 1.0001), ("1.5", 1.5), ("3", 3.0)):
        scenes.append(Scene("glass_ior%s" % label, "smooth glass sphere of index %s over the ground" % label,
                            glass_world(index), Exact(1, wf), maxdepth=100, direct=DIRECT_BOUND, **SPHERE_VIEW))
    for label, r in (("1e-5", 1e-5), ("1", 1.0)):
        scenes.append(Scene("glass_rough%s" % label, "rough glass (alpha %s, index 1.5)" % label,
                            glass_world(1.5, r), Bound(1, wf), maxdepth=100, **SPHERE_VIEW))
    for label, r in (("0", 0.0), ("1e-5", 1e-5), ("1", 1.0)):
        scenes.append(Scene("metal_rough%s" % label, "copper sphere of alpha %s" % label,
                            metal_world(r), Bound(1, wf), maxdepth=100, **SPHERE_VIEW))
    scenes += [
        Scene("camera_in_sphere", "camera inside a closed opaque sphere, environment outside",
              closed_sphere_world, Zero(), eye=(0.2, 0.1, -0.3), look=(0, 0, 1)),
        Scene("camera_in_box", "camera inside a closed triangle-mesh cube, environment outside",
              closed_box_world, Zero(), eye=(0.2, 0.1, -0.3), look=(0.7, 0.6, 1)),
        Scene("emitters_1e-6_1e12", "emitter strips of radiance 1e-6, 1e-3, ..., 1e12 side by side",
              bands_world, Map(bands_expect, "= strip radiance (inner rows)"), fov=90,
              occlusion=Exact(math.pi, "(unoccluded wall filling the view)"), limits=METROPOLIS_STRIPS,
              width=32, height=len(BAND_RADIANCE) * BAND_ROWS),
        Scene("lights_tiny", "radius-1e-3 sphere light of radiance 1e5 over a diffuse floor",
              lights_world(True, False), eye=(0, -3, 3), look=(0, 0, 0), up=(0, 0, 1), fov=60),
        Scene("lights_huge", "100x100 area light of radiance 1e-3 over a diffuse floor",
              lights_world(False, True), eye=(0, -3, 3), look=(0, 0, 0), up=(0, 0, 1), fov=60),
        Scene("lights_both", "the tiny bright light next to the huge dim one",
              lights_world(True, True), Sum(["lights_tiny", "lights_huge"]), eye=(0, -3, 3),
              look=(0, 0, 0), up=(0, 0, 1), fov=60),
        scale_scene(1e-4, "1e-4"),
        scale_scene(1, "1"),
        scale_scene(1e6, "1e6"),
    ]
    return scenes
