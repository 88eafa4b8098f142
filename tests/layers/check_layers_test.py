#!/usr/bin/env python3
"""ctest layers_includes_selftest: scripts/check-layers on temporary trees. A clean
tree (same-layer, downward, system and folder-less includes, the manifold files
that belong to the integrators layer) passes; each planted violation, alone in
its tree, fails with its file:line: an include one layer up (render ->
integrators), several layers up (materials -> scene, core -> job, with spaces
after '#'), the scene-free manifold walk including the scene, a file outside
every layer. The repository's own src/ passes.
usage: check_layers_test.py SCRIPT"""
import os
import subprocess
import sys
import tempfile

script = sys.argv[1]
failures = 0


def check(name, ok, detail=""):
    global failures
    print(("ok   " if ok else "FAIL ") + name + (": " + detail if detail and not ok else ""))
    failures += 0 if ok else 1


def run(files=None):
    """Runs the script on a tree of {path: text} (None: the repository's src/)."""
    if files is None:
        r = subprocess.run([sys.executable, script], capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr
    with tempfile.TemporaryDirectory() as d:
        for rel, text in files.items():
            full = os.path.join(d, rel)
            os.makedirs(os.path.dirname(full), exist_ok=True)
            with open(full, "w") as f:
                f.write(text)
        r = subprocess.run([sys.executable, script, d], capture_output=True, text=True)
        return r.returncode, r.stdout + r.stderr


clean = {
    "core/geometry.h": "#pragma once\n#include <vector>\n#include \"core/error.h\"\n",
    "core/error.h": "#pragma once\n",
    "materials/matte.cpp": "#include \"materials/matte.h\"\n#include \"textures/texture.h\"\n#include \"core/geometry.h\"\n",
    "integrators/manifold/walk.h": "#include \"materials/bsdf.h\"\n#include \"local.h\"\n",
    "integrators/manifold/manifold_scene.h": "#include \"scene/scene.h\"\n#include \"integrators/manifold/walk.h\"\n",
    "render/integrator.h": "#include \"scene/scene.h\"\n",
    "job/job.cpp": "#include \"integrators/registry.h\"\n#include \"render/integrator.h\"\n",
    "tools/gradus/main.cpp": "#include \"job/job.h\"\n",
}
code, out = run(clean)
check("clean tree passes", code == 0, out)

planted = [
    ("one layer up", "render/render_loop.h", "#pragma once\n#include \"integrators/registry.h\"\n",
     "src/render/render_loop.h:2: includes integrators/registry.h"),
    ("materials -> scene", "materials/hair.cpp", "#include \"materials/hair.h\"\n\n#include \"scene/scene.h\"\n",
     "src/materials/hair.cpp:3: includes scene/scene.h"),
    ("core -> job, spaced", "core/error.h", "#pragma once\n#  include   \"job/job.h\"\n",
     "src/core/error.h:2: includes job/job.h"),
    ("manifold walk -> scene", "integrators/manifold/walk.cpp", "#include \"scene/scene.h\"\n",
     "src/integrators/manifold/walk.cpp:1: includes scene/scene.h"),
    ("outside every layer", "newlayer/thing.h", "#pragma once\n", "src/newlayer/thing.h: not in any layer"),
]
for name, rel, text, expect in planted:
    tree = dict(clean)
    tree[rel] = text
    code, out = run(tree)
    check(name + " fails", code == 1 and expect in out, "exit %d, output:\n%s" % (code, out))

code, out = run()
check("the repository's src/ passes", code == 0, out)
print("%d failure(s)" % failures)
sys.exit(1 if failures else 0)
