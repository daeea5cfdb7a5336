"""``python -m bench.service_load`` runs end to end in a tiny mode: a real ``station serve``, 2 client
processes, one raw-insert phase and one service phase of a second each on SQLite, every reading
stored exactly once, the ratio and the load average reported, docs/ left alone. Only the exit
status and the report's shape are checked, never a figure (the machine's load decides those)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
DEADLINE_S = 300  # the whole run, service start-up included, on a loaded machine


@pytest.mark.slow
def test_service_load_runs_in_a_tiny_mode() -> None:
    report = REPO / "docs" / "benchmarks.md"
    before = report.read_bytes() if report.exists() else b""
    cmd = [sys.executable, "-m", "bench.service_load", "--clients", "2", "--rounds", "1", "--duration", "1"]
    cmd += ["--no-postgres", "--no-report"]
    # its own process group: its service and client processes go with it on a timeout
    done = run(cmd, cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)), timeout=DEADLINE_S)
    out = done.stdout + done.stderr
    assert done.returncode == 0, out[-3000:]
    first = out.splitlines()[0] if out else ""
    assert first.startswith("exactly once: PASS; SQLite "), out[-3000:]
    assert "× raw (bar 0.5×)" in first and "(bar 150 ms)" in first
    for line in (
        "SQLite: service ingest, 2 clients",
        "SQLite: raw SQLAlchemy inserts, 2 threads",
        "SQLite: service / raw throughput",
        "SQLite: service latency p99",
        "SQLite: load average during the run",
        "SQLite: rows stored / distinct sent",
    ):
        assert line in out, line
    assert (report.read_bytes() if report.exists() else b"") == before
