"""Root test configuration shared by every suite.

Suites keep their own fixtures in ``tests/<area>/conftest.py``. Qt runs on the offscreen platform
unless a suite (the viewer's GL tests under Xvfb) sets another.

The suite runs in parallel (pytest-xdist, ``scripts/test.sh``): every pytest process (worker) has its
own temporary folders (``tmp_path``), its own disk caches (below), its own throwaway PostgreSQL
databases (``tests/db/_fixtures.py``), free loopback ports and, in the viewer suite, its own Xvfb display.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import pytest

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session", autouse=True)
def _private_caches(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The product's disk caches in this pytest process's own temporary folder.

    ``$STATION_CACHE_DIR`` (the demo library, ``station.formulate.demo``) and ``$CACAD_CACHE_DIR``
    (prefiltered cube maps, ``station.render.envcache``) otherwise default to folders under ``$HOME``,
    which parallel workers and other checkouts would share (the demo library is written through one
    fixed temporary name, so two processes generating it at once would write the same file). A worker
    generates the demo library once (about 4 s). Subprocesses inherit the variables.
    """
    root = tmp_path_factory.mktemp("cache")
    patch = pytest.MonkeyPatch()
    patch.setenv("STATION_CACHE_DIR", str(root / "station"))
    patch.setenv("CACAD_CACHE_DIR", str(root / "cacad"))
    yield root
    patch.undo()


@pytest.fixture(scope="session")
def bright_silver():
    """The shared bright aluminium silver (L*15 = 125, flop L* 38, travel 65°, 90 GU) of every package's
    ``test_bright_silver.py``: ``station.model.examples.BRIGHT_SILVER``."""
    from station.model.examples import BRIGHT_SILVER

    return BRIGHT_SILVER


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """The ../shared folder beside the checkout (skips when absent)."""
    if not SHARED.is_dir():
        pytest.skip(f"../shared not found at {SHARED}")
    return SHARED


@pytest.fixture(scope="session")
def hdri_files(shared_dir: Path) -> list[Path]:
    """Every photographed HDR environment in ../shared/data/hdri (skips when there are none)."""
    folder = shared_dir / "data" / "hdri"
    files = sorted(folder.glob("*.hdr")) + sorted(folder.glob("*.exr")) if folder.is_dir() else []
    if not files:
        pytest.skip(f"no HDR environments in {folder}")
    return files
