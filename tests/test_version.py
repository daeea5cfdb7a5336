"""The version lives in one place (``station.__version__``) and every front reports the same one.

Independent sources compared: the installed package metadata (built from pyproject.toml), the
pyproject.toml declaration resolved by setuptools, the ``station --version`` output of a fresh
interpreter, and the service's OpenAPI document.
"""

from __future__ import annotations

import importlib.metadata
import os
import sys
import tomllib
import warnings
from pathlib import Path

import pytest

import station
from tests.processes import run

ROOT = Path(__file__).resolve().parents[1]
DISTRIBUTION = "cacad-station"


def test_pyproject_reads_the_version_from_the_package() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" not in project["project"], "pyproject.toml must not repeat the version"
    assert "version" in project["project"]["dynamic"]
    assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "station.__version__"}


def test_setuptools_resolves_the_same_version() -> None:
    from setuptools.config.pyprojecttoml import read_configuration

    with warnings.catch_warnings():  # setuptools flags every [tool.setuptools] table as beta
        warnings.filterwarnings("ignore", message=r"Support for `\[tool\.setuptools\]`")
        config = read_configuration(ROOT / "pyproject.toml", expand=True)
    assert config["project"]["version"] == station.__version__


def test_installed_metadata_agrees() -> None:
    try:
        installed = importlib.metadata.version(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        pytest.skip(f"{DISTRIBUTION} is not installed (pip install -e .)")
    assert installed == station.__version__


def test_cli_version_agrees() -> None:
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
    }
    out = run([sys.executable, "-m", "station.cli", "--version"], env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"station {station.__version__}"


def test_openapi_version_agrees(tmp_path: Path) -> None:
    from station.api import Settings, create_app

    app = create_app(
        Settings(
            database_url=f"sqlite:///{tmp_path / 'version.db'}",
            data_dir=tmp_path,
            simulators=(),
            load_demo_library=False,
        )
    )
    assert app.openapi()["info"]["version"] == station.__version__


def test_no_second_copy_of_the_version_string() -> None:
    literal = f'"{station.__version__}"'
    copies = [
        str(path.relative_to(ROOT))
        for package in ("station", "db", "ui", "simulators")
        for path in (ROOT / package).rglob("*.py")
        if path != ROOT / "station" / "__init__.py" and literal in path.read_text(encoding="utf-8")
    ]
    assert copies == [], f"the version is written again in {copies}; import station.__version__"
