#!/usr/bin/python3
"""Unit tests of the harness's statistics (no renderer needed): mean +- stderr, the
log-log time-to-error interpolation behind speed-up factors, the noise-floor correction,
automatic crops and PFM reading."""

import math
import os
import sys
import tempfile
import unittest

import numpy as np

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench"))

from harness import analysis, images, runs  # noqa: E402


def row(integ, budget, seconds, relmse, seed=0, noise=None):
    return {"scene": "s", "integrator": integ, "budget": budget, "seconds": seconds,
            "relmse": relmse, "relmse_untrimmed": relmse, "mse": relmse, "psnr": 1.0,
            "spp": 1, "wall_seconds": seconds, "seed": seed, "ref_noise": noise,
            "status": "ok"}


class Stats(unittest.TestCase):
    def test_mean_stderr(self):
        m, se, n = analysis.mean_stderr([1.0, 2.0, 3.0, 4.0])
        self.assertEqual(n, 4)
        self.assertAlmostEqual(m, 2.5)
        self.assertAlmostEqual(se, math.sqrt((1.5 ** 2 * 2 + 0.5 ** 2 * 2) / 3 / 4))
        self.assertEqual(analysis.mean_stderr([5.0])[:2], (5.0, None))
        self.assertEqual(analysis.mean_stderr([])[2], 0)

    def test_summary_groups_seeds_and_skips_failures(self):
        rows = [row("path", 5, 5.0, 0.2, 0), row("path", 5, 5.0, 0.4, 1),
                dict(row("path", 5, 5.0, 99.0, 2), status="failed")]
        s = analysis.summarise(rows)
        self.assertEqual(len(s), 1)
        self.assertEqual(s[0]["runs"], 2)
        self.assertAlmostEqual(s[0]["relmse"], 0.3)
        self.assertAlmostEqual(s[0]["relmse_stderr"], 0.1)


class TimeToError(unittest.TestCase):
    def test_interpolates_power_law_exactly(self):
        curve = [(1.0, 1.0), (10.0, 0.1), (100.0, 0.01)]
        t, ex = analysis.time_to_error(curve, 0.1 ** 1.5)
        self.assertAlmostEqual(t, 10 ** 1.5, places=9)
        self.assertFalse(ex)

    def test_interpolation_is_log_log_not_linear(self):
        curve = [(1.0, 1.0), (100.0, 0.01)]
        t, _ = analysis.time_to_error(curve, 0.1)
        self.assertAlmostEqual(t, 10.0, places=9)  # linear interpolation would give ~91

    def test_extrapolates_at_monte_carlo_rate(self):
        curve = [(1.0, 1.0), (4.0, 1.0 / 16)]  # a steep start must not be extended
        t, ex = analysis.time_to_error(curve, 1.0 / 64)
        self.assertTrue(ex)
        self.assertAlmostEqual(t, 16.0, places=9)
        t, ex = analysis.time_to_error(curve, 4.0)
        self.assertTrue(ex)
        self.assertAlmostEqual(t, 0.25, places=9)
        # A nearly flat, noisy curve does not blow the factor up either.
        t, _ = analysis.time_to_error([(5.0, 16.0), (10.0, 13.0)], 0.13)
        self.assertAlmostEqual(t, 1000.0, places=6)

    def test_single_point_assumes_monte_carlo_rate(self):
        t, ex = analysis.time_to_error([(2.0, 0.5)], 0.25)
        self.assertTrue(ex)
        self.assertAlmostEqual(t, 4.0)

    def test_non_converging_curve_gives_none(self):
        curve = [(1.0, 0.1), (10.0, 0.2), (100.0, 0.4)]
        self.assertEqual(analysis.time_to_error(curve, 0.05), (None, False))


class Speedups(unittest.TestCase):
    def test_four_times_lower_error_is_four_times_faster(self):
        rows = []
        for t in (5.0, 15.0, 45.0):
            rows.append(row("path", t, t, 1.0 / t))
            rows.append(row("bdpt", t, t, 0.25 / t))
        s = analysis.speedups(analysis.summarise(rows), "path", floor_correction=False)
        for r in s:
            if r["integrator"] == "path":
                self.assertAlmostEqual(r["speedup"], 1.0)
            else:
                self.assertAlmostEqual(r["speedup"], 4.0, places=6)
        # bdpt at 5 s reaches path's 20 s error: inside path's curve, not extrapolated.
        b5 = [r for r in s if r["integrator"] == "bdpt" and r["budget"] == 5.0][0]
        self.assertFalse(b5["speedup_extrapolated"])
        b45 = [r for r in s if r["integrator"] == "bdpt" and r["budget"] == 45.0][0]
        self.assertTrue(b45["speedup_extrapolated"])

    def test_floor_correction(self):
        noise = 0.01
        rows = []
        for t in (1.0, 10.0):
            rows.append(row("path", t, t, 1.0 / t + noise, noise=noise))
            rows.append(row("bdpt", t, t, 0.5 / t + noise, noise=noise))
        rows.append(row("bdpt", 100.0, 100.0, 0.9 * noise, noise=noise))
        s = analysis.speedups(analysis.summarise(rows), "path", floor_correction=True)
        b = {r["budget"]: r for r in s if r["integrator"] == "bdpt"}
        self.assertAlmostEqual(b[1.0]["speedup"], 2.0, places=6)
        self.assertIsNone(b[100.0]["speedup"])
        self.assertTrue(b[100.0]["at_noise_floor"])
        # Without the correction the floor distorts the factor.
        s = analysis.speedups(analysis.summarise(rows), "path", floor_correction=False)
        b = {r["budget"]: r for r in s if r["integrator"] == "bdpt"}
        self.assertNotAlmostEqual(b[10.0]["speedup"], 2.0, places=2)


class Labels(unittest.TestCase):
    def test_layers_share_one_render(self):
        self.assertEqual(runs.split_label("gpt/reconstructed_l2"), ("gpt", "reconstructed_l2"))
        self.assertEqual(runs.split_label("path"), ("path", None))
        groups = runs.group_labels(["gpt", "path", "gpt/primal", "bdpt"])
        self.assertEqual(groups, [("gpt", ["gpt", "gpt/primal"]), ("path", ["path"]),
                                  ("bdpt", ["bdpt"])])


class Images(unittest.TestCase):
    def test_pick_crops_finds_hot_spot(self):
        err = np.zeros((40, 60))
        err[30:36, 8:14] = 5.0
        boxes = images.pick_crops(err, count=2, frac=0.25)
        self.assertEqual(len(boxes), 2)
        x0, y0, x1, y1 = images.crop_pixels(boxes[0], 60, 40)
        self.assertTrue(x0 <= 10 < x1 and y0 <= 32 < y1, boxes[0])
        # The second box does not overlap the first.
        a, b = images.crop_pixels(boxes[0], 60, 40), images.crop_pixels(boxes[1], 60, 40)
        self.assertTrue(a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1])

    def test_read_pfm_orientation(self):
        # PFM stores the bottom row first.
        data = np.array([[[1, 1, 1], [2, 2, 2]], [[3, 3, 3], [4, 4, 4]]], dtype="<f4")
        with tempfile.NamedTemporaryFile(suffix=".pfm", delete=False) as f:
            f.write(b"PF\n2 2\n-1\n" + data.tobytes())
            path = f.name
        try:
            img = images.read_pfm(path)
        finally:
            os.remove(path)
        self.assertEqual(img.shape, (2, 2, 3))
        self.assertEqual(img[0, 0, 0], 3.0)  # top-left is the last stored row
        self.assertEqual(img[1, 1, 2], 2.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
