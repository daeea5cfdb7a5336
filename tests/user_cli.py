"""``station`` run as a user runs it: a subprocess in the user's own folder (not the repository).

The checkout is put on ``PYTHONPATH`` (the console script of an installed copy would do the same), the
demo-library cache goes to ``CWD/cache`` unless the caller's *env* says otherwise, and
``CACAD_DATABASE_URL`` is dropped so a developer's own database is never touched.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

from tests.processes import run

REPO = Path(__file__).resolve().parents[1]


def run_station(
    cwd: Path, *args: str, env: Mapping[str, str] | None = None, timeout: float = 300
) -> subprocess.CompletedProcess[str]:
    """``python -m station.cli ARGS`` in *cwd*, with extra environment *env*; output captured as text.
    Past *timeout* seconds the command and everything it started are killed (``TimeoutExpired``)."""
    full = dict(os.environ, PYTHONPATH=str(REPO), STATION_CACHE_DIR=str(Path(cwd) / "cache"))
    full.pop("CACAD_DATABASE_URL", None)
    full.update(env or {})
    return run([sys.executable, "-m", "station.cli", *args], cwd=cwd, env=full, timeout=timeout)
