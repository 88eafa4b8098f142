#!/usr/bin/python3
"""Slow-tier test: the HTML report of a tiny bench/run renders in headless Chromium.

Installs Debian's chromium with apt-get when it is missing. Checks that Chromium exits
cleanly, writes a 1280x2000 screenshot, and that the page shows the convergence plot
(its first line is matplotlib's default blue) and the rendered images (not a blank or
broken page)."""

import os
import shutil
import subprocess
import tempfile
import unittest

import numpy as np

import sys

sys.dont_write_bytecode = True

import bench_util as bu  # noqa: E402

BIN = None
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--no-first-run"]


def find_chromium():
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


def ensure_chromium():
    path = find_chromium()
    if path:
        return path
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run(sudo + ["apt-get", "update", "-q"], env=env, check=False)
    subprocess.run(sudo + ["apt-get", "install", "-y", "-q", "--no-install-recommends",
                           "chromium"], env=env, check=False)
    path = find_chromium()
    if not path:
        raise AssertionError("chromium is missing and apt-get could not install it")
    return path


class ReportScreenshot(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.chromium = ensure_chromium()
        cls.tmp = tempfile.mkdtemp(prefix="gradus-bench-shot-")
        cls.refdir = os.path.join(cls.tmp, "refs")
        cls.out = os.path.join(cls.tmp, "out")
        bu.make_tiny_reference(BIN, cls.refdir, tmp=cls.tmp)
        p = bu.harness(BIN, "--scenes", bu.TINY, "--integrators", "path", "--times", "0.25,1",
                       "--seeds", 2, "--refdir", cls.refdir, "--out", cls.out, "--nthreads", 2,
                       "--quiet", tmp=cls.tmp)
        if p.returncode != 0:
            raise AssertionError("bench/run failed:\n" + p.stdout + p.stderr)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_screenshot(self):
        shot = os.path.join(self.tmp, "report.png")
        profile = os.path.join(self.tmp, "chromium-profile")
        report = os.path.join(self.out, "report.html")
        argv = [self.chromium] + FLAGS + ["--user-data-dir=" + profile, "--screenshot=" + shot,
                                          "--window-size=1280,2000", "file://" + report]
        p = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, timeout=180)
        self.assertEqual(p.returncode, 0, p.stderr[-2000:])
        self.assertTrue(os.path.isfile(shot), "no screenshot written:\n" + p.stderr[-2000:])
        import matplotlib.image as mpimg
        img = mpimg.imread(shot)[:, :, :3]
        self.assertEqual(img.shape[:2], (2000, 1280))
        self.assertGreater(float(img.std()), 0.05, "the page looks blank")
        # matplotlib's first line colour (31, 119, 180): the plot image was loaded.
        blue = np.array([31, 119, 180]) / 255.0
        near = np.all(np.abs(img - blue) < 0.04, axis=2)
        self.assertGreater(int(near.sum()), 50, "convergence plot not visible")
        # The error map's ramp and the renders give many distinct colours.
        colours = len(np.unique((img * 255).astype(np.uint8).reshape(-1, 3), axis=0))
        self.assertGreater(colours, 500, "images not visible")


if __name__ == "__main__":
    BIN = bu.take_bin_dir()
    if not BIN:
        raise SystemExit("usage: test_bench_report_screenshot.py -DGRADUS_BIN=<build>/bin")
    unittest.main(verbosity=2)
