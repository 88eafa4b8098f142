#!/usr/bin/env python3
"""The energy checks of bench/stress/run.py on synthetic images: unbiased noise
(also correlated in blocks, and smooth reconstructions of a noisy primal) passes;
a gain, a loss, a leak and a bias against a reference fail."""

import math
import os
import random
import sys
import unittest

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench", "stress"))

import run as stress  # noqa: E402
import scenes as S  # noqa: E402

W = H = 32


class FakeRender:
    def __init__(self, **layers):
        self._layers = {("" if k == "main" else k): v for k, v in layers.items()}
        self.layers = {k: 0 for k in self._layers}

    def layer(self, name):
        return self._layers[name]


def image(fn):
    return [[(fn(x, y),) * 3 for x in range(W)] for y in range(H)]


def noisy(mean, sigma, seed):
    rng = random.Random(seed)
    return image(lambda x, y: rng.gauss(mean, sigma))


def verdict(check, r, layer="", noise="", refs=(), twin=None):
    return stress.check_layer(check, r, layer, noise, list(refs), twin)["verdict"]


class Checks(unittest.TestCase):
    def test_unbiased_noise_passes(self):
        for seed in range(5):
            self.assertEqual(verdict(S.Exact(1), FakeRender(main=noisy(1, 0.1, seed))), "ok")

    def test_gain_and_loss(self):
        # sigma 0.1 over 1024 pixels: SE 0.003, so 2% is about 6.5 sigma.
        self.assertEqual(verdict(S.Exact(1), FakeRender(main=noisy(1.02, 0.1, 1))), "gain")
        self.assertEqual(verdict(S.Exact(1), FakeRender(main=noisy(0.98, 0.1, 1))), "loss")

    def test_bound_fails_only_on_gain(self):
        # The expectation varies over the image (0.5 .. 1): the twin render gives the noise.
        base = lambda x, y: 0.5 + 0.5 * (x / (W - 1))
        rng = random.Random(3)
        a = image(lambda x, y: base(x, y) + rng.gauss(0, 0.05))
        b = image(lambda x, y: base(x, y) + rng.gauss(0, 0.05))
        self.assertEqual(verdict(S.Bound(1), FakeRender(main=a), twin=FakeRender(main=b)), "ok")
        hot = image(lambda x, y: 1.01 + rng.gauss(0, 0.05))
        hot2 = image(lambda x, y: 1.01 + rng.gauss(0, 0.05))
        self.assertEqual(verdict(S.Bound(1), FakeRender(main=hot), twin=FakeRender(main=hot2)), "gain")
        self.assertEqual(verdict(S.Bound(1), FakeRender(main=a)), "n/a")

    def test_leak_into_zero_scene(self):
        img = image(lambda x, y: 0.0)
        self.assertEqual(verdict(S.Zero(), FakeRender(main=img)), "ok")
        img[5][7] = (1e-30, 0, 0)
        self.assertEqual(verdict(S.Zero(), FakeRender(main=img)), "gain")

    def test_block_correlated_noise_passes(self):
        # Noise shared by 8x8 blocks: the pixel spread alone would give a 8x too small SE.
        for seed in range(5):
            rng = random.Random(seed)
            blocks = {(bx, by): rng.gauss(0, 0.05) for bx in range(4) for by in range(4)}
            img = image(lambda x, y: 1 + blocks[(x // 8, y // 8)] + rng.gauss(0, 0.01))
            self.assertEqual(verdict(S.Exact(1), FakeRender(main=img)), "ok")

    def test_reconstruction_uses_primal_noise(self):
        # A smooth image at the primal's mean passes with the primal's SE; one 7 primal SE low fails.
        primal = noisy(1, 0.1, 4)
        m = stress.image_mean(primal)
        smooth = image(lambda x, y: m)
        self.assertEqual(verdict(S.Exact(1), FakeRender(main=smooth, primal=primal), noise="primal"), "ok")
        low = image(lambda x, y: 1 - 7 * 0.1 / 32)
        self.assertEqual(verdict(S.Exact(1), FakeRender(main=low, primal=primal), noise="primal"), "loss")

    def test_same_and_sum_against_references(self):
        ref = FakeRender(main=noisy(0.3, 0.05, 5))
        self.assertEqual(verdict(S.Same("r"), FakeRender(main=noisy(0.3, 0.05, 6)), refs=[ref]), "ok")
        self.assertEqual(verdict(S.Same("r"), FakeRender(main=noisy(0.32, 0.05, 6)), refs=[ref]), "gain")
        parts = [FakeRender(main=noisy(0.1, 0.02, 7)), FakeRender(main=noisy(0.2, 0.02, 8))]
        self.assertEqual(verdict(S.Sum(["a", "b"]), FakeRender(main=noisy(0.3, 0.03, 9)), refs=parts), "ok")
        self.assertEqual(verdict(S.Sum(["a", "b"]), FakeRender(main=noisy(0.28, 0.03, 9)), refs=parts), "loss")

    def test_furnace_expectation(self):
        # maxdepth d: Le * sum_{k=0}^{d} rho^k (d bounces; d = 0 is the emitter alone).
        self.assertEqual(S.furnace(0, 0.5, 0.5).check.value, [0.5] * 3)
        self.assertEqual(S.furnace(1, 0.5, 0.5).check.value, [0.75] * 3)
        self.assertAlmostEqual(S.furnace(5, 1.0, 0.8).check.value[0], (1 - 0.8 ** 6) / 0.2)

    def test_classic_integrators_get_their_own_expectations(self):
        scenes = {s.name: s for s in S.all_scenes()}
        # Direct light only: Le (1 + rho) whatever maxdepth (it bounds the specular recursion).
        for name in ("furnace_d0", "furnace_d1", "furnace_d1000"):
            for integ in ("whitted", "directlighting"):
                self.assertEqual(scenes[name].check_for(integ).value, [0.75] * 3)
        self.assertAlmostEqual(scenes["furnace_d5"].check_for("whitted").value[0], 1.8)
        # A white furnace gives at most 1 with direct light only; the environment alone exactly 1.
        self.assertIsInstance(scenes["glass_ior1.5"].check_for("whitted"), S.Bound)
        self.assertIsInstance(scenes["empty_env"].check_for("directlighting"), S.Exact)
        # Occlusion: nothing seen or a closed sphere gives 0, an open wall pi, elsewhere <= pi;
        # the light sum is no occlusion statement.
        for name in ("empty", "empty_env", "furnace_d1", "camera_in_box"):
            self.assertIsInstance(scenes[name].check_for("ambientocclusion"), S.Zero)
        self.assertAlmostEqual(scenes["emitters_1e-6_1e12"].check_for("ambientocclusion").value[0], 3.14159265)
        self.assertEqual(scenes["lights_both"].check_for("ambientocclusion").value[0], math.pi)
        self.assertIsInstance(scenes["scale_1e6"].check_for("ambientocclusion"), S.Same)
        self.assertIsInstance(scenes["far_camera"].check_for("ambientocclusion"), S.Refused)
        # Every other integrator keeps the full-transport check.
        for name, s in scenes.items():
            self.assertIs(s.check_for("path"), s.check)
            self.assertIs(s.check_for("some_future_integrator"), s.check)
        self.assertNotIn("maxdepth", scenes["empty"].text("ambientocclusion", 16, 4, maxdepth=False))
        self.assertIn('"integer maxdepth" [ 5 ]', scenes["empty"].text("path", 16, 4))

    def test_known_limitations_are_exact_specs(self):
        limits = {s.name: s.limits for s in S.all_scenes() if s.limits}
        self.assertEqual(set(limits), {"emitters_1e-6_1e12"})
        self.assertEqual(set(limits["emitters_1e-6_1e12"]), {"mlt", "pmlt", "gmlt"})  # not mlt[largestepmis=true]


if __name__ == "__main__":
    unittest.main()
