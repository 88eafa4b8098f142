"""gradus.reconstruct on arrays equals the reconstruct tool on the EXR."""
import numpy as np
import pytest

import gradus
from conftest import CORNELL, bits, run_tool


@pytest.fixture(scope="module")
def gradient_exr(tmp_path_factory):
    out = tmp_path_factory.mktemp("recon") / "gbdpt.exr"
    run_tool("gradus", CORNELL, "--integrator", "gbdpt", "--resolution", "24x18", "--spp", "2", "--seed", "9",
             "--outfile", out, "--quiet")
    return out


@pytest.mark.parametrize("method,alpha", [("hybrid", None), ("l1", None), ("l2", None), ("l2", 0.5)])
def test_reconstruct_equals_tool(tmp_path, gradient_exr, method, alpha):
    out = tmp_path / "tool.exr"
    args = [gradient_exr, "--outfile", out, "--norm", method, "--no-png"]
    if alpha is not None:
        args += ["--alpha", str(alpha)]
    run_tool("reconstruct", *args)
    tool = gradus.read_image(out).layers[""]
    L = gradus.read_image(gradient_exr).layers
    assert "separated" in L  # the light seen directly: added after the solve, by the tool as here
    img, stats = gradus.reconstruct(L["primal"], L["dx"], L["dy"], method=method, alpha=alpha, return_stats=True,
                                    separated=L["separated"])
    assert img.shape == tool.shape and img.dtype == np.float32
    assert np.array_equal(bits(img), bits(tool))
    assert stats["norm"] == method and stats["alpha"] == (0.2 if alpha is None else alpha)
    assert gradus.read_image(out).metadata["reconstruction"] == stats["method"]


def test_weighted_reconstruction_equals_tool(tmp_path, gradient_exr):
    # Separate inputs with made-up positive variances (the tool's --primal ... --dy-var form).
    L = gradus.read_image(gradient_exr).layers
    rng = np.random.default_rng(3)
    arrays = {k: L[k] for k in ("primal", "dx", "dy")}
    for k in ("primal", "dx", "dy"):
        arrays[k + "_var"] = (L[k] ** 2 + rng.random(L[k].shape)).astype(np.float32)
    args = []
    for k, a in arrays.items():
        gradus.write_image(tmp_path / (k + ".exr"), {"": a})
        args += ["--" + k.replace("_", "-"), tmp_path / (k + ".exr")]
    run_tool("reconstruct", *args, "--norm", "weighted", "--outfile", tmp_path / "tool.exr", "--no-png")
    tool = gradus.read_image(tmp_path / "tool.exr").layers[""]
    img = gradus.reconstruct(arrays["primal"], arrays["dx"], arrays["dy"], method="weighted",
                             primal_var=arrays["primal_var"], dx_var=arrays["dx_var"], dy_var=arrays["dy_var"])
    assert np.array_equal(bits(img), bits(tool))


def test_reconstruct_arguments(gradient_exr):
    L = gradus.read_image(gradient_exr).layers
    with pytest.raises(ValueError, match="unknown preset"):
        gradus.reconstruct(L["primal"], L["dx"], L["dy"], method="l3")
    with pytest.raises(ValueError, match="size"):
        gradus.reconstruct(L["primal"], L["dx"][1:], L["dy"])
    with pytest.raises(gradus.Error, match="variance"):
        gradus.reconstruct(L["primal"], L["dx"], L["dy"], method="weighted")
    # Any float dtype is taken (converted to float32).
    a = gradus.reconstruct(L["primal"].astype(np.float64), L["dx"], L["dy"], method="l2")
    assert np.array_equal(a, gradus.reconstruct(L["primal"], L["dx"], L["dy"], method="l2"))
