"""Gloss readings: stored once (gloss-only or linked), refused cleanly, append-only, paired by panel and time."""

from __future__ import annotations

import datetime as dt
import itertools
import random
import uuid

import pytest
from pydantic import ValidationError
from sqlalchemy import func, select, text
from sqlalchemy.exc import DBAPIError

from db.engine import make_engine, make_sessionmaker
from db.errors import ImmutableRowError
from db.models import AuditEvent, GlossReading, Instrument, Panel
from station.drivers.readings import GlossReading as MeterReading
from station.ingest import (
    PAIR_WINDOW,
    ClientIdConflictError,
    GlossRecord,
    GlossRow,
    InstrumentRef,
    PanelRef,
    ReferenceNotFoundError,
    gloss_record_from_reading,
    pair_gloss,
    store_gloss,
    store_reading,
)
from tests.ingest._readings import T0, make_reading

GLOSS_METER = InstrumentRef(serial="SIM-GL-0001", model="gloss simulator", kind="gloss")


@pytest.fixture
def engine(database_url: str):
    eng = make_engine(database_url)
    yield eng
    eng.dispose()


def _record(**kw: object) -> GlossRecord:
    base: dict[str, object] = dict(
        client_id=uuid.uuid4(),
        instrument=GLOSS_METER,
        operator="ana",
        measured_at=T0,
        gloss_20_gu=81.25,
        gloss_60_gu=90.5,
        gloss_85_gu=97.0,
        haze_hu=12.5,
        doi=88.0,
    )
    base.update(kw)
    return GlossRecord(**base)  # type: ignore[arg-type]


def _count(engine, model) -> int:
    with engine.connect() as conn:
        return conn.execute(select(func.count()).select_from(model)).scalar_one()


def test_gloss_only_reading_is_stored_once_with_every_value(engine) -> None:
    sessions = make_sessionmaker(engine)
    record = _record(panel=PanelRef(job="J-1", part="door"))
    with sessions.begin() as s:
        first = store_gloss(s, record)
    with sessions.begin() as s:
        again = store_gloss(s, GlossRecord.model_validate_json(record.canonical_json()))
    assert first.created and not again.created and first.measurement_id == again.measurement_id
    with sessions() as s:
        row = s.get(GlossReading, first.measurement_id)
        assert row is not None
        assert (row.gloss_20_gu, row.gloss_60_gu, row.gloss_85_gu, row.haze_hu, row.doi) == (
            81.25,
            90.5,
            97.0,
            12.5,
            88.0,
        )
        assert row.measurement_id is None and row.log_haze is None
        panel = s.get(Panel, row.panel_id)
        assert panel is not None and (panel.job, panel.part) == ("J-1", "door")
        assert s.scalar(select(Instrument.kind).where(Instrument.id == row.instrument_id)) == "gloss"
        audit = s.scalars(select(AuditEvent).where(AuditEvent.action == "gloss.create")).all()
        assert [a.entity_id for a in audit] == [str(first.measurement_id)]
    assert _count(engine, GlossReading) == 1


def test_a_linked_reading_takes_the_measurements_panel(engine) -> None:
    sessions = make_sessionmaker(engine)
    with sessions.begin() as s:
        panel = Panel(job="J-2", part="hood")
        s.add(panel)
        s.flush()
        m = store_reading(s, make_reading(3, 0, panel_id=panel.id)).measurement_id
        g = store_gloss(s, _record(measurement_id=m)).measurement_id
        row = s.get(GlossReading, g)
        assert row is not None and row.panel_id == panel.id and row.measurement_id == m


def test_refusals_store_nothing(engine) -> None:
    sessions = make_sessionmaker(engine)
    with sessions.begin() as s:
        a, b = Panel(job="J-3", part="door"), Panel(job="J-3", part="roof")
        s.add_all([a, b])
        s.flush()
        a_id, b_id = a.id, b.id
        m = store_reading(s, make_reading(4, 0, panel_id=a_id)).measurement_id
    stored = _record(panel_id=a_id)
    with sessions.begin() as s:
        store_gloss(s, stored)
    cases = [
        (_record(measurement_id=999_999), ReferenceNotFoundError, "measurement_id 999999"),
        (_record(panel_id=b_id, measurement_id=m), ReferenceNotFoundError, f"panel {a_id}, not panel {b_id}"),
        (_record(panel_id=999_999), ReferenceNotFoundError, "panel_id 999999"),
        (stored.model_copy(update={"gloss_60_gu": 10.0}), ClientIdConflictError, str(stored.client_id)),
    ]
    for record, error, words in cases:
        with pytest.raises(error, match=words), sessions.begin() as s:
            store_gloss(s, record)
    assert _count(engine, GlossReading) == 1


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"gloss_20_gu": None, "gloss_60_gu": None, "gloss_85_gu": None}, "gloss_60_gu"),
        ({"gloss_60_gu": -1.0}, "gloss_60_gu"),
        ({"gloss_85_gu": float("nan")}, "gloss_85_gu"),
        ({"doi": 101.0}, "doi"),
        ({"gloss_20_gu": "81"}, "gloss_20_gu"),
        ({"panel_id": 1, "panel": PanelRef(job="J", part="door")}, "panel"),
        ({"unknown": 1}, "unknown"),
    ],
)
def test_bad_records_name_the_field(change: dict[str, object], field: str) -> None:
    with pytest.raises(ValidationError, match=field):
        _record(**change)


def test_gloss_rows_are_append_only(engine) -> None:
    sessions = make_sessionmaker(engine)
    with sessions.begin() as s:
        gid = store_gloss(s, _record()).measurement_id
    with sessions() as s:
        row = s.get(GlossReading, gid)
        assert row is not None
        row.gloss_60_gu = 1.0
        with pytest.raises(ImmutableRowError):
            s.flush()
    for sql in ("UPDATE gloss_readings SET gloss_60_gu = 1", "DELETE FROM gloss_readings"):
        with pytest.raises(DBAPIError, match="append-only"), engine.begin() as conn:
            conn.execute(text(sql))
    with sessions() as s:
        kept = s.get(GlossReading, gid)
        assert kept is not None and kept.gloss_60_gu == 90.5


def test_record_from_a_meter_reading_keeps_every_geometry() -> None:
    reading = MeterReading(
        gloss_gu={20: 75.5, 60: 88.25, 85: 96.0},
        haze_hu=14.0,
        log_haze=1.15,
        doi=91.0,
        rspec=60.0,
        serial="GL-77",
        calibration_id="CAL-GL-77-0003",
        time=T0,
        temperature_c=22.0,
        model="GL3",
    )
    rec = gloss_record_from_reading(reading, operator="ana", panel_id=5)
    assert rec.gloss_gu() == {20: 75.5, 60: 88.25, 85: 96.0}
    assert (rec.haze_hu, rec.log_haze, rec.doi, rec.rspec_gu) == (14.0, 1.15, 91.0, 60.0)
    assert rec.instrument.kind == "gloss" and rec.instrument.serial == "GL-77"
    assert rec.calibration is not None and rec.measured_at == T0 and rec.panel_id == 5


def _t(minutes: float) -> dt.datetime:
    return T0 + dt.timedelta(minutes=minutes)


def test_pairing_by_hand() -> None:
    colour = [GlossRow(1, 10, _t(0)), GlossRow(2, 10, _t(20)), GlossRow(3, 11, _t(0)), GlossRow(4, 12, _t(0))]
    gloss = [
        GlossRow(100, 10, _t(18)),  # nearest to colour 2 (2 min) before colour 1 (18 min)
        GlossRow(101, 10, _t(1)),  # colour 1, 1 min
        GlossRow(102, 11, _t(31)),  # panel 11 but 31 min away: outside the window
        GlossRow(103, 12, _t(90), measurement_id=4),  # linked: pairs whatever the time
        GlossRow(104, 12, _t(0)),  # colour 4 is taken by its linked reading
        GlossRow(105, None, _t(0)),  # no panel: never paired by time
    ]
    assert pair_gloss(colour, gloss) == {1: 101, 2: 100, 4: 103}
    assert pair_gloss(colour, gloss, window=dt.timedelta(minutes=40))[3] == 102


def test_pairing_is_one_to_one_and_maximal_on_random_sets() -> None:
    rng = random.Random(7)
    for _ in range(200):
        colour = [GlossRow(i, rng.choice([1, 2]), _t(rng.uniform(0, 90))) for i in range(rng.randint(0, 5))]
        gloss = [
            GlossRow(100 + j, rng.choice([1, 2, None]), _t(rng.uniform(0, 90)))
            for j in range(rng.randint(0, 5))
        ]
        paired = pair_gloss(colour, gloss)
        assert len(set(paired.values())) == len(paired)
        by_id = {g.id: g for g in gloss}
        for c in colour:
            if c.id in paired:
                g = by_id[paired[c.id]]
                assert g.panel_id == c.panel_id and abs(g.measured_at - c.measured_at) <= PAIR_WINDOW
        free_c = [c for c in colour if c.id not in paired]
        free_g = [g for g in gloss if g.id not in paired.values()]
        for c, g in itertools.product(free_c, free_g):  # nothing left that could still pair
            assert not (g.panel_id == c.panel_id and abs(g.measured_at - c.measured_at) <= PAIR_WINDOW)
