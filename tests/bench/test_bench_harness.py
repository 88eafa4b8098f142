#!/usr/bin/python3
"""Default-tier test of bench/run on a tiny configuration: one 32x24 scene, 'path' only,
two short budgets. Checks the CSV columns, that relMSE falls with time, that the numbers
are imgtool's, that the report and plots exist, and the errors raised before any render."""

import csv
import json
import os
import shutil
import subprocess
import tempfile
import unittest

import sys

sys.dont_write_bytecode = True

import bench_util as bu  # noqa: E402

BIN = None


class HarnessTiny(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="gradus-bench-test-")
        cls.refdir = os.path.join(cls.tmp, "refs")
        cls.out = os.path.join(cls.tmp, "out")
        bu.make_tiny_reference(BIN, cls.refdir, tmp=cls.tmp)
        cls.proc = bu.harness(BIN, "--scenes", bu.TINY, "--integrators", "path",
                              "--times", "0.25,2", "--refdir", cls.refdir, "--out", cls.out,
                              "--nthreads", 2, "--quiet", tmp=cls.tmp)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def rows(self):
        with open(os.path.join(self.out, "results.csv"), newline="") as f:
            return list(csv.DictReader(f))

    def test_integrator_parameters_and_means(self):
        # NAME[P=V;...] passes --param P=V; the means beside relMSE are imgtool's, and
        # a render that loses energy (maxdepth 0: emitters seen directly only) shows it.
        out = os.path.join(self.tmp, "out-params")
        p = bu.harness(BIN, "--scenes", bu.TINY, "--integrators", "path,path[maxdepth=0]",
                       "--times", "0.5", "--refdir", self.refdir, "--out", out, "--nthreads", 2,
                       "--quiet", tmp=self.tmp)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        with open(os.path.join(out, "results.csv"), newline="") as f:
            rows = {r["integrator"]: r for r in csv.DictReader(f)}
        self.assertEqual(set(rows), {"path", "path[maxdepth=0]"})
        for r in rows.values():
            self.assertEqual(r["status"], "ok", r["error"])
            # The CSV keeps 6 significant digits of each number.
            self.assertAlmostEqual(float(r["mean_rel"]), float(r["mean"]) / float(r["ref_mean"]) - 1, delta=1e-4)
        self.assertLess(float(rows["path[maxdepth=0]"]["mean"]), 0.8 * float(rows["path"]["mean"]))
        meta = json.loads(subprocess.run([os.path.join(BIN, "imgtool"), "info", "--json",
                                          os.path.join(out, rows["path[maxdepth=0]"]["image"])],
                                         capture_output=True, text=True, check=True).stdout)["metadata"]
        self.assertIn('"integer maxdepth" 0', meta["integrator_parameters"])

    def test_run_succeeds(self):
        self.assertEqual(self.proc.returncode, 0, self.proc.stdout + self.proc.stderr)

    def test_reference_files(self):
        d = os.path.join(self.refdir, "tiny-box")
        for name in ("ref.exr", "ref.json", "ref.noise"):
            self.assertTrue(os.path.isfile(os.path.join(d, name)), name)
        with open(os.path.join(d, "ref.json")) as f:
            info = json.load(f)
        self.assertEqual(info["total_spp"], 1024)
        self.assertEqual(len({r["seed"] for r in info["runs"]}), 2, "runs must use distinct seeds")
        self.assertGreater(info["noise"], 0.0)

    def test_csv_columns(self):
        with open(os.path.join(self.out, "results.csv"), newline="") as f:
            header = next(csv.reader(f))
        self.assertEqual(header[:7], ["scene", "integrator", "seconds", "spp", "relmse", "mse",
                                      "psnr"])
        self.assertIn("ref_noise", header)
        rows = self.rows()
        self.assertEqual(len(rows), 2)
        for r in rows:
            self.assertEqual(r["status"], "ok", r["error"])
            self.assertEqual(r["scene"], "tiny-box")
            self.assertEqual(r["integrator"], "path")
            self.assertGreater(float(r["ref_noise"]), 0.0)

    def test_error_falls_with_time(self):
        rows = sorted(self.rows(), key=lambda r: float(r["budget"]))
        short, long_ = rows
        self.assertLess(float(short["seconds"]), float(long_["seconds"]))
        self.assertLess(int(short["spp"]), int(long_["spp"]))
        # About 8x the samples: relMSE must fall well beyond seed-to-seed noise.
        self.assertLess(float(long_["relmse"]), 0.6 * float(short["relmse"]))
        self.assertLess(float(long_["mse"]), float(short["mse"]))
        self.assertGreater(float(long_["psnr"]), float(short["psnr"]))

    def test_numbers_are_imgtools(self):
        for r in self.rows():
            image = os.path.join(self.out, r["image"])
            ref = os.path.join(self.refdir, "tiny-box", "ref.exr")
            d = json.loads(subprocess.check_output(
                [os.path.join(BIN, "imgtool"), "diff", image, ref, "--json"]))
            self.assertAlmostEqual(float(r["relmse"]), d["relmse"], delta=1e-5 * d["relmse"])
            self.assertAlmostEqual(float(r["psnr"]), d["psnr"], places=3)
            info = json.loads(subprocess.check_output(
                [os.path.join(BIN, "imgtool"), "info", image, "--json"]))
            self.assertEqual(int(r["spp"]), int(info["metadata"]["spp"]))

    def test_report_and_plots(self):
        for name in ("report.html", "summary.csv", "results.json", "convergence-tiny-box.png",
                     "convergence-tiny-box.svg"):
            self.assertTrue(os.path.isfile(os.path.join(self.out, name)), name)
        with open(os.path.join(self.out, "convergence-tiny-box.png"), "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        with open(os.path.join(self.out, "report.html")) as f:
            page = f.read()
        self.assertIn('src="convergence-tiny-box.png"', page)
        self.assertIn("tiny-box/reference-framed.png", page)
        self.assertIn("tiny-box/path-error-big.png", page)
        # The scene's interactive comparison page (imgtool compare).
        self.assertIn('href="compare/tiny-box/index.html"', page)
        for name in ("index.html", "viewer.js", "data.js", "img-0.js", "img-1.js"):
            self.assertTrue(os.path.isfile(os.path.join(self.out, "compare", "tiny-box", name)), name)
        with open(os.path.join(self.out, "compare", "tiny-box", "data.js")) as f:
            data = json.loads(f.read().split("=", 1)[1].rstrip().rstrip(";"))
        self.assertEqual([i["label"] for i in data["images"]], ["reference", "path"])
        # Every image the page refers to exists.
        import re
        for src in re.findall(r'src="([^"]+)"', page):
            self.assertTrue(os.path.isfile(os.path.join(self.out, src)), src)


class Overhead(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="gradus-bench-test-")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def overhead(self, pair, out, seeds):
        return bu.harness(BIN, "--overhead", pair, "--spp", 4, "--seeds", seeds,
                          "--scenes", bu.TINY, "--refdir", self.tmp, "--out", out,
                          "--nthreads", 2, "--quiet", tmp=self.tmp)

    def overhead_rows(self, pair, out, seeds):
        p = self.overhead(pair, out, seeds)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        with open(os.path.join(out, "overhead.csv"), newline="") as f:
            return list(csv.DictReader(f))

    def test_equal_spp_timing(self):
        out = os.path.join(self.tmp, "out")
        rows = self.overhead_rows("path:path", out, 2)
        self.assertEqual(len(rows), 1)
        r = rows[0]
        self.assertEqual((r["gradient"], r["primal"], r["spp"], r["runs"]),
                         ("path", "path", "4", "2"))
        ratio = float(r["gradient_seconds"]) / float(r["primal_seconds"])
        self.assertAlmostEqual(float(r["overhead"]), ratio, places=4)
        with open(os.path.join(out, "overhead.json")) as f:
            runs = json.load(f)["runs"]
        self.assertEqual(len(runs), 4)
        self.assertTrue(all(x["spp"] == 4 for x in runs))
        self.assertTrue(os.path.isfile(os.path.join(out, "report.html")))

    def test_pair_member_with_parameters(self):
        # 'NAME[P=V]' reaches gradus as --param P=V (a misspelt one would fail the render).
        out = os.path.join(self.tmp, "out")
        rows = self.overhead_rows("path[maxdepth=2]:path", out, 1)
        self.assertEqual(rows[0]["gradient"], "path[maxdepth=2]")
        p = self.overhead("path[maxdepht=2]:path", out + "2", 1)
        self.assertNotEqual(p.returncode, 0)
        self.assertIn("maxdepht", p.stdout + p.stderr)

    def test_unknown_name_in_pair(self):
        out = os.path.join(self.tmp, "out")
        p = bu.harness(BIN, "--overhead", "no-such-gpt:path", "--scenes", bu.TINY,
                       "--out", out, tmp=self.tmp)
        self.assertEqual(p.returncode, 2)
        self.assertIn("unknown integrator no-such-gpt", p.stderr)
        self.assertFalse(os.path.exists(out))


class HarnessErrors(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="gradus-bench-test-")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def test_unknown_integrator_fails_before_rendering(self):
        out = os.path.join(self.tmp, "out")
        p = bu.harness(BIN, "--scenes", bu.TINY, "--integrators", "path,no-such-integrator",
                       "--times", "0.25", "--refdir", self.tmp, "--out", out, tmp=self.tmp)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn("unknown integrator no-such-integrator", p.stderr)
        self.assertIn("path", p.stderr.split("offers:")[-1])
        self.assertFalse(os.path.exists(out), "nothing may be rendered")

    def test_missing_reference_is_explained(self):
        out = os.path.join(self.tmp, "out")
        p = bu.harness(BIN, "--scenes", bu.TINY, "--integrators", "path", "--times", "0.25",
                       "--refdir", self.tmp, "--out", out, tmp=self.tmp)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn("--make-reference", p.stderr)
        self.assertFalse(os.path.exists(out))

    def test_unknown_scene(self):
        p = bu.harness(BIN, "--scenes", "no-such-scene", "--times", "1", "--refdir", self.tmp,
                       "--out", os.path.join(self.tmp, "out"), tmp=self.tmp)
        self.assertEqual(p.returncode, 2)
        self.assertIn("unknown scene 'no-such-scene'", p.stderr)


if __name__ == "__main__":
    BIN = bu.take_bin_dir()
    if not BIN:
        raise SystemExit("usage: test_bench_harness.py -DGRADUS_BIN=<build>/bin")
    unittest.main(verbosity=2)
