"""Shared helpers of the Python module's tests: paths, the CLI tools, tiny scenes."""
import os
import subprocess

import numpy as np
import pytest

import gradus

SOURCE_DIR = os.path.abspath(os.environ.get("GRADUS_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", "..")))
BINARY_DIR = os.environ.get("GRADUS_BINARY_DIR", os.path.join(SOURCE_DIR, "build"))
BIN = os.path.join(BINARY_DIR, "bin")
CORNELL = os.path.join(SOURCE_DIR, "scenes", "cornell-box.pbrt")
CORNELL_GLB = os.path.join(SOURCE_DIR, "scenes", "cornell-box.glb")


def run_tool(tool, *args):
    """Runs build/bin/TOOL with args; fails the test with its stderr on a non-zero exit."""
    r = subprocess.run([os.path.join(BIN, tool)] + [str(a) for a in args], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.fail("%s %s exited %d:\n%s" % (tool, " ".join(map(str, args)), r.returncode, r.stderr))
    return r


def bits(a):
    """The array's float32 bit patterns (bit-for-bit comparison, NaN included)."""
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def assert_same_layers(a, b):
    """Equal layer names and bit-identical arrays."""
    assert sorted(a.layers) == sorted(b.layers)
    for name in a.layers:
        assert a.layers[name].shape == b.layers[name].shape, name
        diff = np.count_nonzero(bits(a.layers[name]) != bits(b.layers[name]))
        assert diff == 0, "layer %r: %d values differ" % (name, diff)


@pytest.fixture
def tiny_cornell():
    return gradus.load_scene(CORNELL, resolution=(24, 18))
