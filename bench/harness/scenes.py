"""Scene list: names -> scene file, reference image, reference noise floor."""

import glob
import json
import os

from .tools import HarnessError, repo_root


class Scene:
    def __init__(self, name, scene, reference=None, noise=None, noise_source=None,
                 discard_fraction=None, discard_count=None, exposure=None, crops=None,
                 note=None, origin="list"):
        self.name = name
        self.scene = scene
        self.reference = reference
        self.noise = noise
        self.noise_source = noise_source
        self.discard_fraction = discard_fraction
        self.discard_count = discard_count
        self.exposure = exposure
        self.crops = crops
        self.note = note
        self.origin = origin

    def as_dict(self):
        return dict(name=self.name, scene=self.scene, reference=self.reference,
                    noise=self.noise, noise_source=self.noise_source,
                    discard_fraction=self.discard_fraction, discard_count=self.discard_count,
                    exposure=self.exposure, crops=self.crops, note=self.note, origin=self.origin)


def default_list_path():
    return os.path.join(repo_root(), "bench", "scenes.json")


def shared_dir(config, override=None):
    """--shared-dir, else $GRADUS_SHARED, else the list's shared_dir relative to the repo."""
    if override:
        return os.path.abspath(override)
    if os.environ.get("GRADUS_SHARED"):
        return os.path.abspath(os.environ["GRADUS_SHARED"])
    return os.path.normpath(os.path.join(repo_root(), config.get("shared_dir", "../shared")))


def read_noise(path):
    try:
        with open(path) as f:
            return float(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def load_catalogue(list_path=None, shared_override=None):
    """All scenes the list names that exist on this machine, by name (ordered).

    Shared scenes whose folder is absent are left out (CI without ../shared);
    they are reported as missing only when asked for by name."""
    list_path = list_path or default_list_path()
    try:
        with open(list_path) as f:
            config = json.load(f)
    except (OSError, ValueError) as e:
        raise HarnessError("cannot read scene list %s: %s" % (list_path, e))
    base = os.path.dirname(os.path.abspath(list_path))
    sdir = shared_dir(config, shared_override)
    catalogue = {}
    absent = {}
    for entry in config.get("scenes", []):
        opts = {k: entry.get(k) for k in ("discard_fraction", "discard_count", "exposure",
                                          "crops", "note")}
        if "glob" in entry:
            pattern = entry["glob"]
            root = repo_root() if not os.path.isabs(pattern) else ""
            for path in sorted(glob.glob(os.path.join(root, pattern))):
                name = entry.get("prefix", "") + os.path.splitext(os.path.basename(path))[0]
                if name not in catalogue:
                    catalogue[name] = Scene(name, path, origin="project", **opts)
        elif entry.get("source") == "shared":
            name = entry["name"]
            folder = os.path.join(sdir, "references", name)
            pbrt = os.path.join(folder, "ref.pbrt")
            ref = os.path.join(folder, "ref.exr")
            if os.path.isfile(pbrt) and os.path.isfile(ref):
                catalogue[name] = Scene(name, pbrt, reference=ref,
                                        noise=read_noise(os.path.join(folder, "ref.noise")),
                                        noise_source=os.path.join(folder, "ref.noise"),
                                        origin="shared", **opts)
            else:
                absent[name] = folder
        else:
            name = entry["name"]
            path = entry["scene"]
            if not os.path.isabs(path):
                path = os.path.normpath(os.path.join(base, path))
            ref = entry.get("reference")
            if ref and not os.path.isabs(ref):
                ref = os.path.normpath(os.path.join(base, ref))
            catalogue[name] = Scene(name, path, reference=ref, noise=entry.get("noise"),
                                    origin="list", **opts)
    return catalogue, absent, sdir


def resolve(names, catalogue, absent, refdir):
    """Scenes for the --scenes argument: list names or paths to .pbrt files.

    Scenes without a reference of their own take <refdir>/<name>/ref.exr (and
    its ref.noise) when reference mode has made one."""
    scenes = []
    for item in names:
        if item in catalogue:
            s = catalogue[item]
        elif item.endswith(".pbrt"):
            if not os.path.isfile(item):
                raise HarnessError("scene file not found: %s" % item)
            path = os.path.abspath(item)
            s = Scene(os.path.splitext(os.path.basename(path))[0], path, origin="file")
        elif item in absent:
            raise HarnessError("scene '%s' needs %s/ref.pbrt and ref.exr, which are missing "
                               "(is ../shared beside the repository? see --shared-dir)"
                               % (item, absent[item]))
        else:
            known = ", ".join(sorted(catalogue)) or "(none)"
            raise HarnessError("unknown scene '%s'; known scenes: %s; or give a .pbrt path"
                               % (item, known))
        if not s.reference:
            ref = os.path.join(refdir, s.name, "ref.exr")
            if os.path.isfile(ref):
                s.reference = ref
                s.noise = read_noise(os.path.join(refdir, s.name, "ref.noise"))
                s.noise_source = os.path.join(refdir, s.name, "ref.noise")
        scenes.append(s)
    return scenes
