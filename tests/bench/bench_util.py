"""Shared helpers of the bench/run tests: argument parsing and running the harness."""

import os
import subprocess
import sys

sys.dont_write_bytecode = True

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
RUN = os.path.join(REPO, "bench", "run")
TINY = os.path.join(HERE, "data", "tiny-box.pbrt")


def take_bin_dir():
    """Removes -DGRADUS_BIN=DIR from sys.argv (the CMake add_test argument) and returns DIR."""
    bin_dir = os.environ.get("GRADUS_BIN")
    rest = []
    for a in sys.argv[1:]:
        if a.startswith("-DGRADUS_BIN="):
            bin_dir = a.split("=", 1)[1]
        else:
            rest.append(a)
    sys.argv[1:] = rest
    return bin_dir


def harness(bin_dir, *args, timeout=300, tmp=None):
    """Runs bench/run with the given arguments; returns the CompletedProcess.

    With tmp, matplotlib keeps its cache there, so a test writes only to temp dirs."""
    argv = [sys.executable, RUN, "--bin-dir", bin_dir] + [str(a) for a in args]
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    if tmp:
        env["MPLCONFIGDIR"] = os.path.join(tmp, "matplotlib")
    return subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=timeout, cwd=REPO, env=env)


def make_tiny_reference(bin_dir, refdir, tmp=None):
    """Reference of the tiny scene: 2 x 512 spp (a few seconds on two threads)."""
    p = harness(bin_dir, "--make-reference", "--scenes", TINY, "--ref-spp", 512,
                "--ref-runs", 2, "--refdir", refdir, "--nthreads", 2, "--quiet", tmp=tmp)
    if p.returncode != 0:
        raise AssertionError("reference mode failed:\n" + p.stdout + p.stderr)
