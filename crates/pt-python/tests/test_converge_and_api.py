"""converge() returns the table `pt converge` writes; the type stub covers the compiled
module; the README's examples run."""

import ast
import csv
import inspect
import re
from pathlib import Path

import pytest

import pt_renderer as pt
from pt_renderer import _pt_renderer as core

PACKAGE = Path(__file__).resolve().parents[1]


def test_converge_table_matches_its_csv(repo, tmp_path):
    lines = []
    result = pt.converge(
        repo / "scenes/cornell-box.xml",
        repo / "references/cornell-box.exr",
        spp=[1, 4, 16],
        strategies=["mis", "bsdf"],
        out=tmp_path / "cv",
        threads=2,
        log=lines.append,
    )
    table = result["table"]
    assert [(r["curve"], r["spp"]) for r in table] == [
        (c, s) for c in ("pt-mis", "pt-bsdf") for s in (1, 4, 16)
    ]
    # More samples, less error (a factor 16 in spp is a factor ~16 in relMSE; noise cannot
    # reverse it), and MIS beats BSDF sampling on the Cornell box's small light.
    for c in ("pt-mis", "pt-bsdf"):
        e = [r["relmse"] for r in table if r["curve"] == c]
        assert e[0] > e[1] > e[2]
    mis16 = next(r for r in table if r["curve"] == "pt-mis" and r["spp"] == 16)
    bsdf16 = next(r for r in table if r["curve"] == "pt-bsdf" and r["spp"] == 16)
    assert mis16["relmse"] < bsdf16["relmse"]
    with open(tmp_path / "cv" / "converge.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(table)
    for row, r in zip(rows, table):
        assert row["series"] == r["curve"] and int(row["spp"]) == r["spp"]
        assert float(row["relmse"]) == pytest.approx(r["relmse"], rel=1e-6)
    assert (tmp_path / "cv" / "converge.png").is_file()
    assert result["summary"] == (tmp_path / "cv" / "summary.txt").read_text()
    assert lines, "no progress lines logged"


def test_stub_covers_the_compiled_module():
    """Every public name of the compiled module has a declaration in _pt_renderer.pyi, and the
    functions' parameters agree with their Rust signatures."""
    stub = ast.parse((PACKAGE / "python" / "pt_renderer" / "_pt_renderer.pyi").read_text())
    declared = {}
    for node in stub.body:
        if isinstance(node, ast.FunctionDef):
            declared[node.name] = [a.arg for a in node.args.args]
        elif isinstance(node, ast.ClassDef):
            declared[node.name] = None
        elif isinstance(node, ast.AnnAssign):
            declared[node.target.id] = None
    public = {n for n in dir(core) if not n.startswith("_")}
    assert public <= set(declared), f"not in the stub: {sorted(public - set(declared))}"
    for name, params in declared.items():
        obj = getattr(core, name)
        if params is not None and callable(obj):
            sig = inspect.signature(obj)
            assert list(sig.parameters) == params, name
    assert (PACKAGE / "python" / "pt_renderer" / "py.typed").is_file()


def readme_blocks():
    text = (PACKAGE / "README.md").read_text()
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_readme_examples_run(repo, tmp_path, monkeypatch):
    """The README's Python blocks, run in order in one namespace (as a notebook runs them)."""
    blocks = readme_blocks()
    assert len(blocks) >= 4
    import matplotlib

    matplotlib.use("Agg")
    # The examples' relative paths, seen from a scratch folder that holds their outputs.
    for name in ("scenes", "references"):
        (tmp_path / name).symlink_to(repo / name)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for i, code in enumerate(blocks):
        exec(compile(code, f"README.md python block {i + 1}", "exec"), namespace)
