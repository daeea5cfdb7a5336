"""A write interrupted inside a statement (Ctrl-C, SIGINT to ``station import watch``) ends as the
interrupt, stores nothing, and leaves the process able to write.

SQLAlchemy invalidates a connection when a BaseException such as KeyboardInterrupt escapes a statement;
its rollback event then runs on an invalid connection. The soak (tests/soak) found a watch folder that,
asked to end while storing, exited 1 with PendingRollbackError instead: the engine's writer queue read
its lock flag from ``conn.info``, which raises there, and the lock stayed held, so that each later writer
of the process would have failed as "database is locked". The interrupt comes from
:func:`tests.db._interrupt.interrupt_at`.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import Engine, text

from db.engine import make_engine
from tests.db._interrupt import interrupt_at


@pytest.fixture
def engine(tmp_path: Path) -> Iterator[Engine]:
    """A new SQLite database with one empty table ``t (x)`` and a short busy timeout, disposed after."""
    engine = make_engine(f"sqlite:///{tmp_path / 't.sqlite3'}", busy_timeout_ms=500)
    with engine.begin() as conn:
        conn.execute(text("CREATE TABLE t (x INTEGER)"))
    yield engine
    engine.dispose()


def _rows(engine: Engine) -> list[int]:
    with engine.connect() as conn:
        return [r[0] for r in conn.execute(text("SELECT x FROM t ORDER BY x"))]


def test_an_interrupt_inside_a_write_ends_as_the_interrupt_and_frees_the_writer(engine: Engine) -> None:
    with engine.begin() as conn:
        conn.execute(text("INSERT INTO t VALUES (1)"))
    with (
        interrupt_at(engine, "INSERT") as armed,
        pytest.raises(KeyboardInterrupt),
        engine.begin() as conn,
    ):
        conn.execute(text("INSERT INTO t VALUES (2)"))
    assert armed == [False]
    assert _rows(engine) == [1]  # the interrupted transaction stored nothing
    with engine.begin() as conn:  # the same thread writes again
        conn.execute(text("INSERT INTO t VALUES (3)"))
    errors: list[BaseException] = []

    def other_thread() -> None:
        try:
            with engine.begin() as conn:
                conn.execute(text("INSERT INTO t VALUES (4)"))
        except BaseException as exc:
            errors.append(exc)

    t = threading.Thread(target=other_thread)
    t.start()
    t.join(10.0)
    assert not t.is_alive() and errors == []
    assert _rows(engine) == [1, 3, 4]


def test_an_interrupt_in_a_session_flush_frees_the_writer(engine: Engine) -> None:
    """The same through the ORM's session (the ingest path): the flush's INSERT interrupted."""
    from db.engine import make_sessionmaker

    sessions = make_sessionmaker(engine)
    with (
        interrupt_at(engine, "INSERT") as armed,
        pytest.raises(KeyboardInterrupt),
        sessions.begin() as session,
    ):
        session.execute(text("INSERT INTO t VALUES (1)"))
    assert armed == [False]
    with sessions.begin() as session:
        session.execute(text("INSERT INTO t VALUES (2)"))
    assert _rows(engine) == [2]


def test_an_interrupt_inside_begin_immediate_frees_the_writer(engine: Engine) -> None:
    """The interrupt in the engine's own BEGIN IMMEDIATE (the writer lock just taken): released once."""
    with (
        interrupt_at(engine, "BEGIN IMMEDIATE") as armed,
        pytest.raises(KeyboardInterrupt),
        engine.begin() as conn,
    ):
        conn.execute(text("INSERT INTO t VALUES (1)"))
    assert armed == [False]
    for x in (2, 3):  # a lock released twice would raise here; one never released would time out
        with engine.begin() as conn:
            conn.execute(text(f"INSERT INTO t VALUES ({x})"))
    assert _rows(engine) == [2, 3]
