"""Outbox and database files are private: folder 0700, files (journals included) 0600, checked with os.stat."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from sqlalchemy import text
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from station.ingest import Outbox


def _mode(path: Path) -> int:
    return stat.S_IMODE(os.stat(path).st_mode)


def test_outbox_is_private_with_its_journals(tmp_path: Path) -> None:
    path = tmp_path / "new-folder" / "outbox.sqlite3"
    with Outbox(path) as outbox:
        outbox.put("c-1", "{}")
        assert _mode(path.parent) == 0o700
        journals = [path.with_name(path.name + s) for s in ("-wal", "-shm")]
        assert all(j.exists() for j in journals)
        assert [_mode(p) for p in (path, *journals)] == [0o600, 0o600, 0o600]


def test_an_existing_world_readable_outbox_is_tightened(tmp_path: Path) -> None:
    path = tmp_path / "outbox.sqlite3"
    Outbox(path).close()
    os.chmod(path, 0o644)
    Outbox(path).close()
    assert _mode(path) == 0o600


def test_a_new_sqlite_database_is_private(tmp_path: Path) -> None:
    path = tmp_path / "data" / "station.sqlite3"
    engine = make_engine(f"sqlite:///{path}", poolclass=NullPool)
    with engine.begin() as conn:
        conn.execute(text("CREATE TABLE t (x INTEGER)"))
        conn.execute(text("INSERT INTO t VALUES (1)"))
        assert _mode(path.with_name("station.sqlite3-wal")) == 0o600
    engine.dispose()
    assert _mode(path.parent) == 0o700 and _mode(path) == 0o600
