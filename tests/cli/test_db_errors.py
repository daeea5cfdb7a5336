"""The admin commands driven as a user would, by subprocess from an empty folder.

A database that cannot be reached (PostgreSQL on a closed port, an SQLite file under a path that is
not a folder) or a revision that does not exist: one line on stderr, exit status 2, no traceback, for
every command that opens the database. ``users add`` refuses the names the API refuses.
"""

from __future__ import annotations

import socket
import stat
import subprocess
from pathlib import Path

import pytest

from tests.user_cli import run_station

#: About twenty ``station`` processes: a long file, run early (tests/conftest.py orders the files).
pytestmark = pytest.mark.slow


def _station(cwd: Path, *args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return run_station(cwd, *args, env=env, timeout=120)


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]  # nothing listens once the socket is closed


COMMANDS = (
    ("db", "upgrade"),
    ("db", "current"),
    ("db", "verify"),
    ("db", "downgrade"),
    ("users", "list"),
    ("users", "add", "ana"),
    ("serve", "--simulators", "", "--no-demo-library"),
)


@pytest.mark.parametrize("where", ["postgres-closed-port", "sqlite-under-a-file"])
def test_unreachable_database_is_one_line_and_exit_2(tmp_path: Path, where: str) -> None:
    if where == "postgres-closed-port":
        url = f"postgresql://cacad:secret@127.0.0.1:{_closed_port()}/cacad"
    else:
        (tmp_path / "not-a-folder").write_text("")
        url = f"sqlite:///{tmp_path / 'not-a-folder' / 'station.sqlite3'}"
    for command in COMMANDS:
        done = _station(tmp_path, *command, "--database", url)
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2, (command, done.stderr)
        assert len(lines) == 1 and "Traceback" not in done.stderr, (command, done.stderr)
        assert lines[0].startswith("error: database:") and "secret" not in lines[0], (command, lines[0])
        # serve announces its start-up steps on stdout ("…" lines) before it fails; nothing else
        progress = [x for x in done.stdout.splitlines() if not x.endswith("…")]
        assert progress == [] and (command[0] == "serve" or done.stdout == ""), (command, done.stdout)


@pytest.mark.parametrize("action", ["upgrade", "downgrade"])
def test_unknown_revision_is_one_line_and_exit_2(tmp_path: Path, action: str) -> None:
    done = _station(tmp_path, "db", action, "9999", "--data-dir", "data")
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [done.stderr.strip()] and "Traceback" not in done.stderr
    assert "revision" in done.stderr and "9999" in done.stderr


@pytest.mark.parametrize(
    ("name", "field"),
    [("has space", "name"), ("x" * 65, "name"), ("semi;colon", "name"), ("", "name"), ("ünï", "name")],
)
def test_users_add_validates_names_like_the_api(tmp_path: Path, name: str, field: str) -> None:
    import pydantic

    from station.api.schemas.users import UserCreate

    with pytest.raises(pydantic.ValidationError):  # the API's own rule refuses it too
        UserCreate(name=name, role="technician")  # type: ignore[arg-type]
    done = _station(tmp_path, "users", "add", name, "--data-dir", "data")
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"error: {field}") and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "data" / "station.sqlite3").exists()  # refused before the database is opened


def test_users_add_accepts_what_the_api_accepts_in_a_private_data_folder(tmp_path: Path) -> None:
    done = _station(tmp_path, "users", "add", "ana.b-2@lab_1", "--data-dir", "data", "--json")
    assert done.returncode == 0, done.stderr
    assert stat.S_IMODE((tmp_path / "data").stat().st_mode) == 0o700
    assert stat.S_IMODE((tmp_path / "data" / "station.sqlite3").stat().st_mode) == 0o600
    done = _station(tmp_path, "db", "verify", "--data-dir", "data")
    assert done.returncode == 0 and "intact" in done.stdout, done.stderr
