"""Outbox and database files are private: folder 0700, files (journals included) 0600, checked with os.stat;
the database file is only ever opened through SQLite, so processes sharing it lose nothing."""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

from sqlalchemy import text
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from db.files import NotRegularFileError
from station.ingest import Outbox
from tests.ingest.conftest import REPO
from tests.processes import Child
from tests.user_cli import run_station


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


def test_an_existing_outbox_keeps_its_mode(tmp_path: Path) -> None:
    """The product creates its files 0600 and never chmods a file that is already there."""
    path = tmp_path / "outbox.sqlite3"
    Outbox(path).close()
    os.chmod(path, 0o640)
    with Outbox(path) as outbox:
        outbox.put("c-1", "{}")
    assert _mode(path) == 0o640


def test_an_outbox_path_that_is_a_symlink_is_refused_naming_the_outbox(tmp_path: Path) -> None:
    """A link at the outbox path is refused with an error naming the outbox, and its target is left alone."""
    target = tmp_path / "elsewhere.txt"
    target.write_text("not ours")
    os.chmod(target, 0o644)
    link = tmp_path / "outbox.sqlite3"
    link.symlink_to(target)
    try:
        Outbox(link)
    except NotRegularFileError as exc:
        assert exc.field == "outbox" and "symlink" in str(exc)
    else:
        raise AssertionError("an outbox path that is a symlink was accepted")
    assert target.read_text() == "not ours" and _mode(target) == 0o644


def test_a_new_sqlite_database_is_private(tmp_path: Path) -> None:
    path = tmp_path / "data" / "station.sqlite3"
    engine = make_engine(f"sqlite:///{path}", poolclass=NullPool)
    with engine.begin() as conn:
        conn.execute(text("CREATE TABLE t (x INTEGER)"))
        conn.execute(text("INSERT INTO t VALUES (1)"))
        assert _mode(path.with_name("station.sqlite3-wal")) == 0o600
    engine.dispose()
    assert _mode(path.parent) == 0o700 and _mode(path) == 0o600


def _measurements(url: str) -> list[tuple[int, str]]:
    engine = make_engine(url, poolclass=NullPool)
    try:
        with engine.connect() as conn:
            rows = conn.execute(text("SELECT id, client_id FROM measurements ORDER BY id")).all()
    finally:
        engine.dispose()
    return [(int(r[0]), str(r[1])) for r in rows]


def test_two_processes_sharing_the_database_lose_no_reading(
    tmp_path: Path, _migrated_sqlite: Path, sim_files: tuple[dict[str, object], dict[str, Path]]
) -> None:
    """Found 1: a viewer-like process with open engines, an import from a terminal, the viewer's next scan.

    The holder stores a reading, creates more engines on the same file (the viewer makes three),
    ``station import FILE --store`` stores from its own process and exits, then the holder stores
    again. Every reading must be in the file once, under its own id, after both processes are gone.
    """
    db = tmp_path / "station.sqlite3"
    shutil.copyfile(_migrated_sqlite, db)
    url = f"sqlite:///{db}"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    env.pop("CACAD_DATABASE_URL", None)
    with Child(
        [sys.executable, "-m", "tests.db._engine_holder", url, str(tmp_path / "viewer-outbox.sqlite3"), "7"],
        stdin=subprocess.PIPE, cwd=REPO, env=env,
    ) as holder:  # fmt: skip
        assert holder.out is not None and holder.err is not None and holder.stdin is not None
        seen = holder.out.wait_for("ready\n", timeout=120)
        first = seen[: seen.index("ready\n") + len("ready\n")]  # the holder now waits for "go"
        lines = [line.strip() for line in first.splitlines()]
        assert len(lines) == 2 and lines[0].startswith("stored ") and lines[1] == "ready", (
            lines,
            holder.err.text(),
        )
        imported = run_station(
            tmp_path, "import", str(sim_files[1]["cxf"]), "--store", url,
            "--outbox", str(tmp_path / "cli-outbox.sqlite3"), "--json",
        )  # fmt: skip
        assert imported.returncode == 0, imported.stderr
        holder.stdin.write(b"go\n")
        holder.stdin.close()
        assert holder.finish(timeout=120) == 0, holder.err.text()
        out = holder.out.text()[len(first) :]
    stored = [int(line.split()[1]) for line in [lines[0], *out.split("\n")] if line.startswith("stored ")]
    rows = _measurements(url)
    imported_rows = [r for r in rows if r[0] not in stored]
    assert len(stored) == 2 and len(set(stored)) == 2, (stored, rows)
    assert len(rows) == 2 + len(imported_rows) and imported_rows, rows  # the import is still there
    assert len({r[1] for r in rows}) == len(rows), rows  # every reading once
    assert set(stored) <= {r[0] for r in rows}, (stored, rows)
