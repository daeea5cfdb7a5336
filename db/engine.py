"""Engines and sessions for the embedded SQLite file or a shared PostgreSQL server.

SQLite runs in WAL mode with ``synchronous=FULL`` (a committed reading survives power loss), with
foreign keys enforced and a busy timeout. A transaction that may write begins ``BEGIN IMMEDIATE``, so
concurrent writers queue on the lock instead of failing on a stale snapshot; that is the default for
every session and connection. Code that only reads uses :func:`reading` (or
``make_sessionmaker(engine, read_only=True)``): its transactions begin deferred (``BEGIN``), which in
WAL mode never wait for a writer and never make one wait, and run with ``PRAGMA query_only`` so a
write slipped into a read path fails loudly ("attempt to write a readonly database") instead of
racing the writers. On PostgreSQL the same read path runs ``READ ONLY`` transactions.

The database file itself is only ever opened by SQLite (see :mod:`db.files`): a missing file is
created private without a descriptor left to close, an existing one is not touched, and a path that
is not a regular file is refused. PostgreSQL URLs use psycopg 3.
"""

from __future__ import annotations

import os
import sqlite3
import threading
import weakref
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session, sessionmaker

from db.files import check_regular, private_dir, private_sqlite
from station.errors import InputError

DEFAULT_DB_FILE = "station.sqlite3"
SQLITE_BUSY_TIMEOUT_MS = 2_000  # a locked database counts as away after 2 s (the reading goes to the outbox)
PG_CONNECT_TIMEOUT_S = 5
READ_ONLY_OPTION = "cacad_read_only"  # execution option: this connection's transactions only read
_QUERY_ONLY_INFO = "cacad_query_only"  # per SQLite connection: whether PRAGMA query_only is on now


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

    For SQLite a missing parent folder is created (0700) and a missing database file is created 0600
    (SQLite gives its journals the same mode); an existing file or folder is left as it is, and a
    database path that is a symlink, folder, FIFO or device is refused with
    :class:`db.files.NotRegularFileError` (an :class:`InputError` naming ``database``), before anything
    is opened. ``foreign_keys=False`` is only for batch migrations,
    which recreate tables that others reference. ``busy_timeout_ms`` is how long an SQLite writer
    waits for the lock before the database counts as unreachable.

    Every transaction of the returned engine may write (``BEGIN IMMEDIATE`` on SQLite); derive the
    read-only face with :func:`reading` once and keep it for the read paths.
    """
    url = normalise_url(url)
    parsed = make_url(url)
    if parsed.get_backend_name() != "sqlite":
        kwargs.setdefault("pool_pre_ping", True)
        connect_args = kwargs.pop("connect_args", {})
        connect_args.setdefault("connect_timeout", PG_CONNECT_TIMEOUT_S)  # a dead host fails fast → outbox
        return create_engine(url, connect_args=connect_args, **kwargs)
    if parsed.database and parsed.database != ":memory:" and not parsed.database.startswith("file:"):
        file = Path(parsed.database)
        if not check_regular(file):  # refuse a symlink/FIFO/device/folder before creating its folder
            private_dir(file.parent)
        private_sqlite(file)
    connect_args = kwargs.pop("connect_args", {})
    connect_args.setdefault("check_same_thread", False)
    connect_args.setdefault("timeout", busy_timeout_ms / 1000)
    engine = create_engine(url, connect_args=connect_args, **kwargs)
    _sqlite_writer_queue(engine, foreign_keys=foreign_keys, busy_timeout_ms=busy_timeout_ms)
    return engine


def _sqlite_writer_queue(engine: Engine, *, foreign_keys: bool, busy_timeout_ms: int) -> None:
    """Hook *engine* (SQLite): each new connection in WAL mode with full sync, *foreign_keys* and the busy
    timeout; each writing transaction queued on the engine's own lock, then ``BEGIN IMMEDIATE``."""

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
    # Readers (READ_ONLY_OPTION) take neither that lock nor SQLite's: a deferred BEGIN under query_only.
    # The connections holding the writer lock. Kept apart from ``conn.info``: a connection invalidated
    # mid-write (Ctrl-C or SIGINT inside a statement, a dropped file handle) raises PendingRollbackError
    # on ``conn.info`` in its rollback event, which would hide the first error and keep the lock
    # held, so that every later writer of the process failed as "locked".
    writer = threading.Lock()
    holders: weakref.WeakSet[Any] = weakref.WeakSet()
    wait_s = busy_timeout_ms / 1000

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Any) -> None:
        read_only = bool(conn.get_execution_options().get(READ_ONLY_OPTION, False))
        pooled = conn.connection.info  # lives as long as the SQLite connection itself
        if pooled.get(_QUERY_ONLY_INFO, False) != read_only:
            conn.exec_driver_sql(f"PRAGMA query_only={'ON' if read_only else 'OFF'}")
            pooled[_QUERY_ONLY_INFO] = read_only
        if read_only:
            conn.exec_driver_sql("BEGIN")
            return
        if not writer.acquire(timeout=wait_s):
            raise OperationalError(
                "BEGIN IMMEDIATE",
                None,
                sqlite3.OperationalError("database is locked (writers of this process)"),
            )
        holders.add(conn)  # before BEGIN: an interrupt between the two would otherwise keep the lock
        try:
            conn.exec_driver_sql("BEGIN IMMEDIATE")
        except BaseException:
            _on_end(conn)
            raise

    @event.listens_for(engine, "commit")
    @event.listens_for(engine, "rollback")
    def _on_end(conn: Any) -> None:
        if conn in holders:  # once per transaction: a failed BEGIN may end in a rollback event too
            holders.discard(conn)
            writer.release()


def reading(engine: Engine) -> Engine:
    """The read-only face of *engine* (same pool): transactions that never take the write lock.

    SQLite: ``BEGIN`` (deferred) under ``PRAGMA query_only``, without the engine's writer queue; in WAL
    mode such a reader neither waits for a writer nor delays one, and a write attempted through it
    fails with "attempt to write a readonly database". PostgreSQL: ``READ ONLY`` transactions. Call it
    once per engine and keep the result (each call registers the dialect's connection options anew).
    """
    options: dict[str, Any] = {READ_ONLY_OPTION: True}
    if engine.dialect.name == "postgresql":
        options["postgresql_readonly"] = True
    return engine.execution_options(**options)


def make_sessionmaker(engine: Engine, *, read_only: bool = False) -> sessionmaker[Session]:
    """A session factory bound to *engine* (objects stay readable after commit).

    ``read_only=True`` binds it to :func:`reading` of *engine*: for code paths that never write (lists,
    exports, checks), whose transactions then never take or wait for the write lock.
    """
    import db.chain  # noqa: F401  (its flush hook seals every record row a session writes: db.chain._seal_flushed)

    return sessionmaker(reading(engine) if read_only else engine, expire_on_commit=False)
