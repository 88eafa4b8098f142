"""Gradus from Python: load a scene, render it, reconstruct and compare images.

    import gradus
    scene = gradus.load_scene("scenes/cornell-box.pbrt", resolution=(320, 240))
    result = scene.render(integrator="gbdpt", spp=16, seed=0)
    result.image                # the output (H x W x 3 float32), as the EXR's R, G, B
    result.layers["primal"]     # every layer of the EXR gradus would write
    result.metadata["spp"]      # the EXR's attributes
    result.stats["seconds"]     # render statistics

A render takes the command line's route (load, build, render), so it equals
``gradus SCENE --seed S ...`` bit for bit at equal options; the scene is
loaded and built once by ``load_scene`` and its renders share the build.
Renders release the GIL; Ctrl-C stops one cleanly (KeyboardInterrupt once the
loop has stopped).
"""
import math
import numbers
import os
import shlex

from . import _gradus
from ._errors import Error, SceneError

__all__ = ["Error", "SceneError", "Image", "RenderResult", "Scene", "load_scene", "integrators", "describe",
           "reconstruct", "metrics", "read_image", "write_image", "__version__"]

__version__ = _gradus.version()

_MAX_SIDE = 1 << 17
_MAX_SPP = 1 << 30


def integrators():
    """The available integrators: {name: description} in the registry's order."""
    return _gradus.integrators()


def describe(name):
    """An integrator's parameter table: {"name", "description", "parameters":
    [{"name", "type", "default", "help", "values", "group"}, ...], "text"}
    (``text`` is what ``gradus --describe NAME`` prints)."""
    return _gradus.describe(name)


class Image:
    """Layers of an image file or a render: ``layers`` maps a layer name ("" for
    the unprefixed R, G, B; "primal", "dx", ...) to an H x W x C float32 array
    (C = 3 for R, G, B; otherwise the layer's channels, named in ``channels``).
    ``origin`` and ``display_size`` place a crop in the full image."""

    def __init__(self, layers, metadata=None, channels=None, origin=(0, 0), display_size=None):
        self.layers = dict(layers)
        self.metadata = dict(metadata or {})
        self.channels = dict(channels or {})
        self.origin = tuple(origin)
        if display_size is None and self.layers:
            h, w = next(iter(self.layers.values())).shape[:2]
            display_size = (w, h)
        self.display_size = tuple(display_size) if display_size else None

    @classmethod
    def _from_dict(cls, d, **extra):
        return cls(d["layers"], d["metadata"], d["channels"], d["origin"], d["display_size"], **extra)

    @property
    def image(self):
        """The layer single-layer outputs use: "" (unprefixed R, G, B), else
        "primal", else the first layer."""
        for name in ("", "primal"):
            if name in self.layers:
                return self.layers[name]
        return next(iter(self.layers.values()))

    def __getitem__(self, layer):
        return self.layers[layer]

    def __repr__(self):
        h, w = self.image.shape[:2] if self.layers else (0, 0)
        return "<%s %dx%d layers=%s>" % (type(self).__name__, w, h, list(self.layers))


class RenderResult(Image):
    """A render: its layers, ``metadata`` (the records of the EXR gradus writes)
    and ``stats`` (spp, passes, seconds, interrupted, time_limited,
    nonfinite_discarded, counters, text: what gradus prints as statistics, notes)."""

    def __init__(self, *args, stats=None, **kwargs):
        super().__init__(*args, **kwargs)
        self.stats = dict(stats or {})

    def write(self, path):
        """Writes the render as gradus would (.exr: every layer and the metadata; .png, .pfm)."""
        write_image(path, self)


def _param_text(name, value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, str):
        return value
    if isinstance(value, (list, tuple)):
        return ",".join(_param_text(name, v) for v in value)
    raise TypeError("params[%r]: expected a bool, number, string or list, got %s" % (name, type(value).__name__))


def _integer(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError("%s: expected an integer, got %r" % (name, value))
    if not lo <= value <= hi:
        raise ValueError("%s must be in [%d, %d], got %d" % (name, lo, hi, value))
    return int(value)


def _environment(envmap, scale, rotate, base=None):
    """The environment options (map, scale, rotate) and their gradus options;
    None takes base's value (a Scene's), else the default."""
    base_map, base_scale, base_rotate = base or ("", 1.0, 0.0)
    if envmap is None:
        envmap = base_map
    elif not isinstance(envmap, (str, os.PathLike)):
        raise TypeError("envmap: expected a file name or \"none\", got %r" % (envmap,))
    else:
        envmap = os.fspath(envmap)
        if not envmap:
            raise ValueError("envmap: expected a file name or \"none\", got an empty string")
        if envmap != "none":
            envmap = os.path.abspath(envmap)
    scale = base_scale if scale is None else float(scale)
    rotate = base_rotate if rotate is None else float(rotate)
    if not (math.isfinite(scale) and scale >= 0):
        raise ValueError("envmap_scale must be a finite number >= 0, got %r" % scale)
    if not math.isfinite(rotate):
        raise ValueError("envmap_rotate must be a finite number of degrees, got %r" % rotate)
    if (scale != 1 or rotate != 0) and envmap in ("", "none"):
        raise ValueError("envmap_scale and envmap_rotate need envmap=FILE")
    args = []
    if envmap:
        args += ["--envmap", envmap]
    if scale != 1:
        args += ["--envmap-scale", repr(scale)]
    if rotate != 0:
        args += ["--envmap-rotate", repr(rotate)]
    return (envmap, scale, rotate), args


class Scene:
    """A loaded scene (``load_scene``), parsed and built once: its renders
    share the build (a render with other environment options builds the scene
    anew and keeps that build). Its figures come from the build at load time:
    ``resolution``, ``integrator`` and ``spp`` (the scene's), ``features``,
    ``notes``, ``provenance`` (the metadata records of the scene), ``load_seconds``."""

    def __init__(self, handle, overrides, args, environment):
        self._scene = handle
        self._overrides = dict(overrides)
        self._args = list(args)  # the overrides as gradus options (without the environment's)
        self._environment = environment  # (map, scale, rotate) of load_scene
        info = handle.info
        self.path = handle.path
        self.resolution = tuple(info["resolution"])
        self.pixel_bounds = tuple(info["pixel_bounds"])
        self.integrator = info["integrator"]
        self.spp = info["spp"]
        self.features = info["features"]
        self.notes = list(info["notes"])
        self.provenance = dict(info["provenance"])
        self.load_seconds = info["load_seconds"]  # parse and build (renders then build their jobs only)

    def __repr__(self):
        return "<gradus.Scene %r %dx%d integrator=%s spp=%d>" % (self.path, self.resolution[0],
                                                                  self.resolution[1], self.integrator, self.spp)

    def render(self, integrator=None, spp=None, time=None, seed=0, threads=None, params=None, progress=None,
               envmap=None, envmap_scale=None, envmap_rotate=None, display_server=None, display_layers=False):
        """Renders the scene and returns a RenderResult.

        integrator -- a name of ``integrators()`` (default: the scene's)
        spp        -- samples per pixel (default: the scene's sampler, or the
                      integrator's own count such as vcm's iterations)
        time       -- wall-clock budget in seconds for everything after scene
                      loading; with spp as well, whichever ends first
        seed       -- the render's random seed (a non-negative integer)
        threads    -- worker threads (default: all cores)
        params     -- integrator parameters {name: value} (``describe(name)``),
                      as gradus's --param NAME=VALUE
        progress   -- called as progress(spp_done, spp_total, seconds) while
                      rendering (spp_total is 0 with a time budget alone); an
                      exception it raises stops the render and is re-raised
        envmap, envmap_scale, envmap_rotate -- gradus's --envmap FILE|"none",
                      --envmap-scale, --envmap-rotate (default: load_scene's)
        display_server -- "HOST:PORT" of a viewer speaking tev's protocol, to
                      which the film streams while it renders (gradus
                      --display-server); display_layers: its layers too

        The render shares the scene's build (no render modifies a built
        scene), so it equals ``gradus SCENE --seed S [...]`` bit for bit.
        """
        args = []
        if integrator is not None:
            if not isinstance(integrator, str):
                raise TypeError("integrator: expected a name, got %r" % (integrator,))
            args += ["--integrator", integrator]
        if spp is not None:
            spp = _integer("spp", spp, 1, _MAX_SPP)
            args += ["--spp", str(spp)]
        if time is not None:
            time = float(time)
            if not (time > 0 and math.isfinite(time)):
                raise ValueError("time must be a positive number of seconds, got %r" % time)
            args += ["--time", repr(time)]
        seed = _integer("seed", seed, 0, (1 << 63) - 1)
        args += ["--seed", str(seed)]
        if threads is not None:
            threads = _integer("threads", threads, 1, 1024)
            args += ["--nthreads", str(threads)]
        texts = []
        for name, value in (params or {}).items():
            texts.append("%s=%s" % (name, _param_text(name, value)))
            args += ["--param", texts[-1]]
        if progress is not None and not callable(progress):
            raise TypeError("progress: expected a callable")
        environment, env_args = _environment(envmap, envmap_scale, envmap_rotate, self._environment)
        if display_server is not None:
            if not isinstance(display_server, str):
                raise TypeError("display_server: expected \"HOST:PORT\", got %r" % (display_server,))
            args += ["--display-server", display_server]
        if display_layers:
            if display_server is None:
                raise ValueError("display_layers needs display_server")
            args += ["--display-layers"]
        command = " ".join(shlex.quote(a) for a in ["gradus", self.path] + self._args + env_args + args)
        command += " (Python module)"
        d = self._scene.render(integrator or "", spp or 0, time or 0.0, seed, threads or 0, texts, progress, command,
                               *environment, display_server or "", bool(display_layers))
        return RenderResult._from_dict(d, stats=d["stats"])


def load_scene(path, **overrides):
    """Loads a pbrt-v3 (.pbrt) or glTF 2.0 (.gltf, .glb) scene.

    Overrides (as gradus's options): resolution=(w, h), cropwindow=(x0, x1, y0,
    y1), camera="name" (glTF), quick=True (1/4 resolution, 1/8 of the samples),
    envmap="sky.exr" or "none", envmap_scale=S, envmap_rotate=DEG (--envmap ...).
    The scene is parsed and built once here (its errors raise SceneError, with
    file, line and column, from this call); renders use this build.
    """
    path = os.path.abspath(os.fspath(path))
    known = {"resolution", "cropwindow", "camera", "quick", "envmap", "envmap_scale", "envmap_rotate"}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise TypeError("load_scene: unknown override %s (known: %s)" % (", ".join(unknown), ", ".join(sorted(known))))
    args = []
    resolution = overrides.get("resolution")
    if resolution is not None:
        w, h = resolution
        w, h = _integer("resolution width", w, 1, _MAX_SIDE), _integer("resolution height", h, 1, _MAX_SIDE)
        resolution = (w, h)
        args += ["--resolution", "%dx%d" % resolution]
    crop = overrides.get("cropwindow")
    if crop is not None:
        crop = [float(c) for c in crop]
        if len(crop) != 4 or not all(0 <= c <= 1 for c in crop) or crop[0] >= crop[1] or crop[2] >= crop[3]:
            raise ValueError("cropwindow: expected x0 < x1 and y0 < y1 in [0, 1], got %r" % (crop,))
        args += ["--cropwindow"] + [repr(c) for c in crop]
    camera = overrides.get("camera") or ""
    if camera:
        args += ["--camera", camera]
    quick = bool(overrides.get("quick", False))
    if quick:
        args += ["--quick"]
    environment, _ = _environment(overrides.get("envmap"), overrides.get("envmap_scale"),
                                  overrides.get("envmap_rotate"))
    handle = _gradus.load_scene(path, resolution, crop, camera, quick, *environment)
    return Scene(handle, overrides, args, environment)


def reconstruct(primal, dx, dy, method="hybrid", alpha=None, primal_var=None, dx_var=None, dy_var=None,
                return_stats=False, separated=None):
    """Screened-Poisson reconstruction of H x W x 3 arrays (the code of the
    ``reconstruct`` tool): method "hybrid" (default), "l1", "l2", "weighted"
    (needs the three variances), "l1-reference" or "l2-cg"; alpha weights the
    primal (default: the preset's, 0.2). dx(x, y) = I(x+1, y) - I(x, y).
    separated: the part of primal without gradients (a gradient render's
    "separated" layer: light through ideal specular scattering only); the solve
    takes primal - separated and the result adds it back.
    Returns the image (H x W x 3 float32), with return_stats a (image, stats) pair."""
    return _gradus.reconstruct(primal, dx, dy, method, alpha, primal_var, dx_var, dy_var, separated, return_stats)


def metrics(test, ref, discard_fraction=0.0, discard_count=0, rel_epsilon=0.001):
    """Error of ``test`` against the reference ``ref`` (H x W x 3 arrays), as
    ``imgtool diff``: relmse (mean of (X-R)^2 / (R^2 + rel_epsilon), the papers'
    relMSE), mse, rmse, psnr (peak 1), means, and pixel counts. NaN/Inf pixels
    are left out; discard_fraction / discard_count trim the highest-error pixels
    (ranked by per-pixel relMSE) for the trimmed variants."""
    return _gradus.metrics(test, ref, float(discard_fraction), int(discard_count), float(rel_epsilon))


def read_image(path):
    """Reads an EXR (every layer and the metadata), PNG or PFM file as an Image."""
    return Image._from_dict(_gradus.read_image(os.fspath(path)))


def write_image(path, image, metadata=None, origin=None, display_size=None):
    """Writes an Image (or a {layer: array} dict) by extension: .exr (every
    layer; metadata as typed attributes: str, int, float), .png, .pfm (the
    default layer). Layers are H x W x 3 (R, G, B) or H x W (Y) arrays."""
    if isinstance(image, Image):
        layers = image.layers
        metadata = image.metadata if metadata is None else metadata
        origin = image.origin if origin is None else origin
        display_size = image.display_size if display_size is None else display_size
    else:
        layers = image
    _gradus.write_image(os.fspath(path), dict(layers), dict(metadata or {}), tuple(origin or (0, 0)),
                        tuple(display_size) if display_size else None)
