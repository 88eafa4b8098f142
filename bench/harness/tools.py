"""Thin wrappers around the gradus and imgtool executables.

Every measurement the harness reports comes from these two programs: gradus
renders with a wall-clock budget (--time) or a sample count (--spp) and stores
spp / render_seconds / integrator in the EXR metadata; imgtool computes the
error metrics (relMSE with the papers' 0.001 offset and outlier trimming, MSE,
PSNR), merges renders and draws false-colour error maps.
"""

import json
import os
import resource
import subprocess
import time


class HarnessError(Exception):
    """A problem the user must fix (bad option, missing file); exit 2."""


def repo_root():
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def find_bin_dir(explicit=None):
    """--bin-dir, else $GRADUS_BIN, else <repo>/build/bin."""
    candidates = []
    if explicit:
        candidates.append(explicit)
    elif os.environ.get("GRADUS_BIN"):
        candidates.append(os.environ["GRADUS_BIN"])
    else:
        candidates.append(os.path.join(repo_root(), "build", "bin"))
    for d in candidates:
        d = os.path.abspath(d)
        if all(os.access(os.path.join(d, exe), os.X_OK) for exe in ("gradus", "imgtool")):
            return d
    raise HarnessError(
        "cannot find gradus and imgtool in %s (use --bin-dir or $GRADUS_BIN)"
        % ", ".join(os.path.abspath(c) for c in candidates))


class Tools:
    def __init__(self, bin_dir, verbose=False):
        self.bin_dir = bin_dir
        self.gradus = os.path.join(bin_dir, "gradus")
        self.imgtool = os.path.join(bin_dir, "imgtool")
        self.verbose = verbose

    # -- process helpers -------------------------------------------------
    def _run(self, argv, what):
        if self.verbose:
            print("  $ " + " ".join(argv), flush=True)
        proc = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              universal_newlines=True)
        if proc.returncode != 0:
            msg = (proc.stderr.strip() or proc.stdout.strip() or "no output")
            raise RuntimeError("%s failed (exit %d): %s\n  command: %s"
                               % (what, proc.returncode, msg, " ".join(argv)))
        return proc.stdout

    # -- gradus ----------------------------------------------------------
    def list_integrators(self):
        """Names printed by `gradus --list-integrators` (first word of each line)."""
        out = self._run([self.gradus, "--list-integrators"], "gradus --list-integrators")
        names = []
        for line in out.splitlines():
            words = line.split()
            if words:
                names.append(words[0])
        return names

    def render(self, scene, outfile, integrator=None, seconds=None, spp=None, seed=0,
               nthreads=None, params=()):
        """Render and return (metadata dict, harness-measured wall seconds)."""
        argv = [self.gradus, scene, "--outfile", outfile, "--seed", str(seed), "--quiet"]
        if integrator:
            argv += ["--integrator", integrator]
        for p in params:
            argv += ["--param", p]
        if seconds is not None:
            argv += ["--time", _num(seconds)]
        if spp is not None:
            argv += ["--spp", str(int(spp))]
        if nthreads:
            argv += ["--nthreads", str(int(nthreads))]
        os.makedirs(os.path.dirname(os.path.abspath(outfile)), exist_ok=True)
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        self._run(argv, "gradus render of %s" % scene)
        wall = time.monotonic() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.last_cpu_seconds = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
        return self.metadata(outfile), wall

    # -- imgtool ---------------------------------------------------------
    def info(self, path):
        return json.loads(self._run([self.imgtool, "info", path, "--json"], "imgtool info"))

    def metadata(self, path):
        return self.info(path).get("metadata", {})

    def diff(self, image, reference, discard_fraction=0.0, discard_count=0, layer=None,
             error_image=None):
        argv = [self.imgtool, "diff", image, reference, "--json"]
        if discard_fraction:
            argv += ["--discard-fraction", _num(discard_fraction)]
        if discard_count:
            argv += ["--discard-count", str(int(discard_count))]
        if layer:
            argv += ["--layer", layer]
        if error_image:
            argv += ["--outfile", error_image]
        return json.loads(self._run(argv, "imgtool diff"))

    def merge(self, out, inputs, weights=None):
        argv = [self.imgtool, "merge", out] + list(inputs)
        if weights:
            argv += ["--weights", ",".join(_num(w) for w in weights)]
        self._run(argv, "imgtool merge")

    def convert(self, src, dst, exposure=None, layer=None):
        argv = [self.imgtool, "convert", src, dst]
        if exposure:
            argv += ["--exposure", _num(exposure)]
        if layer:
            argv += ["--layer", layer]
        self._run(argv, "imgtool convert")

    def falsecolor(self, image, reference, out_png, vmax, layer=None):
        argv = [self.imgtool, "falsecolor", image, reference, out_png, "--max", _num(vmax)]
        if layer:
            argv += ["--layer", layer]
        self._run(argv, "imgtool falsecolor")

    def compare(self, reference, images, out_dir, labels, layers=None, exposure=None,
                error_max=None, discard_fraction=None, discard_count=None, title=None):
        """The interactive comparison page (imgtool compare) of images against reference."""
        argv = [self.imgtool, "compare", reference] + list(images) + ["-o", out_dir,
                "--labels", ",".join(l.replace(",", ";") for l in labels)]
        if layers and any(layers):
            argv += ["--layers", ",".join(layers)]
        for opt, v in (("--exposure", exposure), ("--error-max", error_max),
                       ("--discard-fraction", discard_fraction), ("--discard-count", discard_count)):
            if v:
                argv += [opt, _num(v)]
        if title:
            argv += ["--title", title]
        self._run(argv, "imgtool compare")


def _num(x):
    """Format a number for a command line without a trailing '.0'."""
    x = float(x)
    return str(int(x)) if x == int(x) else repr(x)


def git_commit(root):
    try:
        out = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             universal_newlines=True)
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                               stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                               universal_newlines=True)
        if out.returncode == 0:
            return out.stdout.strip() + ("-dirty" if dirty.stdout.strip() else "")
    except OSError:
        pass
    return "unknown"
