"""Hash chains over measurements and audit events: each kind of tampering is named by ``station db verify``.

The tampering runs as the database owner (triggers lifted, rows truncated, deleted, changed, inserted
around the writer or forged with back-dated times); the expectation is recomputed independently here
with :mod:`hashlib` from the rows' canonical JSON (not read back from ``db.chain``'s own output).
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import uuid
from collections.abc import Callable
from typing import Any

import pytest
from sqlalchemy import Connection, text
from sqlalchemy.pool import NullPool

from db import chain, chain_audit
from db.engine import make_engine, make_sessionmaker
from station.api.services import audit
from station.cli import main
from station.ingest import DatabaseDestination
from tests.ingest._readings import make_reading

N = 5


def _fill(url: str, n: int = N) -> None:
    destination = DatabaseDestination(url)
    try:
        for i in range(n):
            assert destination.store(make_reading(7, i)).status == "stored"
        assert destination.store(make_reading(7, 0)).status == "duplicate"  # a re-send adds no link
    finally:
        destination.close()
    engine = make_engine(url, poolclass=NullPool)
    with make_sessionmaker(engine).begin() as session:
        audit.record(session=session, actor=None, action="test.note", entity="panel", entity_id=1, n=1.5)
    engine.dispose()


def _verify(url: str, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(["db", "verify", "--database", url])
    captured = capsys.readouterr()
    return code, (captured.err + captured.out).strip()


def _owner(url: str, work: Callable[[Connection, str], None]) -> None:
    engine = make_engine(url, poolclass=NullPool)
    with engine.begin() as conn:
        work(conn, engine.dialect.name)
    engine.dispose()


def _lift(conn: Connection, dialect: str, table: str) -> None:
    if dialect == "postgresql":
        conn.execute(text(f"ALTER TABLE {table} DISABLE TRIGGER tr_{table}_append_only"))
    else:
        conn.execute(text(f"DROP TRIGGER tr_{table}_no_update"))
        conn.execute(text(f"DROP TRIGGER tr_{table}_no_delete"))


def test_intact_chain_verifies_and_matches_an_independent_recomputation(
    database_url: str, capsys: pytest.CaptureFixture[str]
) -> None:
    _fill(database_url)
    code, out = _verify(database_url, capsys)
    assert code == 0, out
    assert "measurements: 5" in out and "audit_events: 6" in out
    engine = make_engine(database_url, poolclass=NullPool)
    with engine.connect() as conn:
        rows = conn.execute(
            text("SELECT action, entity, entity_id, row_sha256, chain_sha256 FROM audit_events ORDER BY id")
        ).all()
        detail = conn.execute(text("SELECT detail FROM audit_events ORDER BY id DESC LIMIT 1")).scalar()
        at = chain.chain_table("audit_events")
        last = conn.execute(at.select().order_by(at.c.id.desc()).limit(1)).mappings().one()
    engine.dispose()
    previous = "0" * 64
    for row in rows:  # the links, by hand: sha256(previous hex + row hex)
        previous = hashlib.sha256((previous + row.row_sha256).encode()).hexdigest()
        assert row.chain_sha256 == previous
    detail = json.loads(detail) if isinstance(detail, str) else detail
    assert detail == {"n": 1.5}
    by_hand = {
        "action": "test.note",
        "actor_id": None,
        "at": last["at"].isoformat(timespec="microseconds"),
        "detail": {"n": 1.5},
        "entity": "panel",
        "entity_id": "1",
    }
    expected = hashlib.sha256(json.dumps(by_hand, sort_keys=True, separators=(",", ":")).encode()).hexdigest()
    assert last["row_sha256"] == expected


def _update_row(conn: Connection, dialect: str) -> None:
    _lift(conn, dialect, "measurements")
    conn.execute(text("UPDATE measurements SET operator = 'someone else' WHERE id = 3"))


def _delete_middle(conn: Connection, dialect: str) -> None:
    _lift(conn, dialect, "measurements")
    conn.execute(text("DELETE FROM measurements WHERE id = 2"))


def _delete_last(conn: Connection, dialect: str) -> None:
    _lift(conn, dialect, "audit_events")
    conn.execute(text("DELETE FROM audit_events WHERE id = (SELECT max(id) FROM audit_events)"))


def _truncate(conn: Connection, dialect: str) -> None:
    if dialect == "postgresql":  # TRUNCATE fires no row trigger; CASCADE takes the rows that refer to them
        conn.execute(text("TRUNCATE measurements CASCADE"))
    else:  # SQLite has no TRUNCATE: drop the triggers, then delete everything
        _lift(conn, dialect, "measurements")
        conn.execute(text("DELETE FROM measurements"))


def _insert_unchained(conn: Connection, dialect: str) -> None:
    conn.execute(
        text(
            "INSERT INTO audit_events (at, action, entity, entity_id, detail) "
            "VALUES ('2020-01-01 00:00:00', 'measurement.create', 'measurement', '1', '{}')"
        )
    )


def _insert_back_dated(conn: Connection, dialect: str) -> None:
    """A forger who knows the algorithm: a correct link, the head advanced, but a time in the past."""
    import datetime as dt

    head = chain.lock_head(conn, "audit_events")
    at = dt.datetime(2020, 1, 1, tzinfo=dt.UTC)
    row: dict[str, Any] = {
        "at": at,
        "actor_id": None,
        "action": "user.create",
        "entity": "user",
        "entity_id": "99",
        "detail": {},
    }
    row_hash, link = chain.seal("audit_events", head, row)
    tbl = chain.chain_table("audit_events")
    conn.execute(tbl.insert().values(**row, row_sha256=row_hash, chain_sha256=link))
    chain.advance(conn, "audit_events", head, link, at)


def _insert_into_gap(conn: Connection, dialect: str) -> None:
    """A reading slipped in between two others (an id below the head), with an old received_at."""
    _lift(conn, dialect, "measurements")
    conn.execute(text("DELETE FROM measurements WHERE id = 2"))
    cols = ", ".join(c for c in chain.PAYLOAD_COLUMNS["measurements"] if c != "client_id")
    client = uuid.uuid4().hex if dialect == "sqlite" else str(uuid.uuid4())
    conn.execute(
        text(
            f"INSERT INTO measurements (id, client_id, {cols}, row_sha256, chain_sha256) "
            f"SELECT 2, :client, {cols}, row_sha256, chain_sha256 FROM measurements WHERE id = 1"
        ),
        {"client": client},
    )


CASES = {
    "update": (_update_row, "measurements id 3: payload hash differs"),
    "delete-middle": (_delete_middle, "measurements id 3: link to the previous row differs"),
    "delete-last": (_delete_last, "audit_events: head records 6 rows, table holds 5"),
    "truncate": (_truncate, "measurements: head records 5 rows, table holds 0"),
    "insert-unchained": (_insert_unchained, "audit_events id 7: no hash"),
    "insert-back-dated": (_insert_back_dated, "audit_events id 7: at 2020-01-01T00:00:00+00:00 earlier"),
    "insert-into-gap": (_insert_into_gap, "measurements id 2: payload hash differs"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_verify_names_the_first_broken_link(
    database_url: str, case: str, capsys: pytest.CaptureFixture[str]
) -> None:
    _fill(database_url)
    tamper, expected = CASES[case]
    _owner(database_url, tamper)
    code = main(["db", "verify", "--database", database_url])
    captured = capsys.readouterr()
    assert code == 1, captured
    err = captured.err.strip()
    assert len(err.splitlines()) == 1 and expected in err, err  # the first finding on stderr
    assert f"finding: {expected}" in captured.out or any(
        line.startswith("finding: ") and expected in line for line in captured.out.splitlines()
    ), captured.out


def test_head_row_only_moves_forward(database_url: str) -> None:
    _fill(database_url)
    from sqlalchemy.exc import DBAPIError

    for statement in (
        "UPDATE ledger_heads SET length = 0 WHERE chain = 'measurements'",
        "DELETE FROM ledger_heads WHERE chain = 'audit_events'",
        "UPDATE ledger_heads SET backfill_last_id = 1000 WHERE chain = 'audit_events'",
    ):
        with pytest.raises(DBAPIError, match="only moves forward"):

            def update(conn: Connection, _d: str, s: str = statement) -> None:
                conn.execute(text(s))

            _owner(database_url, update)


def test_concurrent_writers_form_one_chain(database_url: str, capsys: pytest.CaptureFixture[str]) -> None:
    writers, each = 4, 8
    destination = DatabaseDestination(database_url)

    def write(w: int) -> list[str]:
        return [destination.store(make_reading(100 + w, i)).status for i in range(each)]

    try:
        with concurrent.futures.ThreadPoolExecutor(writers) as pool:
            statuses = [s for batch in pool.map(write, range(writers)) for s in batch]
    finally:
        destination.close()
    assert statuses.count("stored") == writers * each
    code, out = _verify(database_url, capsys)
    assert code == 0, out
    assert f"measurements: {writers * each}" in out and f"audit_events: {writers * each}" in out


def test_migration_back_fills_rows_written_before_the_chain(empty_database_url: str) -> None:
    from db import migrate

    migrate.upgrade(empty_database_url, "0003")
    engine = make_engine(empty_database_url, poolclass=NullPool)
    with engine.begin() as conn:  # rows as the earlier writer left them: no hashes, times out of order
        for i, at in enumerate(("2026-11-23 06:00:02", "2026-11-23 06:00:01", "2026-11-23 06:00:03")):
            conn.execute(
                text(
                    "INSERT INTO audit_events (at, action, entity, entity_id, detail) "
                    "VALUES (:at, 'user.create', 'user', :i, '{}')"
                ),
                {"at": at, "i": str(i)},
            )
    migrate.upgrade(empty_database_url)
    with engine.connect() as conn:
        verdicts = chain_audit.verify(conn)
    engine.dispose()
    assert [(v.chain, v.rows, v.broken) for v in verdicts] == [
        ("measurements", 0, None),
        ("audit_events", 3, None),
    ]
    _fill(empty_database_url, 2)  # new rows chain on from the back-filled head
    engine = make_engine(empty_database_url, poolclass=NullPool)
    with engine.connect() as conn:
        assert [v.broken for v in chain_audit.verify(conn)] == [None, None]
    engine.dispose()


def test_a_clock_stepped_back_does_not_break_the_chain(
    database_url: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    _fill(database_url, 2)
    back = chain.utcnow() - chain.MAX_CLOCK_SKEW / 2
    monkeypatch.setattr(chain, "utcnow", lambda: back)  # an NTP step back within the allowed skew
    destination = DatabaseDestination(database_url)
    try:  # readings 2 and 3 written "a few minutes ago"
        assert [destination.store(make_reading(7, i)).status for i in (2, 3)] == ["stored", "stored"]
    finally:
        destination.close()
    code, out = _verify(database_url, capsys)
    assert code == 0, out
    engine = make_engine(database_url, poolclass=NullPool)
    with engine.connect() as conn:
        m = chain.chain_table("measurements")
        times = conn.execute(m.select().with_only_columns(m.c.received_at).order_by(m.c.id)).scalars().all()
    engine.dispose()
    assert times == sorted(times) and times[2] == times[3] == times[1]  # held at the last time written
