"""Ctrl-C while ``station import FILE --store`` writes to an SQLite database: the command says it was
cancelled in one line (exit 130), stores nothing, and the next import in the same process stores.

The interrupt is raised by a ``before_cursor_execute`` hook on every engine (at the measurements table's
INSERT), inside the statement as a signal would land; before the writer queue's fix it came out as a
PendingRollbackError traceback and left the process's writer lock held (tests/db/test_interrupted_write.py
holds the engine alone).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import Engine, event

from tests.ingest.test_import_cli import _count  # measurements stored at a URL


@pytest.fixture
def interrupt_first_measurement_insert() -> Iterator[list[bool]]:
    """KeyboardInterrupt at the first INSERT into the measurements table of any engine; the flag is True
    until it fired."""
    armed = [True]

    def boom(conn, cursor, statement, parameters, context, executemany) -> None:
        if armed[0] and statement.lstrip().upper().startswith("INSERT INTO MEASUREMENTS"):
            armed[0] = False
            raise KeyboardInterrupt

    event.listen(Engine, "before_cursor_execute", boom)
    try:
        yield armed
    finally:
        event.remove(Engine, "before_cursor_execute", boom)


def test_ctrl_c_inside_the_store_cancels_in_one_line_and_the_next_import_stores(
    tmp_path: Path,
    _migrated_sqlite: Path,
    sim_files: tuple[dict[str, object], dict[str, Path]],
    interrupt_first_measurement_insert: list[bool],
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from station.cli import EXIT_INTERRUPTED, main

    db = tmp_path / "station.sqlite3"
    shutil.copyfile(_migrated_sqlite, db)
    url = f"sqlite:///{db}"
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
    assert main(args) == EXIT_INTERRUPTED
    assert interrupt_first_measurement_insert == [False]  # the interrupt landed in the store
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["cancelled (Ctrl+C)"], err
    assert _count(url) == 0
    assert main([*args, "--json"]) == 0  # the same process stores now: no writer lock left held
    stored = json.loads(capsys.readouterr().out)["stored"]
    assert [s["status"] for s in stored] == ["stored", "stored"]  # the file's two illumination blocks
    assert _count(url) == 2
