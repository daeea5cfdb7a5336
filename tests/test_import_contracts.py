"""The import contracts can fail: ``lint-imports`` run on a copy of the tree breaks the no-cycles contract
when a two-module cycle is planted, and a layering contract when the model imports a front."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

from tests.processes import run

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("station", "db", "ui", "simulators")
LINT = Path(sys.executable).with_name("lint-imports")


@pytest.fixture(scope="module")
def tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of the packages and pyproject.toml (no caches), checked clean before anything is planted."""
    root = tmp_path_factory.mktemp("tree")
    for name in PACKAGES:
        shutil.copytree(
            REPO / name, root / name, ignore=shutil.ignore_patterns("__pycache__", "*.npz", "*.hdr")
        )
    shutil.copy(REPO / "pyproject.toml", root / "pyproject.toml")
    return root


def _lint(root: Path) -> tuple[int, str]:
    env = {"PYTHONPATH": str(root), "PATH": str(LINT.parent)}
    done = run([str(LINT), "--no-cache"], cwd=root, env=env, timeout=300)
    return done.returncode, done.stdout + done.stderr


def test_the_tree_keeps_every_contract(tree: Path) -> None:
    code, out = _lint(tree)
    assert code == 0, out
    assert "No import cycles" in out and " 0 broken" in out


def test_a_planted_two_module_cycle_breaks_the_no_cycles_contract(tree: Path) -> None:
    planted = [tree / "station" / "qc" / "_planted_a.py", tree / "station" / "qc" / "_planted_b.py"]
    planted[0].write_text("from station.qc import _planted_b  # noqa: F401\n")
    planted[1].write_text("def f() -> None:\n    from station.qc import _planted_a  # noqa: F401\n")
    try:
        code, out = _lint(tree)
    finally:
        for p in planted:
            p.unlink()
    assert code == 1, out
    assert "No import cycles" in out and "BROKEN" in out and "_planted_" in out


def test_the_model_importing_a_front_breaks_the_layers(tree: Path) -> None:
    planted = tree / "station" / "model" / "_planted.py"
    planted.write_text("import station.cli  # noqa: F401\n")
    try:
        code, out = _lint(tree)
    finally:
        planted.unlink()
    assert code == 1, out
    assert "The model sits below everything else in station BROKEN" in out
