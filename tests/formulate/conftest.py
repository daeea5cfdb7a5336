"""Fixtures of the formulation suite: small synthetic libraries (fast) and an isolated cache folder."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.formulate.demo import generate_library
from station.formulate.library import Library


@pytest.fixture(scope="session", autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Point the demo-library cache at a temporary folder so tests never write to $HOME."""
    path = tmp_path_factory.mktemp("station-cache")
    old = os.environ.get("STATION_CACHE_DIR")
    os.environ["STATION_CACHE_DIR"] = str(path)
    yield path
    if old is None:
        os.environ.pop("STATION_CACHE_DIR", None)
    else:
        os.environ["STATION_CACHE_DIR"] = old


@pytest.fixture(scope="session")
def small_library() -> Library:
    """A 240-paint SYNTHETIC library from the colorant model (seed 11)."""
    return generate_library(120, 80, 40, seed=11)
