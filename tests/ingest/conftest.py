"""Ingest fixtures: migrated databases (tests.db), and one simulated reading written in every import format."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from tests.db._fixtures import (  # noqa: F401
    _migrated_pg,
    _migrated_sqlite,
    database_url,
    empty_database_url,
    pg_server,
    pg_url,
)
from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
FORMATS = ("cxf", "cgats", "csv")  # the text formats
ALL_FORMATS = (*FORMATS, "xlsx")


@pytest.fixture(scope="session")
def sim_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, object], dict[str, Path]]:
    """One simulated 12-geometry reading of the design ``std.json`` (returned folder), as the
    ``station measure --json`` output and as one file per format (``station measure --out``)."""
    from station.model.design_io import save_design
    from station.model.representations import FaceFlopTravelGloss

    d = tmp_path_factory.mktemp("sim")
    save_design(FaceFlopTravelGloss((80.0, -2.0, -20.0), (30.0, 1.0, -8.0), 60.0), d / "std.json")
    files = {f: d / f"std.{f}" for f in ALL_FORMATS}
    outs = [a for f in ALL_FORMATS for a in ("--out", str(files[f]))]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    res = run(
        [sys.executable, "-m", "station.cli", "measure", "sim:ma6", "--twelve", "--design", "std.json",
         "--sample", "std panel", *outs, "--json"],
        timeout=120, cwd=d, env=env,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout), files
