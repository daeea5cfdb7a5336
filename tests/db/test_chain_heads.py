"""The chain's heads are read once per transaction and kept current by each append (``db.chain.lock_head``).

A writer that stores many readings in one transaction (the service's group commit) must not read the
locked head rows again for every row; a savepoint rolled back, or a new transaction on the same
connection, must read them again, or the next row would chain from a link that was never stored.
"""

from __future__ import annotations

from typing import Any

import pytest
from sqlalchemy import event
from sqlalchemy.pool import NullPool

from db import chain
from db.engine import make_engine, make_sessionmaker
from station.cli import main
from station.ingest.destination import store_audited
from tests.ingest._readings import make_reading


def _verify(url: str, capsys: pytest.CaptureFixture[str]) -> str:
    code = main(["db", "verify", "--database", url])
    captured = capsys.readouterr()
    out = (captured.err + captured.out).strip()
    assert code == 0, out
    return out


def test_one_head_read_for_a_transaction_of_many_readings(
    database_url: str, capsys: pytest.CaptureFixture[str]
) -> None:
    engine = make_engine(database_url, poolclass=NullPool)
    head_reads: list[str] = []

    def count(_conn: Any, _cursor: Any, statement: str, *_args: Any) -> None:
        if statement.lstrip().upper().startswith("SELECT") and "ledger_heads" in statement:
            head_reads.append(statement)

    event.listen(engine, "before_cursor_execute", count)
    try:
        with make_sessionmaker(engine).begin() as session:
            for i in range(4):
                assert store_audited(session, make_reading(41, i), actor_id=None, action="test.store").created
    finally:
        engine.dispose()
    assert len(head_reads) == 1, head_reads
    out = _verify(database_url, capsys)
    assert "measurements: 4" in out and "audit_events: 4" in out


def test_a_savepoint_rolled_back_reads_the_heads_again(
    database_url: str, capsys: pytest.CaptureFixture[str]
) -> None:
    engine = make_engine(database_url, poolclass=NullPool)
    try:
        with make_sessionmaker(engine).begin() as session:
            store_audited(session, make_reading(42, 0), actor_id=None, action="test.store")
            nested = session.begin_nested()
            store_audited(session, make_reading(42, 1), actor_id=None, action="test.store")
            nested.rollback()
            store_audited(session, make_reading(42, 2), actor_id=None, action="test.store")
    finally:
        engine.dispose()
    out = _verify(database_url, capsys)
    assert "measurements: 2" in out and "audit_events: 2" in out


def test_each_transaction_of_one_connection_reads_the_heads_again(
    database_url: str, capsys: pytest.CaptureFixture[str]
) -> None:
    engine = make_engine(database_url, poolclass=NullPool)
    try:
        with engine.connect() as conn:
            for i in range(3):  # commit as you go: each append begins a new transaction
                chain.append_audit(
                    conn,
                    {
                        "actor_id": None,
                        "action": "test.note",
                        "entity": "panel",
                        "entity_id": str(i),
                        "detail": {},
                    },
                )
                conn.commit()
            chain.append_audit(
                conn,
                {"actor_id": None, "action": "test.note", "entity": "panel", "entity_id": "x", "detail": {}},
            )
            conn.rollback()  # the head this moved was never stored
            chain.append_audit(
                conn,
                {"actor_id": None, "action": "test.note", "entity": "panel", "entity_id": "y", "detail": {}},
            )
            conn.commit()
    finally:
        engine.dispose()
    assert "audit_events: 4" in _verify(database_url, capsys)
