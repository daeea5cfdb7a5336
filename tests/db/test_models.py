"""Durability settings, append-only measurements, time zones and constraints on both backends."""

from __future__ import annotations

import datetime as dt
import uuid

import pytest
from sqlalchemy import func, select, text
from sqlalchemy.exc import IntegrityError

from db.engine import make_engine, make_sessionmaker, normalise_url
from db.errors import ImmutableRowError
from db.models import AuditEvent, Instrument, Measurement, Role, User
from station.errors import InputError

T0 = dt.datetime(2026, 11, 23, 8, 30, tzinfo=dt.timezone(dt.timedelta(hours=2)))


def _measurement(instrument_id: int, **kw: object) -> Measurement:
    fields: dict[str, object] = dict(
        client_id=uuid.uuid4(),
        instrument_id=instrument_id,
        operator="ana",
        measured_at=T0,
        geometries_deg=[15.0, 45.0, 110.0],
        lab=[[60.0, 1.0, 2.0], [40.0, 1.0, 1.0], [20.0, 0.5, 0.5]],
        payload_sha256="0" * 64,
    )
    fields.update(kw)
    return Measurement(**fields)


@pytest.fixture
def session_factory(database_url: str):
    engine = make_engine(database_url)
    yield make_sessionmaker(engine)
    engine.dispose()


def test_sqlite_pragmas(tmp_path) -> None:
    engine = make_engine(f"sqlite:///{tmp_path / 'x' / 'db.sqlite3'}")
    with engine.connect() as conn:
        assert conn.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert conn.execute(text("PRAGMA synchronous")).scalar() == 2  # FULL
        assert conn.execute(text("PRAGMA foreign_keys")).scalar() == 1
    engine.dispose()


def test_url_normalisation() -> None:
    assert normalise_url("postgresql://u@h/db").startswith("postgresql+psycopg://")
    assert normalise_url("postgres://u@h/db").startswith("postgresql+psycopg://")
    with pytest.raises(InputError, match="database"):
        normalise_url("mysql://u@h/db")
    with pytest.raises(InputError):
        normalise_url("not a url")


def test_measurement_is_append_only(session_factory) -> None:
    with session_factory() as s:
        inst = Instrument(serial="SN1", model="sim", kind="multiangle")
        s.add(inst)
        s.flush()
        m = _measurement(inst.id)
        s.add(m)
        s.commit()
        m.operator = "someone else"
        with pytest.raises(ImmutableRowError):
            s.commit()
        s.rollback()
        s.delete(s.get(Measurement, m.id))
        with pytest.raises(ImmutableRowError):
            s.commit()


def test_timestamps_come_back_utc_aware(session_factory) -> None:
    with session_factory() as s:
        inst = Instrument(serial="SN2", model="sim", kind="multiangle")
        s.add(inst)
        s.flush()
        s.add(_measurement(inst.id))
        s.commit()
    with session_factory() as s:
        got = s.scalars(select(Measurement)).one().measured_at
    assert got.tzinfo is not None
    assert got == T0
    assert got.utcoffset() == dt.timedelta(0)


def test_naive_datetime_refused(session_factory) -> None:
    with session_factory() as s:
        inst = Instrument(serial="SN3", model="sim", kind="multiangle")
        s.add(inst)
        s.flush()
        s.add(_measurement(inst.id, measured_at=dt.datetime(2026, 1, 1)))
        with pytest.raises(Exception, match="naive datetime"):
            s.commit()


def test_client_id_unique_and_foreign_keys_enforced(session_factory) -> None:
    cid = uuid.uuid4()
    with session_factory() as s:
        inst = Instrument(serial="SN4", model="sim", kind="multiangle")
        s.add(inst)
        s.flush()
        s.add(_measurement(inst.id, client_id=cid))
        s.commit()
        s.add(_measurement(inst.id, client_id=cid))
        with pytest.raises(IntegrityError):
            s.commit()
        s.rollback()
        s.add(_measurement(inst.id, panel_id=999_999))
        with pytest.raises(IntegrityError):
            s.commit()


def test_enum_check_constraints(session_factory) -> None:
    with session_factory() as s:
        s.add(User(name="root", role=Role.ADMIN))
        s.commit()
        with pytest.raises(IntegrityError):
            s.execute(
                text(
                    "INSERT INTO panels (job, part, substrate, notes, created_at) "
                    "VALUES ('J1', 'wing', '', '', CURRENT_TIMESTAMP)"
                )
            )
            s.commit()


def test_database_refuses_update_and_delete_of_measurements(session_factory) -> None:
    """The triggers of revision 0002 hold for raw SQL too, not only through the ORM."""
    with session_factory() as s:
        inst = Instrument(serial="SN5", model="sim", kind="multiangle")
        s.add(inst)
        s.flush()
        s.add(_measurement(inst.id))
        s.add(AuditEvent(action="measurement.create", entity="measurement", entity_id="1"))
        s.commit()
        for sql in (
            "UPDATE measurements SET operator = 'x'",
            "DELETE FROM measurements",
            "DELETE FROM audit_events",
        ):
            with pytest.raises(Exception, match="append-only"):
                s.execute(text(sql))
            s.rollback()
        assert s.scalar(select(func.count()).select_from(Measurement)) == 1
