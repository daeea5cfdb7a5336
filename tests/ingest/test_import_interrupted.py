"""Ctrl-C while ``station import FILE --store`` writes to an SQLite database: the command says it was
cancelled in one line (exit 130), stores nothing, and the next import in the same process stores.

The interrupt comes from :func:`tests.db._interrupt.interrupt_at` on every engine, at the measurements
table's INSERT; before the writer queue's fix it came out as a
PendingRollbackError traceback and left the process's writer lock held (tests/db/test_interrupted_write.py
holds the engine alone).
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from sqlalchemy import Engine

from tests.db._interrupt import interrupt_at
from tests.ingest.test_import_cli import _count  # measurements stored at a URL


@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)  # the writer queue is SQLite's
def test_ctrl_c_inside_the_store_cancels_in_one_line_and_the_next_import_stores(
    tmp_path: Path,
    database_url: str,
    sim_files: tuple[dict[str, object], dict[str, Path]],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from station.cli import EXIT_INTERRUPTED, main

    url = database_url
    shutil.copy(sim_files[1]["cgats"], tmp_path / "std.cgats")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("CACAD_OPERATOR", "qa")
    args = [
        "import",
        "std.cgats",
        "--store",
        url,
        "--outbox",
        "outbox.sqlite3",
        "--job",
        "J-1",
        "--part",
        "door",
    ]
    capsys.readouterr()
    with interrupt_at(Engine, "INSERT INTO measurements") as armed:  # any engine the command makes
        assert main(args) == EXIT_INTERRUPTED
    assert armed == [False]  # the interrupt landed in the store
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["cancelled (Ctrl+C)"], err
    assert _count(url) == 0
    assert main([*args, "--json"]) == 0  # the same process stores now: no writer lock left held
    stored = json.loads(capsys.readouterr().out)["stored"]
    assert [s["status"] for s in stored] == ["stored", "stored"]  # the file's two illumination blocks
    assert _count(url) == 2
