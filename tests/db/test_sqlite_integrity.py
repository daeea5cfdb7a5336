"""The product touches only its own files: a database path that is not a regular file is refused with one
line naming it, and no existing file or folder has its mode changed (issue 24 Found 2).

Every path here is one the test made (a FIFO, a folder, symlinks to files it wrote); modes are read with
``os.lstat``/``os.stat`` before and after. ``/dev/null`` is only looked at: its mode before and after
``station db verify`` must be the same. The CLI runs as a user runs it, in a subprocess from a
temporary folder, with a deadline (opening a FIFO for writing would block for ever).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from sqlalchemy import text
from sqlalchemy.pool import NullPool

from db.engine import make_engine
from db.files import NotRegularFileError, private_dir, write_private_text
from tests.user_cli import run_station

CLI_DEADLINE_S = 120


def _mode(path: Path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def _refused(cwd: Path, target: Path) -> str:
    """``station db verify`` on *target*: exit status 2 and one line on stderr; that line."""
    res = run_station(cwd, "db", "verify", "--database", f"sqlite:///{target}", timeout=CLI_DEADLINE_S)
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert str(target) in lines[0] and "database" in lines[0], lines[0]
    return lines[0]


def test_dev_null_is_refused_and_keeps_its_mode(tmp_path: Path) -> None:
    dev_null = Path("/dev/null")
    before = os.stat(dev_null)
    assert stat.S_ISCHR(before.st_mode)
    line = _refused(tmp_path, dev_null)
    assert "character device" in line, line
    after = os.stat(dev_null)
    assert stat.S_IMODE(after.st_mode) == stat.S_IMODE(before.st_mode)


def test_a_fifo_is_refused_and_keeps_its_mode(tmp_path: Path) -> None:
    fifo = tmp_path / "station.sqlite3"
    os.mkfifo(fifo, 0o644)
    line = _refused(tmp_path, fifo)
    assert "FIFO" in line, line
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and _mode(fifo) == 0o644


def test_a_symlink_is_refused_and_neither_it_nor_its_target_changes(tmp_path: Path) -> None:
    target = tmp_path / "elsewhere.sqlite3"
    target.write_bytes(b"")
    os.chmod(target, 0o644)
    link = tmp_path / "station.sqlite3"
    link.symlink_to(target)
    line = _refused(tmp_path, link)
    assert "symlink" in line, line
    assert link.is_symlink() and _mode(target) == 0o644 and target.read_bytes() == b""


def test_a_folder_is_refused_and_keeps_its_mode(tmp_path: Path) -> None:
    folder = tmp_path / "station.sqlite3"
    folder.mkdir(mode=0o755)
    os.chmod(folder, 0o755)
    line = _refused(tmp_path, folder)
    assert "folder" in line, line
    assert _mode(folder) == 0o755 and not any(folder.iterdir())


def test_a_journal_name_taken_by_a_symlink_refuses_the_database(tmp_path: Path) -> None:
    target = tmp_path / "victim"
    target.write_text("precious\n")
    db = tmp_path / "station.sqlite3"
    (tmp_path / "station.sqlite3-wal").symlink_to(target)
    with pytest.raises(NotRegularFileError, match="symlink"):
        make_engine(f"sqlite:///{db}")
    assert not db.exists() and target.read_text() == "precious\n"


def test_in_process_refusal_names_the_path_and_creates_nothing(tmp_path: Path) -> None:
    link = tmp_path / "db-link"
    link.symlink_to(tmp_path / "missing" / "station.sqlite3")  # dangling: must not be created through
    with pytest.raises(NotRegularFileError) as caught:
        make_engine(f"sqlite:///{link}")
    assert caught.value.field == "database" and str(link) in str(caught.value)
    assert not (tmp_path / "missing").exists()


def test_an_existing_database_and_its_folder_keep_their_modes(tmp_path: Path) -> None:
    folder = tmp_path / "shared"
    folder.mkdir()
    os.chmod(folder, 0o755)
    db = folder / "station.sqlite3"
    engine = make_engine(f"sqlite:///{db}", poolclass=NullPool)
    with engine.begin() as conn:
        conn.execute(text("CREATE TABLE t (x INTEGER)"))
    engine.dispose()
    assert _mode(db) == 0o600 and _mode(folder) == 0o755  # created by the product: 0600; folder as it was
    os.chmod(db, 0o640)
    engine = make_engine(f"sqlite:///{db}", poolclass=NullPool)
    with engine.begin() as conn:
        conn.execute(text("INSERT INTO t VALUES (1)"))
    engine.dispose()
    assert _mode(db) == 0o640 and _mode(folder) == 0o755


def test_the_data_folder_is_created_private_level_by_level_and_an_existing_one_is_left_alone(
    tmp_path: Path,
) -> None:
    existing = tmp_path / "lab"
    existing.mkdir()
    os.chmod(existing, 0o777)
    created = private_dir(existing / "a" / "b")
    assert [_mode(p) for p in (existing, existing / "a", created)] == [0o777, 0o700, 0o700]
    private_dir(existing)
    assert _mode(existing) == 0o777


def test_the_service_starts_in_an_existing_data_folder_without_changing_its_mode(tmp_path: Path) -> None:
    """``CACAD_DATA_DIR=/tmp`` must not make /tmp 0700: the service's start-up leaves the folder as it is."""
    from fastapi.testclient import TestClient

    from station.api import Settings, create_app

    data = tmp_path / "data"
    data.mkdir()
    os.chmod(data, 0o750)
    settings = Settings(data_dir=data, simulators=(), load_demo_library=False)
    with TestClient(create_app(settings)) as client:
        assert client.get("/health").json()["status"] == "ok"
    assert _mode(data) == 0o750 and _mode(data / "station.sqlite3") == 0o600


def test_a_private_text_replaces_a_symlink_instead_of_writing_through_it(tmp_path: Path) -> None:
    target = tmp_path / "victim"
    target.write_text("precious\n")
    os.chmod(target, 0o644)
    link = tmp_path / "bootstrap-token"
    link.symlink_to(target)
    write_private_text(link, "secret\n")
    assert target.read_text() == "precious\n" and _mode(target) == 0o644
    assert not link.is_symlink() and link.read_text() == "secret\n" and _mode(link) == 0o600
