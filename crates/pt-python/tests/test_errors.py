"""Bad input becomes Python exceptions with the loader's file:line:column message; the
interpreter never crashes."""

import re

import numpy as np
import pytest

import pt_renderer as pt

LOCATED = re.compile(r":\d+:\d+: <")


def test_missing_scene_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError) as e:
        pt.load_file(tmp_path / "nope.xml")
    assert e.value.filename == str(tmp_path / "nope.xml")


def test_scene_errors_name_file_line_column_and_element(tmp_path):
    scene = tmp_path / "bad.xml"
    scene.write_text(
        '<scene version="3.0.0">\n'
        '  <shape type="obj">\n'
        '    <string name="filename" value="missing-mesh.obj"/>\n'
        "  </shape>\n"
        "</scene>\n"
    )
    with pytest.raises(pt.SceneError) as e:
        pt.load_file(scene)
    msg = str(e.value)
    assert msg.startswith(f"{scene}:2:3: <shape type=\"obj\">"), msg
    assert "missing-mesh.obj" in msg
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize(
    "xml, needle",
    [
        ('<scene version="3.0.0"><shape type="teapot"/></scene>', 'unknown shape plugin "teapot"'),
        ('<scene version="3.0.0"><bsdf type="diffuse"><float name="reflectanse" value="0.5"/></bsdf></scene>', "reflectanse"),
        ('<scene version="3.0.0"><shape type="sphere"><float name="radius" value="abc"/></shape></scene>', "abc"),
        ('<scene version="3.0.0"><shape type="sphere">', ""),
        ("not xml at all", ""),
    ],
)
def test_malformed_scenes_raise_scene_error(xml, needle):
    with pytest.raises(pt.SceneError) as e:
        pt.load_string(xml)
    assert needle in str(e.value)
    assert str(e.value).startswith("<string>:"), str(e.value)


def test_unknown_default_parameter_is_refused(repo):
    with pytest.raises(pt.SceneError, match="spq"):
        pt.load_file(repo / "scenes/cornell-box.xml", spq=4)


def test_image_errors(tmp_path):
    junk = tmp_path / "junk.exr"
    junk.write_bytes(b"not an exr")
    with pytest.raises(OSError):
        pt.read_exr(junk)
    with pytest.raises(FileNotFoundError):
        pt.read_exr(tmp_path / "missing.exr")
    with pytest.raises(ValueError):
        pt.write_exr(tmp_path / "x.exr", np.zeros((2, 2, 5)))
    with pytest.raises(OSError):
        pt.write_exr(tmp_path / "no-such-folder" / "x.exr", np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match="3x2 but the reference is 2x2"):
        pt.compare(np.zeros((2, 3, 3)), np.zeros((2, 2, 3)))


def test_bsdf_errors():
    with pytest.raises(pt.SceneError, match="unknown model 'velvet'"):
        pt.bsdf("velvet")
    with pytest.raises(pt.SceneError, match="alphaa"):
        pt.bsdf("roughconductor", alphaa=0.1)
    with pytest.raises(pt.SceneError, match="unobtainium"):
        pt.bsdf("roughconductor", material="unobtainium")
    b = pt.bsdf("diffuse", mode="spectral")
    with pytest.raises(ValueError, match="needs wavelengths"):
        b.eval([0, 0, 1], [0, 0, 1])
    with pytest.raises(ValueError, match="takes no wavelengths"):
        pt.bsdf("diffuse").eval([0, 0, 1], [0, 0, 1], wavelengths=[500.0])
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        pt.bsdf("diffuse").eval([0, 1], [0, 0, 1])
