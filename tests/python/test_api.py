"""The module's tables and image functions against the tools that share their code."""
import json
import os

import numpy as np
import pytest

import gradus
from conftest import BIN, assert_same_layers, bits, run_tool


def test_integrators_are_the_registry():
    listed = run_tool("gradus", "--list-integrators").stdout.splitlines()
    names = [line.split()[0] for line in listed]
    assert list(gradus.integrators()) == names
    assert all(gradus.integrators().values())


def test_describe_is_the_parameter_table():
    d = gradus.describe("gbdpt")
    assert d["name"] == "gbdpt"
    printed = run_tool("gradus", "--describe", "gbdpt").stdout
    assert d["text"] in printed
    names = [p["name"] for p in d["parameters"]]
    assert "maxdepth" in names and "alpha" in names
    for p in d["parameters"]:
        assert p["type"] in ("bool", "integer", "float", "string")
    with pytest.raises(ValueError, match="unknown integrator"):
        gradus.describe("pathh")


def test_image_round_trip_keeps_layers_and_typed_metadata(tmp_path):
    rng = np.random.default_rng(1)
    layers = {"": rng.random((5, 7, 3), dtype=np.float32), "primal": rng.random((5, 7, 3), dtype=np.float32),
              "density": rng.random((5, 7), dtype=np.float32)}
    meta = {"note": "text", "count": 42, "scale": 0.1, "flag": True}
    path = tmp_path / "t.exr"
    gradus.write_image(path, layers, meta, origin=(3, 4), display_size=(20, 10))
    img = gradus.read_image(path)
    assert img.origin == (3, 4) and img.display_size == (20, 10)
    assert img.layers["density"].shape == (5, 7, 1)
    assert img.channels["density"] == ["Y"]
    np.testing.assert_array_equal(img.layers["density"][:, :, 0], layers["density"])
    for name in ("", "primal"):
        assert np.array_equal(bits(img.layers[name]), bits(layers[name]))
    assert img.metadata["note"] == "text"
    assert img.metadata["count"] == 42 and isinstance(img.metadata["count"], int)
    assert img.metadata["scale"] == 0.1 and isinstance(img.metadata["scale"], float)
    assert img.metadata["flag"] == 1
    # Written back, an Image keeps everything.
    gradus.write_image(tmp_path / "u.exr", img)
    again = gradus.read_image(tmp_path / "u.exr")
    assert_same_layers(img, again)
    assert again.metadata == img.metadata and again.origin == img.origin


def test_image_errors():
    with pytest.raises(gradus.Error, match="missing.exr"):
        gradus.read_image("/nonexistent/missing.exr")
    with pytest.raises(ValueError):
        gradus.write_image("/tmp/x.exr", {"": np.zeros((4, 4, 2), np.float32)})


def test_metrics_equal_imgtool_diff(tmp_path):
    rng = np.random.default_rng(7)
    ref = rng.random((16, 12, 3), dtype=np.float32)
    test = (ref + rng.normal(0, 0.05, ref.shape)).astype(np.float32)
    test[3, 4] = 50.0  # an outlier for the trimmed variant
    gradus.write_image(tmp_path / "ref.exr", {"": ref})
    gradus.write_image(tmp_path / "test.exr", {"": test})
    for trim in ([], ["--discard-count", "2"], ["--discard-fraction", "0.01"]):
        tool = json.loads(run_tool("imgtool", "diff", tmp_path / "test.exr", tmp_path / "ref.exr", "--json",
                                   *trim).stdout)
        kw = {}
        if trim:
            kw[trim[0][2:].replace("-", "_")] = float(trim[1]) if "fraction" in trim[0] else int(trim[1])
        m = gradus.metrics(test, ref, **kw)
        for key in ("relmse", "mse", "rmse", "psnr"):
            assert m[key] == tool[key], (key, trim)
        assert m["discarded_pixels"] == tool["discarded_pixels"]
    # relMSE as the papers define it: mean of (X - R)^2 / (R^2 + 0.001).
    expect = np.mean((test.astype(np.float64) - ref) ** 2 / (ref.astype(np.float64) ** 2 + 0.001))
    assert gradus.metrics(test, ref)["relmse"] == pytest.approx(expect, rel=1e-9)
    assert gradus.metrics(ref, ref)["mse"] == 0


def test_equal_time_example_writes_a_plot(tmp_path):
    import subprocess
    import sys
    from conftest import SOURCE_DIR
    out = tmp_path / "plot.png"
    r = subprocess.run([sys.executable, os.path.join(SOURCE_DIR, "examples", "equal_time.py"), "--resolution", "16x16",
                        "--times", "0.05,0.1", "--out", out], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert r.stdout.count("gbdpt") == 2 and r.stdout.count("path ") == 2
