"""Claims of the watch folder, in process against a real SQLite database: a killed watcher's claim
folder (its lock free) is taken over by the next scan, its half-written reason removed; a running
watcher's claim folder (its lock held) is left alone; the claim folder is given back on close."""

from __future__ import annotations

import fcntl
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from station.ingest import DatabaseDestination, Ingestor
from station.ingest.formats.records import ImportOptions
from station.ingest.formats.watch import DONE, PROCESSING, REJECTED, WatchFolder

CSV = "sample,geometry,L,a,b\np1,45as15,50,1,2\np1,45as45,40,1.5,2.5\n"


@pytest.fixture
def ingestor(tmp_path: Path, _migrated_sqlite: Path) -> Iterator[Ingestor]:
    db = tmp_path / "station.sqlite3"
    shutil.copyfile(_migrated_sqlite, db)
    destination = DatabaseDestination(f"sqlite:///{db}", migrate=False, source="cli")
    try:
        with Ingestor(destination, tmp_path / "outbox.sqlite3") as ing:
            yield ing
    finally:
        destination.close()


def test_a_killed_watchers_files_are_taken_over(tmp_path: Path, ingestor: Ingestor) -> None:
    drop = tmp_path / "drop"
    drop.mkdir()
    dead = drop / PROCESSING / "12345-deadbeef"
    dead.mkdir(parents=True, mode=0o700)
    (drop / PROCESSING).chmod(0o700)
    (dead / "a.csv").write_text(CSV)
    (dead / ".0f0f.reason").write_text("half a reas")
    live = drop / PROCESSING / "23456-cafecafe"
    live.mkdir(mode=0o700)
    (live / "b.csv").write_text(CSV)
    held = os.open(live, os.O_RDONLY | os.O_DIRECTORY)
    fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)  # a watcher still running holds its lock
    try:
        with WatchFolder(drop) as watcher:
            outcomes = watcher.scan(ingestor, ImportOptions("qa"), settle_s=0)
            mine = [p.name for p in (drop / PROCESSING).iterdir() if p.name not in ("23456-cafecafe",)]
            assert len(mine) == 1 and mine[0].startswith(f"{os.getpid()}-")
    finally:
        os.close(held)
    assert [(o.file, o.status) for o in outcomes] == [("a.csv", "done")]
    assert [r["status"] for r in outcomes[0].receipts] == ["stored"]
    assert sorted(p.name for p in (drop / PROCESSING).iterdir()) == ["23456-cafecafe"]
    assert (live / "b.csv").is_file() and (drop / DONE / "a.csv").is_file()
    assert list((drop / REJECTED).iterdir()) == []
