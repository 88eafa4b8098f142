"""Errors raise gradus.SceneError with the place the command line names."""
import os
import re
import subprocess

import pytest

import gradus
from conftest import BIN, CORNELL

HEAD = 'Film "image" "integer xresolution" [8] "integer yresolution" [8]\nCamera "perspective"\nWorldBegin\n'


def cli_location(scene):
    """file, line, column of gradus's error message for the scene."""
    r = subprocess.run([os.path.join(BIN, "gradus"), scene, "--quiet", "--outfile",
                        os.path.join(os.path.dirname(scene), "out.exr")],
                       capture_output=True, text=True)
    assert r.returncode == 1
    m = re.match(r"(.*):(\d+):(\d+): ", r.stderr)
    return m.group(1), int(m.group(2)), int(m.group(3))


def test_missing_file():
    with pytest.raises(gradus.SceneError, match="cannot open") as e:
        gradus.load_scene("/nonexistent/scene.pbrt")
    assert e.value.file == "/nonexistent/scene.pbrt" and e.value.line is None and e.value.column is None


def test_syntax_error_has_line_and_column(tmp_path):
    scene = tmp_path / "syntax.pbrt"
    scene.write_text(HEAD + 'Shape "sphere" "float radius" [ 1 ] ]\nWorldEnd\n')
    with pytest.raises(gradus.SceneError) as e:
        gradus.load_scene(scene)
    assert (e.value.file, e.value.line, e.value.column) == (str(scene), 4, 37)
    assert (e.value.file, e.value.line, e.value.column) == cli_location(str(scene))
    assert str(e.value).startswith("%s:4:37: " % scene)


def test_error_in_an_included_file_names_it(tmp_path):
    (tmp_path / "part.pbrt").write_text('\n\nMaterial "matte" "rgb Kd" [ 0.5 0.5 ]\n')
    scene = tmp_path / "main.pbrt"
    scene.write_text(HEAD + 'Include "part.pbrt"\nWorldEnd\n')
    with pytest.raises(gradus.SceneError) as e:
        gradus.load_scene(scene)
    assert e.value.file.endswith("part.pbrt") and e.value.line == 3
    assert (e.value.file, e.value.line, e.value.column) == cli_location(str(scene))


def test_misspelt_scene_parameter(tmp_path):
    scene = tmp_path / "misspelt.pbrt"
    scene.write_text(HEAD + 'LightSource "point"\nShape "sphere" "float radiuss" [ 1 ]\nWorldEnd\n')
    with pytest.raises(gradus.SceneError, match="radiuss") as e:
        gradus.load_scene(scene)
    assert (e.value.file, e.value.line) == (str(scene), 5)
    assert (e.value.file, e.value.line, e.value.column) == cli_location(str(scene))


def test_misspelt_render_parameter_and_unknown_integrator(tiny_cornell):
    with pytest.raises(gradus.SceneError, match='no parameter "maxdepht"') as e:
        tiny_cornell.render(integrator="path", spp=1, params={"maxdepht": 3})
    assert e.value.file == "<command line --param>"
    with pytest.raises(gradus.SceneError, match="pathh"):
        tiny_cornell.render(integrator="pathh", spp=1)
    with pytest.raises(gradus.SceneError, match="expects integer"):
        tiny_cornell.render(integrator="path", spp=1, params={"maxdepth": 1.5})
    # Nothing is left behind: the next render works.
    assert tiny_cornell.render(spp=1).stats["spp"] == 1


def test_gltf_error_has_json_line_and_column(tmp_path):
    scene = tmp_path / "bad.gltf"
    scene.write_text('{\n  "asset": {"version": "2.0"},\n  "scenes": [{"nodes": [5]}],\n  "scene": 0\n}\n')
    with pytest.raises(gradus.SceneError) as e:
        gradus.load_scene(scene)
    assert e.value.file == str(scene) and e.value.line == 3
    assert (e.value.file, e.value.line, e.value.column) == cli_location(str(scene))


def test_bad_arguments(tiny_cornell):
    with pytest.raises(TypeError, match="unknown override"):
        gradus.load_scene(CORNELL, resolutoin=(8, 8))
    with pytest.raises(ValueError):
        gradus.load_scene(CORNELL, resolution=(0, 8))
    with pytest.raises(ValueError):
        gradus.load_scene(CORNELL, camera="Main")  # glTF only
    with pytest.raises(ValueError):
        tiny_cornell.render(spp=0)
    with pytest.raises(ValueError):
        tiny_cornell.render(time=-1)
    with pytest.raises(ValueError):
        tiny_cornell.render(seed=-1)
    with pytest.raises(TypeError):
        tiny_cornell.render(params={"maxdepth": object()})
