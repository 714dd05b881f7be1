"""EXR input and output, and compare() against the figures `pt compare` prints."""

import re

import numpy as np
import pytest

import pt_renderer as pt
from conftest import run_pt


def test_exr_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    img = rng.random((5, 7, 3), dtype=np.float32) * 10
    path = tmp_path / "a.exr"
    pt.write_exr(path, img)
    assert np.array_equal(pt.read_exr(path), img)
    ch = pt.read_exr_channels(path)
    assert set(ch) == {"R", "G", "B"} and np.array_equal(ch["G"], img[:, :, 1])
    pt.write_exr(tmp_path / "y.exr", img[:, :, 0])
    assert list(pt.read_exr_channels(tmp_path / "y.exr")) == ["Y"]
    pt.write_exr(tmp_path / "n.exr", img[:, :, :2], channels=["depth", "id"])
    assert set(pt.read_exr_channels(tmp_path / "n.exr")) == {"depth", "id"}
    # Atomic: nothing but the outputs in the folder.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.exr", "n.exr", "y.exr"]


def cli_figures(text: str) -> dict:
    """The numbers of `pt compare`'s table."""
    out = {}
    for key in ("relMSE", "RMSE", "MAE", "mean ratio"):
        m = re.search(rf"^{key}\s+(\S+)\s+(\S+)\s+(\S+)", text, re.M)
        out[key] = [float(x) for x in m.groups()]
    out["FLIP"] = float(re.search(r"^FLIP\s+(\S+)", text, re.M).group(1))
    m = re.search(r"max \|z\| (\S+), (\d+) of (\d+) block-channels fail .* chi2 (\S+) on", text)
    out["z"] = (float(m.group(1)), int(m.group(2)), int(m.group(3)), float(m.group(4)))
    return out


def test_compare_gives_the_figures_pt_compare_prints(repo, pt_bin, tmp_path):
    """A 16-spp render against the Mitsuba reference of the Cornell box: every figure equals the
    CLI's to its printed digits, and the verdict is the CLI's exit code."""
    img_path = tmp_path / "img.exr"
    run_pt(pt_bin, "render", repo / "scenes/cornell-box.xml", "--spp", "16", "--seed", "11", "-o", img_path, "--variance", "--quiet")
    ref = repo / "references/cornell-box.exr"
    ref_var = repo / "references/cornell-box_var.exr"
    p = run_pt(pt_bin, "compare", img_path, ref, check=False)
    assert p.returncode in (0, 1), p.stderr
    cli = cli_figures(p.stdout)
    c = pt.compare(
        pt.read_exr(img_path),
        pt.read_exr(ref),
        image_variance=pt.read_exr(tmp_path / "img_var.exr"),
        reference_variance=pt.read_exr(ref_var),
    )
    for key, name in (("relmse", "relMSE"), ("rmse", "RMSE"), ("mae", "MAE"), ("mean_ratio", "mean ratio")):
        # Printed with 7 significant digits (%.6e).
        assert np.allclose(c[key], cli[name], rtol=1e-6, atol=0), key
    assert c["flip"] == pytest.approx(cli["FLIP"], abs=1e-6)
    z = c["ztest"]
    assert z["max_abs_z"] == pytest.approx(cli["z"][0], abs=0.005)
    assert (z["failed"], z["tests"]) == cli["z"][1:3]
    assert z["chi2"] == pytest.approx(cli["z"][3], abs=0.05)
    assert c["agree"] == (p.returncode == 0)
    assert c["flip_map"].shape == (256, 256)
    # Without variances there is no z-test, and the verdict rests on finite pixels alone.
    c2 = pt.compare(pt.read_exr(img_path), pt.read_exr(ref))
    assert c2["ztest"] is None and c2["agree"]


def test_compare_detects_a_two_percent_bias(repo):
    """The block z-test of a render scaled by 1.02 against the reference fails; the render
    itself passes. 256 spp: the block means' noise is well below 2% of the box's radiance."""
    scene = pt.load_file(repo / "scenes/cornell-box.xml")
    img, var = pt.render(scene, spp=256, seed=21, variance=True)
    ref = pt.read_exr(repo / "references/cornell-box.exr")
    ref_var = pt.read_exr(repo / "references/cornell-box_var.exr")
    assert pt.compare(img, ref, var, ref_var)["agree"]
    biased = pt.compare(img * 1.02, ref, var * 1.02**2, ref_var)
    assert not biased["agree"] and not biased["ztest"]["pass"]
