"""Tamper evidence without gaps: canonical numbers, every record sealed, a rewind caught by a signed
checkpoint, times that cannot run ahead, and every break reported (``station db verify --json``).

Tampering runs as the database owner with plain SQL (triggers lifted where the schema refuses it); the
verdicts are read from the command's JSON report, the form the soak test relies on.
"""

from __future__ import annotations

import datetime as dt
import json
import uuid
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import Connection, text
from sqlalchemy.pool import NullPool

from db import chain, chain_audit
from db.engine import make_engine, make_sessionmaker
from db.models import Role
from station.api.services import audit, users
from station.cli import main
from station.ingest import DatabaseDestination, PanelRef
from tests.ingest._readings import make_reading


def _report(
    url: str, data: Path, capsys: pytest.CaptureFixture[str], action: str = "verify"
) -> tuple[int, Any]:
    code = main(["db", action, "--database", url, "--data-dir", str(data), "--json"])
    out = capsys.readouterr().out.strip()
    return code, json.loads(out.splitlines()[-1])


def _kinds(report: dict[str, Any]) -> list[tuple[str, str, int | None]]:
    return [(f["chain"], f["kind"], f["id"]) for f in report["findings"]]


def _store(url: str, readings: list[Any]) -> None:
    destination = DatabaseDestination(url)
    try:
        for reading in readings:
            assert destination.store(reading).status == "stored"
    finally:
        destination.close()


def _owner(url: str, work: Callable[[Connection, str], None]) -> None:
    engine = make_engine(url, poolclass=NullPool)
    with engine.begin() as conn:
        work(conn, engine.dialect.name)
    engine.dispose()


def _lift(conn: Connection, dialect: str, table: str) -> None:
    if dialect == "postgresql":
        conn.execute(text(f"ALTER TABLE {table} DISABLE TRIGGER ALL"))
    else:
        for name in (f"tr_{table}_no_update", f"tr_{table}_no_delete", f"tr_{table}_forward"):
            conn.execute(text(f"DROP TRIGGER IF EXISTS {name}"))


def test_negative_zero_is_a_legal_value_that_verifies(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    base = make_reading(11, 0)
    lab = [[50.0, -0.0, 3.0], [30.0, round(-0.004, 2), -0.0], [20.0, 1.0, 1.0]]  # a* rounded to -0.0
    _store(database_url, [base.model_copy(update={"lab": lab, "gloss_gu": -0.0}), make_reading(11, 1)])
    code, report = _report(database_url, tmp_path, capsys)
    assert (code, report["findings"]) == (0, []), report
    assert report["measurements"] == 2 and report["intact"] is True


def test_rows_hashed_before_canonical_numbers_keep_verifying(
    empty_database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A row written by the earlier code (form 1: −0.0 hashed with its sign) verifies after 0009."""
    from db import migrate

    url = empty_database_url
    migrate.upgrade(url, "0008_measurement_texture")
    engine = make_engine(url, poolclass=NullPool)
    at = dt.datetime(2026, 12, 1, 8, 0, tzinfo=dt.UTC)
    with engine.begin() as conn:
        inst = conn.execute(
            text(
                "INSERT INTO instruments (serial, model, kind, created_at) VALUES ('S1', 'M', 'sphere', :at) RETURNING id"
            ),
            {"at": at.replace(tzinfo=None)},
        ).scalar_one()
        row = {
            "client_id": uuid.uuid4(), "panel_id": None, "instrument_id": inst, "calibration_id": None,
            "operator": "qa", "measured_at": at, "received_at": at, "illuminant": "D65",
            "observer": "CIE 1964 10 Degree Standard Observer", "geometries_deg": [15.0, 45.0],
            "lab": [[80.0, -0.0, -20.0], [50.0, 0.0, -0.0]], "wavelengths_nm": None, "spectra": None,
            "gloss_gu": -0.0, "gloss_geometry_deg": 60.0, "payload_sha256": "a" * 64, "supersedes_id": None,
            "correction_reason": None, "created_by_id": None,
        }  # fmt: skip
        head = chain.lock_head(conn, "measurements")
        old_hash = chain.payload_sha256("measurements", row, form=1)
        assert old_hash != chain.payload_sha256("measurements", row)  # the sign of zero was hashed
        link = chain.link_sha256(head.sha256, old_hash)
        tbl = chain.chain_table("measurements", optional=False)
        conn.execute(tbl.insert().values(**row, row_sha256=old_hash, chain_sha256=link))
        chain.advance(conn, "measurements", head, link, at)
    engine.dispose()
    migrate.upgrade(url)
    _store(url, [make_reading(12, 0)])
    code, report = _report(url, tmp_path, capsys)
    assert (code, report["findings"]) == (0, []), report

    def change(conn: Connection, d: str) -> None:
        _lift(conn, d, "measurements")
        conn.execute(text("UPDATE measurements SET gloss_gu = 1.0 WHERE id = 1"))

    _owner(url, change)
    code, report = _report(url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("measurements", "row_changed", 1)], report


def test_a_rewound_tail_is_caught_by_the_signed_checkpoint(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store(database_url, [make_reading(13, i) for i in range(4)])
    code, report = _report(database_url, tmp_path, capsys, "checkpoint")
    assert code == 0 and report["checkpoint"]["measurements"] == 4, report
    assert oct((tmp_path / chain_audit.CHECKPOINT_KEY_FILE).stat().st_mode & 0o777) == "0o600"

    def rewind(conn: Connection, dialect: str) -> None:  # two statements, as the writer of the database
        _lift(conn, dialect, "measurements")
        _lift(conn, dialect, "ledger_heads")
        kept = conn.execute(text("SELECT chain_sha256, received_at FROM measurements WHERE id = 2")).one()
        conn.execute(text("DELETE FROM measurements WHERE id > 2"))
        conn.execute(
            text(
                "UPDATE ledger_heads SET length = 2, head_sha256 = :h, head_at = :at WHERE chain = 'measurements'"
            ),
            {"h": kept[0], "at": kept[1]},
        )

    _owner(database_url, rewind)
    code = main(["db", "verify", "--database", database_url])  # without the checkpoint: looks intact
    capsys.readouterr()
    assert code == 0
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("measurements", "rewound", None)], report
    assert "recorded 4 rows, the table holds 2" in report["findings"][0]["message"]


def test_a_forged_checkpoint_line_is_named(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store(database_url, [make_reading(14, 0)])
    assert _report(database_url, tmp_path, capsys, "checkpoint")[0] == 0
    path = tmp_path / chain_audit.CHECKPOINT_FILE
    line = json.loads(path.read_text().splitlines()[-1])
    line["chains"]["measurements"]["length"] = 0
    with path.open("a") as f:
        f.write(json.dumps(line) + "\n")
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("checkpoints", "checkpoint_invalid", None)], report


def _product_records(url: str) -> None:
    """Users, tokens, a deactivation, a panel, an instrument and a calibration, all through the product."""
    engine = make_engine(url, poolclass=NullPool)
    with make_sessionmaker(engine)() as session:
        user, _token, _secret = users.create_user(
            session=session, actor=None, name="ana", role=Role.QA, label="t"
        )
        users.issue_token(session=session, actor=None, user=user, label="second")
        users.deactivate(session=session, actor=None, user=user)
        users.create_user(session=session, actor=None, name="ben", role=Role.TECHNICIAN, label="t")
    engine.dispose()
    panel = PanelRef(job="J-1", part="door")
    _store(
        url, [make_reading(15, 0).model_copy(update={"panel": panel}), make_reading(15, 1, serial="SIM-2")]
    )


def test_records_written_by_the_product_verify(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _product_records(database_url)
    code, report = _report(database_url, tmp_path, capsys)
    assert (code, report["findings"]) == (0, []), report
    engine = make_engine(database_url, poolclass=NullPool)
    with engine.connect() as conn:
        sealed = conn.execute(text("SELECT entity, op FROM record_events ORDER BY id")).all()
    engine.dispose()
    assert {e for e, _op in sealed} >= {"users", "api_tokens", "instruments", "panels"}, sealed
    assert ("users", "update") in sealed and ("api_tokens", "update") in sealed


def test_records_changed_outside_the_product_are_each_named(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _product_records(database_url)

    def tamper(conn: Connection, _dialect: str) -> None:
        conn.execute(text("UPDATE users SET role = 'admin' WHERE name = 'ben'"))
        conn.execute(text("UPDATE panels SET job = 'J-2'"))
        conn.execute(text("UPDATE instruments SET firmware = 'x' WHERE serial = 'SIM-2'"))
        conn.execute(text("DELETE FROM api_tokens WHERE id = (SELECT max(id) FROM api_tokens)"))
        conn.execute(
            text("INSERT INTO users (name, role, active, created_at) VALUES ('eve', 'admin', :t, :at)"),
            {"t": True, "at": dt.datetime(2026, 12, 1)},
        )

    _owner(database_url, tamper)
    code, report = _report(database_url, tmp_path, capsys)
    kinds = sorted((c, k) for c, k, _id in _kinds(report))
    assert code == 1 and kinds == [
        ("api_tokens", "record_missing"),
        ("instruments", "record_changed"),
        ("panels", "record_changed"),
        ("users", "record_changed"),
        ("users", "record_unsealed"),
    ], report


def test_every_break_is_reported_not_only_the_first(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store(database_url, [make_reading(16, i) for i in range(5)])

    def tamper(conn: Connection, dialect: str) -> None:
        _lift(conn, dialect, "measurements")
        conn.execute(text("UPDATE measurements SET operator = 'x' WHERE id IN (2, 4)"))
        conn.execute(text("DELETE FROM measurements WHERE id = 3"))

    _owner(database_url, tamper)
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [
        ("measurements", "row_changed", 2),
        ("measurements", "row_changed", 4),
        ("measurements", "link_broken", 4),
        ("measurements", "head_mismatch", None),
    ], report


def test_a_row_dated_in_the_future_is_not_carried_forward(
    database_url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    engine = make_engine(database_url, poolclass=NullPool)
    sessions = make_sessionmaker(engine)
    real = chain.utcnow
    monkeypatch.setattr(chain, "utcnow", lambda: dt.datetime(2099, 1, 1, tzinfo=dt.UTC))  # a clock run wild
    with sessions.begin() as session:
        audit.record(session=session, actor=None, action="test.note", entity="panel", entity_id=1)
    monkeypatch.setattr(chain, "utcnow", real)
    with sessions.begin() as session:
        for i in range(2):
            audit.record(session=session, actor=None, action="test.note", entity="panel", entity_id=i)
    with engine.connect() as conn:
        times = conn.execute(text("SELECT id FROM audit_events ORDER BY id")).scalars().all()
        tbl = chain.chain_table("audit_events")
        ats = conn.execute(tbl.select().with_only_columns(tbl.c.at).order_by(tbl.c.id)).scalars().all()
    engine.dispose()
    assert len(times) == 3 and ats[0].year == 2099 and all(at <= real() for at in ats[1:]), ats
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("audit_events", "future", times[0])], report


def test_a_head_moves_only_onto_the_chains_last_row(database_url: str) -> None:
    """Even a writer allowed to update ``ledger_heads`` cannot move a head past rows that are not there."""
    from sqlalchemy.exc import DBAPIError

    _store(database_url, [make_reading(17, i) for i in range(2)])
    for statement in (
        "UPDATE ledger_heads SET length = length + 1, head_sha256 = :f WHERE chain = 'measurements'",
        "UPDATE ledger_heads SET length = length + 1, head_sha256 = (SELECT chain_sha256 FROM measurements "
        "WHERE id = 1) WHERE chain = 'measurements'",
        "UPDATE ledger_heads SET length = length + 1, legacy_last_id = 99 WHERE chain = 'record_events'",
    ):
        with pytest.raises(DBAPIError, match="only moves forward"):

            def update(conn: Connection, _d: str, s: str = statement) -> None:
                conn.execute(text(s), {"f": "f" * 64})

            _owner(database_url, update)


def test_a_checkpoint_file_replaced_by_a_link_is_named_not_followed(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store(database_url, [make_reading(18, 0)])
    assert _report(database_url, tmp_path, capsys, "checkpoint")[0] == 0
    path = tmp_path / chain_audit.CHECKPOINT_FILE
    elsewhere = tmp_path / "elsewhere.jsonl"
    path.rename(elsewhere)
    path.symlink_to(elsewhere)
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("checkpoints", "checkpoint_invalid", None)], report


def test_a_tail_replaced_to_the_same_length_differs_from_the_checkpoint(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store(database_url, [make_reading(19, i) for i in range(4)])
    assert _report(database_url, tmp_path, capsys, "checkpoint")[0] == 0

    def rewind(conn: Connection, dialect: str) -> None:
        _lift(conn, dialect, "measurements")
        _lift(conn, dialect, "ledger_heads")
        kept = conn.execute(text("SELECT chain_sha256, received_at FROM measurements WHERE id = 2")).one()
        conn.execute(text("DELETE FROM measurements WHERE id > 2"))
        conn.execute(
            text(
                "UPDATE ledger_heads SET length = 2, head_sha256 = :h, head_at = :at WHERE chain = 'measurements'"
            ),
            {"h": kept[0], "at": kept[1]},
        )
        if dialect == "postgresql":
            conn.execute(text("ALTER TABLE ledger_heads ENABLE TRIGGER ALL"))
            conn.execute(text("ALTER TABLE measurements ENABLE TRIGGER ALL"))

    _owner(database_url, rewind)
    _store(database_url, [make_reading(20, i) for i in range(2)])  # two other readings take their places
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1, report
    assert [(c, k) for c, k, _id in _kinds(report)] == [("measurements", "checkpoint_mismatch")], report


def test_a_gloss_reading_is_sealed_and_a_change_to_it_named(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from station.ingest import InstrumentRef
    from station.ingest.gloss import GlossRecord, store_gloss

    engine = make_engine(database_url, poolclass=NullPool)
    record = GlossRecord(
        client_id=uuid.uuid4(),
        instrument=InstrumentRef(serial="GL-1", model="gloss meter", kind="gloss"),
        operator="ana",
        measured_at=dt.datetime(2026, 12, 1, 8, 0, tzinfo=dt.UTC),
        gloss_60_gu=-0.0,  # a legal reading of a matte black, rounded
        gloss_85_gu=2.5,
        panel=PanelRef(job="J-9", part="hood"),
    )
    with make_sessionmaker(engine).begin() as session:
        gloss_id = store_gloss(session, record).measurement_id
    engine.dispose()
    code, report = _report(database_url, tmp_path, capsys)
    assert (code, report["findings"]) == (0, []), report

    def tamper(conn: Connection, dialect: str) -> None:
        _lift(conn, dialect, "gloss_readings")
        conn.execute(text("UPDATE gloss_readings SET gloss_85_gu = 3.5"))

    _owner(database_url, tamper)
    code, report = _report(database_url, tmp_path, capsys)
    assert code == 1 and _kinds(report) == [("gloss_readings", "record_changed", gloss_id)], report


def test_verify_reads_one_snapshot_while_writers_append(
    database_url: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Readings stored during a verify never show as a head that disagrees with the table."""
    import threading

    _store(database_url, [make_reading(22, i) for i in range(3)])
    stop = threading.Event()
    stored: list[str] = []

    def write() -> None:
        destination = DatabaseDestination(database_url)
        try:
            i = 3
            while not stop.is_set() and i < 200:
                stored.append(destination.store(make_reading(22, i)).status)
                i += 1
        finally:
            destination.close()

    writer = threading.Thread(target=write)
    writer.start()
    try:
        reports = [_report(database_url, tmp_path, capsys) for _ in range(4)]
    finally:
        stop.set()
        writer.join(timeout=60)
    # SQLite: a store that waited past the busy timeout behind the verify goes to the outbox (not stored)
    assert not writer.is_alive() and "stored" in stored, stored
    assert [(code, r["findings"]) for code, r in reports] == [(0, [])] * 4, reports
