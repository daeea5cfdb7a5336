"""Engines and sessions for the embedded SQLite file or a shared PostgreSQL server.

SQLite runs in WAL mode with ``synchronous=FULL`` (a committed reading survives power loss), with
foreign keys enforced, a busy timeout, and ``BEGIN IMMEDIATE`` transactions so concurrent writers
queue on the lock instead of failing on a stale snapshot. PostgreSQL URLs use psycopg 3.
"""

from __future__ import annotations

import os
import sqlite3
import threading
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session, sessionmaker

from db.files import private_dir, private_sqlite
from station.errors import InputError

DEFAULT_DB_FILE = "station.sqlite3"
SQLITE_BUSY_TIMEOUT_MS = 2_000  # a locked database counts as away after 2 s (the reading goes to the outbox)
PG_CONNECT_TIMEOUT_S = 5


def data_dir() -> Path:
    """The workstation's data folder: ``$CACAD_DATA_DIR`` or ``./var``."""
    return Path(os.environ.get("CACAD_DATA_DIR") or "var").resolve()


def default_database_url(folder: Path | None = None) -> str:
    """The embedded SQLite database inside *folder* (default :func:`data_dir`)."""
    folder = folder or data_dir()
    return f"sqlite:///{(folder / DEFAULT_DB_FILE).as_posix()}"


def configured_database_url() -> str:
    """The database ``station serve`` uses: ``$CACAD_DATABASE_URL``, else :func:`default_database_url`
    (the embedded SQLite file in ``$CACAD_DATA_DIR`` or ``./var``)."""
    return os.environ.get("CACAD_DATABASE_URL") or default_database_url()


def normalise_url(url: str) -> str:
    """Accept ``postgres://``/``postgresql://`` and pin the psycopg 3 driver; refuse other backends."""
    try:
        parsed = make_url(url)
    except Exception as exc:
        raise InputError("database", "an SQLAlchemy URL (sqlite:///PATH or postgresql://…)", url) from exc
    backend = parsed.get_backend_name()
    if backend in ("postgres", "postgresql"):
        return parsed.set(drivername="postgresql+psycopg").render_as_string(hide_password=False)
    if backend == "sqlite":
        return url
    raise InputError("database", "sqlite:///PATH or postgresql://USER@HOST/DB", url)


def make_engine(
    url: str, *, foreign_keys: bool = True, busy_timeout_ms: int = SQLITE_BUSY_TIMEOUT_MS, **kwargs: Any
) -> Engine:
    """Create an engine for *url* with the workstation's durability settings.

    For SQLite the parent folder is created (0700) and the database file is private (0600, with its
    journals; see :mod:`db.files`). ``foreign_keys=False`` is only for batch migrations,
    which recreate tables that others reference. ``busy_timeout_ms`` is how long an SQLite writer
    waits for the lock before the database counts as unreachable.
    """
    url = normalise_url(url)
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite":
        kwargs.setdefault("pool_pre_ping", True)
        connect_args = kwargs.pop("connect_args", {})
        connect_args.setdefault("connect_timeout", PG_CONNECT_TIMEOUT_S)  # a dead host fails fast → outbox
        return create_engine(url, connect_args=connect_args, **kwargs)
    if parsed.database and parsed.database != ":memory:" and not parsed.database.startswith("file:"):
        folder = Path(parsed.database).parent
        if not folder.exists():
            private_dir(folder)
        private_sqlite(parsed.database)
    connect_args = kwargs.pop("connect_args", {})
    connect_args.setdefault("check_same_thread", False)
    connect_args.setdefault("timeout", busy_timeout_ms / 1000)
    engine = create_engine(url, connect_args=connect_args, **kwargs)

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_conn: Any, _record: Any) -> None:
        dbapi_conn.isolation_level = None  # we issue BEGIN ourselves (below)
        cur = dbapi_conn.cursor()
        cur.execute("PRAGMA journal_mode=WAL")
        cur.execute("PRAGMA synchronous=FULL")
        cur.execute(f"PRAGMA foreign_keys={'ON' if foreign_keys else 'OFF'}")
        cur.execute(f"PRAGMA busy_timeout={int(busy_timeout_ms)}")
        cur.close()

    # Writers of this engine queue on a lock of their own before BEGIN IMMEDIATE: SQLite's busy handler
    # polls with growing sleeps (up to 100 ms), which under concurrent writers of one process gives long,
    # unfair tails; a lock hands over at once. The wait stays bounded by the same busy timeout.
    writer = threading.Lock()
    wait_s = busy_timeout_ms / 1000

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Any) -> None:
        if not writer.acquire(timeout=wait_s):
            raise OperationalError(
                "BEGIN IMMEDIATE",
                None,
                sqlite3.OperationalError("database is locked (writers of this process)"),
            )
        try:
            conn.exec_driver_sql("BEGIN IMMEDIATE")
        except BaseException:
            writer.release()
            raise
        conn.info["cacad_writer"] = True

    @event.listens_for(engine, "commit")
    @event.listens_for(engine, "rollback")
    def _on_end(conn: Any) -> None:
        if conn.info.pop("cacad_writer", False):
            writer.release()

    return engine


def make_sessionmaker(engine: Engine) -> sessionmaker[Session]:
    """A session factory bound to *engine* (objects stay readable after commit)."""
    return sessionmaker(engine, expire_on_commit=False)
