"""Reads never take the write lock; writes still queue on it; a write slipped into a read path fails loudly.

SQLite runs in WAL mode: a transaction of :func:`db.engine.reading` begins deferred under
``PRAGMA query_only``, so it neither waits for a writer (a competing connection holding ``BEGIN
IMMEDIATE``) nor delays one (a writer of the same engine while a read transaction stays open). The
same pooled connection writes again once the read is over. On both backends a write through the
read-only face is refused and nothing is stored. Times are bounded with the wall clock around the
single operation, against the 2 s busy timeout a lock wait would cost.
"""

from __future__ import annotations

import sqlite3
import threading
import time
from pathlib import Path

import pytest
from sqlalchemy import Engine, text
from sqlalchemy.exc import DBAPIError

from db.engine import SQLITE_BUSY_TIMEOUT_MS, make_engine, make_sessionmaker, reading

NO_WAIT_S = SQLITE_BUSY_TIMEOUT_MS / 1000 / 4  # well under one busy wait


def _table(engine: Engine) -> None:
    with engine.begin() as conn:
        conn.execute(text("CREATE TABLE t (x INTEGER)"))
        conn.execute(text("INSERT INTO t VALUES (1)"))


def test_a_read_does_not_wait_for_another_connections_write_lock(tmp_path: Path) -> None:
    path = tmp_path / "r.sqlite3"
    engine = make_engine(f"sqlite:///{path}")
    _table(engine)
    holder = sqlite3.connect(path, isolation_level=None, timeout=5)
    holder.execute("BEGIN IMMEDIATE")
    holder.execute("INSERT INTO t VALUES (2)")
    try:
        t0 = time.monotonic()
        with make_sessionmaker(engine, read_only=True)() as session:
            seen = session.execute(text("SELECT count(*) FROM t")).scalar_one()
        took = time.monotonic() - t0
    finally:
        holder.execute("ROLLBACK")
        holder.close()
        engine.dispose()
    assert seen == 1 and took < NO_WAIT_S, (seen, took)


def test_an_open_read_transaction_does_not_delay_a_writer_of_the_same_engine(tmp_path: Path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path / 'w.sqlite3'}")
    _table(engine)
    reading_now, release = threading.Event(), threading.Event()

    def read_and_hold() -> None:
        with make_sessionmaker(engine, read_only=True)() as session:
            session.execute(text("SELECT count(*) FROM t")).scalar_one()
            reading_now.set()
            release.wait(10)

    reader = threading.Thread(target=read_and_hold)
    reader.start()
    try:
        assert reading_now.wait(10)
        t0 = time.monotonic()
        with make_sessionmaker(engine)() as session:
            session.execute(text("INSERT INTO t VALUES (2)"))
            session.commit()
        took = time.monotonic() - t0
    finally:
        release.set()
        reader.join(10)
    with engine.connect() as conn:
        assert conn.execute(text("SELECT count(*) FROM t")).scalar_one() == 2
    engine.dispose()
    assert took < NO_WAIT_S, took


def test_the_same_pooled_connection_reads_then_writes(tmp_path: Path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path / 'p.sqlite3'}", pool_size=1, max_overflow=0)
    _table(engine)
    for value in (2, 3):
        with reading(engine).connect() as conn:
            assert conn.execute(text("SELECT count(*) FROM t")).scalar_one() == value - 1
        with engine.begin() as conn:
            conn.execute(text("INSERT INTO t VALUES (:v)"), {"v": value})
    with engine.connect() as conn:
        assert conn.execute(text("SELECT count(*) FROM t")).scalar_one() == 3
    engine.dispose()


def test_a_write_through_the_read_only_face_is_refused_and_stores_nothing(database_url: str) -> None:
    engine = make_engine(database_url)
    try:
        with (
            pytest.raises(DBAPIError, match=r"(?i)read.?only"),
            make_sessionmaker(engine, read_only=True)() as s,
        ):
            s.execute(text("UPDATE measurements SET operator = 'x'"))
            s.execute(text("CREATE TABLE sneaked (x INTEGER)"))
            s.commit()
        with engine.connect() as conn:
            names = conn.execute(text("SELECT count(*) FROM measurements WHERE operator = 'x'")).scalar_one()
        assert names == 0
        with engine.begin() as conn:  # the write face still writes
            conn.execute(text("CREATE TABLE allowed (x INTEGER)"))
            conn.execute(text("DROP TABLE allowed"))
    finally:
        engine.dispose()
