"""Shared fixtures: the repository, the `pt` binary the CLI comparisons run, a scratch folder."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def pt_bin() -> Path:
    """The `pt` command line: $PT_BIN, else target/debug/pt or target/release/pt of this
    repository (built by `cargo test` / `cargo build`). Missing is a failure, not a skip: the
    bit-for-bit tests are the point of the suite."""
    env = os.environ.get("PT_BIN")
    candidates = [Path(env)] if env else [REPO / "target" / "debug" / "pt", REPO / "target" / "release" / "pt"]
    for c in candidates:
        if c.is_file():
            return c
    found = shutil.which("pt") if not env else None
    if found:
        return Path(found)
    pytest.fail(f"no pt binary: set PT_BIN or build it (looked for {', '.join(map(str, candidates))})")


def run_pt(pt_bin: Path, *args, cwd=None, check=True) -> subprocess.CompletedProcess:
    """Runs `pt ARGS...`, returning the completed process (stdout and stderr as text)."""
    p = subprocess.run([str(pt_bin), *map(str, args)], cwd=cwd, capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"pt {' '.join(map(str, args))} exited {p.returncode}:\n{p.stderr}")
    return p
