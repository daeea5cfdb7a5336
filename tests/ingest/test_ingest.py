"""Exactly-once storage, conflicts, the outbox and its in-order replay, and reading validation."""

from __future__ import annotations

import base64
import hashlib
import uuid
from pathlib import Path

import pytest
from pydantic import ValidationError
from sqlalchemy import func, select

from db.engine import make_engine, make_sessionmaker
from db.models import CalibrationRecord, Instrument, Measurement, Panel
from station.ingest import (
    CalibrationRef,
    ClientIdConflictError,
    Ingestor,
    Outbox,
    Reading,
    ReferenceNotFoundError,
    store_reading,
)
from tests.ingest._readings import T0, make_reading

UNREACHABLE_PG = "postgresql://postgres@127.0.0.1:1/nowhere"


@pytest.fixture
def engine(database_url: str):
    eng = make_engine(database_url)
    yield eng
    eng.dispose()


def _count(engine, model) -> int:
    with engine.connect() as conn:
        return conn.execute(select(func.count()).select_from(model)).scalar_one()


def test_same_reading_twice_is_stored_once(engine) -> None:
    sessions = make_sessionmaker(engine)
    reading = make_reading(1, 0)
    with sessions.begin() as s:
        first = store_reading(s, reading)
    with sessions.begin() as s:
        second = store_reading(s, Reading.model_validate_json(reading.canonical_json()))
    assert first.created and not second.created
    assert first.measurement_id == second.measurement_id
    assert _count(engine, Measurement) == 1
    assert _count(engine, Instrument) == 1


def test_client_id_reused_with_other_payload_is_refused(engine) -> None:
    sessions = make_sessionmaker(engine)
    reading = make_reading(1, 0)
    with sessions.begin() as s:
        store_reading(s, reading)
    forged = make_reading(1, 1).model_copy(update={"client_id": reading.client_id})
    with pytest.raises(ClientIdConflictError), sessions.begin() as s:
        store_reading(s, forged)
    assert _count(engine, Measurement) == 1


def test_panel_and_calibration_references(engine) -> None:
    sessions = make_sessionmaker(engine)
    with pytest.raises(ReferenceNotFoundError), sessions.begin() as s:
        store_reading(s, make_reading(1, 0, panel_id=42))
    with sessions.begin() as s:
        panel = Panel(job="J-1", part="bumper")
        s.add(panel)
        s.flush()
        panel_id = panel.id
    cal = CalibrationRef(client_id=uuid.uuid4(), performed_at=T0, reference="white tile W-17")
    for i in range(3):
        with sessions.begin() as s:
            store_reading(s, make_reading(2, i, panel_id=panel_id).model_copy(update={"calibration": cal}))
    assert _count(engine, CalibrationRecord) == 1
    with engine.connect() as conn:
        cal_ids = set(conn.execute(select(Measurement.calibration_id)).scalars())
    assert len(cal_ids) == 1 and None not in cal_ids


def test_hash_is_of_the_raw_payload_when_given() -> None:
    raw = b"\x02MA98;L=82.10;a=-1.20;b=-18.50\x03"
    reading = make_reading(1, 0).model_copy(update={"raw_payload_b64": base64.b64encode(raw).decode()})
    assert reading.payload_sha256() == hashlib.sha256(raw).hexdigest()
    assert make_reading(1, 0).payload_sha256() == make_reading(1, 0).payload_sha256()
    assert make_reading(1, 0).payload_sha256() != make_reading(1, 1).payload_sha256()


@pytest.mark.parametrize(
    ("update", "match"),
    [
        ({"lab": [[50, 0, 0]]}, "one \\[L\\*, a\\*, b\\*\\] per geometry"),
        ({"geometries_deg": [15, 15, 110]}, "distinct"),
        ({"geometries_deg": [15, 45, 200]}, "less than 180"),
        ({"lab": [[50, 0, 0], [50, 0], [50, 0, 0]]}, "at least 3"),
        ({"lab": [[float("nan"), 0, 0], [1, 0, 0], [1, 0, 0]]}, "finite"),
        ({"spectra": None}, "both or neither"),
        ({"gloss_gu": -1.0}, "greater than or equal to 0"),
        ({"illuminant": "D99"}, "D65"),
        ({"measured_at": "2026-01-01T00:00:00"}, "timezone"),
        ({"raw_payload_b64": "!!"}, "base64"),
        ({"operator": ""}, "at least 1"),
    ],
)
def test_reading_validation(update: dict, match: str) -> None:
    data = make_reading(1, 0).model_dump(mode="json") | update
    with pytest.raises(ValidationError, match=match):
        Reading.model_validate(data)


def test_outbox_keeps_order_and_ignores_requeue(tmp_path: Path) -> None:
    with Outbox(tmp_path / "o.sqlite3") as box:
        for i in (3, 1, 2, 1):
            box.put(f"id-{i}", f"body-{i}")
        assert [e.client_id for e in box.entries()] == ["id-3", "id-1", "id-2"]
        first = next(box.entries())
        box.remove(first.seq)
        box.bury(next(box.entries()), "refused")
    with Outbox(tmp_path / "o.sqlite3") as box:  # reopened: on disk
        assert [e.client_id for e in box.entries()] == ["id-2"]
        assert box.dead_letters() == [("id-1", "refused")]


@pytest.mark.postgres
def test_ingestor_queues_while_database_is_away_and_replays_in_order(pg_url: str, tmp_path: Path) -> None:
    from db.migrate import upgrade

    upgrade(pg_url)
    outbox = tmp_path / "outbox.sqlite3"
    with Ingestor(UNREACHABLE_PG, outbox) as away:
        receipts = [away.submit(make_reading(3, i)) for i in range(5)]
        assert {r.status for r in receipts} == {"queued"}
        assert len(away.outbox) == 5
        assert away.replay() == 0
    with Ingestor(pg_url, outbox) as back:
        receipt = back.submit(make_reading(3, 5))  # drains the queue first, then stores this one
        assert receipt.status == "stored"
        assert len(back.outbox) == 0
        assert back.submit(make_reading(3, 0)).status == "duplicate"
        with back.engine.connect() as conn:
            ids = conn.execute(select(Measurement.client_id).order_by(Measurement.id)).scalars().all()
    assert [str(c) for c in ids] == [str(make_reading(3, i).client_id) for i in range(6)]


def test_replay_buries_a_refused_reading_and_goes_on(database_url: str, tmp_path: Path) -> None:
    outbox = tmp_path / "outbox.sqlite3"
    with Outbox(outbox) as box:
        bad = make_reading(4, 0, panel_id=999)
        box.put(str(bad.client_id), bad.canonical_json())
        good = make_reading(4, 1)
        box.put(str(good.client_id), good.canonical_json())
    with Ingestor(database_url, outbox) as ing:
        assert ing.replay() == 2
        assert len(ing.outbox) == 0
        assert [c for c, _ in ing.outbox.dead_letters()] == [str(bad.client_id)]
        assert _count(ing.engine, Measurement) == 1


def test_non_connection_errors_are_not_swallowed(database_url: str, tmp_path: Path) -> None:
    with Ingestor(database_url, tmp_path / "o.sqlite3") as ing, pytest.raises(ReferenceNotFoundError):
        ing.submit(make_reading(5, 0, panel_id=12345))
    with Outbox(tmp_path / "o.sqlite3") as box:
        assert len(box) == 0


def test_ingested_readings_are_audited(database_url: str, tmp_path: Path) -> None:
    from db.models import AuditEvent

    with Ingestor(database_url, tmp_path / "o.sqlite3") as ing:
        ing.submit(make_reading(6, 0))
        ing.submit(make_reading(6, 0))  # duplicate: no second audit row
        with ing.engine.connect() as conn:
            events = conn.execute(select(AuditEvent.action, AuditEvent.detail)).all()
    assert [e.action for e in events] == ["measurement.ingest"]
    assert events[0].detail["client_id"] == str(make_reading(6, 0).client_id)


def test_concurrent_writers_of_one_reading_store_it_once(database_url: str) -> None:
    """Eight threads, each with its own connection, store the same reading at once: one row, one creator."""
    import threading

    engine = (
        make_engine(database_url, pool_size=8)
        if database_url.startswith("postgres")
        else make_engine(database_url)
    )
    sessions = make_sessionmaker(engine)
    reading = make_reading(9, 0)
    barrier = threading.Barrier(8)
    results: list[bool] = []
    errors: list[BaseException] = []

    def worker() -> None:
        try:
            barrier.wait()
            with sessions.begin() as s:
                results.append(store_reading(s, reading).created)
        except BaseException as exc:  # collected and asserted below
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    try:
        assert not errors, errors
        assert sorted(results) == [False] * 7 + [True]
        assert _count(engine, Measurement) == 1
    finally:
        engine.dispose()
