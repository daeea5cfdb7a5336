"""A reading refused after its instrument was upserted rolls that instrument row back: the id must not be
remembered (on both backends, through the :class:`Ingestor` and through the service's group commit)."""

from __future__ import annotations

from pathlib import Path

import pytest
from sqlalchemy import select

from db.engine import make_engine, make_sessionmaker
from db.models import Instrument, Measurement
from station.ingest import ClientIdConflictError, Ingestor
from station.ingest.group import GroupCommit
from tests.ingest._readings import make_reading


def _serial_of(url: str, client_id: object) -> str:
    engine = make_engine(url)
    with engine.connect() as conn:
        serial = conn.execute(
            select(Instrument.serial)
            .join(Measurement, Measurement.instrument_id == Instrument.id)
            .where(Measurement.client_id == client_id)
        ).scalar_one()
    engine.dispose()
    return str(serial)


def test_ingestor_forgets_the_instrument_of_a_refused_reading(database_url: str, tmp_path: Path) -> None:
    stored = make_reading(8, 0)
    clash = make_reading(8, 1, serial="NEW-1").model_copy(update={"client_id": stored.client_id})
    later = make_reading(8, 2, serial="NEW-1")
    with Ingestor(database_url, tmp_path / "o.sqlite3") as ing:
        assert ing.submit(stored).status == "stored"
        with pytest.raises(ClientIdConflictError):
            ing.submit(clash)  # NEW-1 was inserted in its transaction, then rolled back
        assert ing.submit(later).status == "stored"
    assert _serial_of(database_url, later.client_id) == "NEW-1"


def test_group_commit_forgets_the_instrument_of_a_refused_reading(database_url: str) -> None:
    stored = make_reading(9, 0)
    clash = make_reading(9, 1, serial="NEW-2").model_copy(update={"client_id": stored.client_id})
    later = make_reading(9, 2, serial="NEW-2")
    engine = make_engine(database_url)
    group: GroupCommit[int] = GroupCommit("measurement.create")
    with make_sessionmaker(engine)() as session:
        for reading in (stored, clash, later):
            try:
                group.store(session, reading, actor_id=None, answer=lambda _s, _r, res: res.measurement_id)
            except ClientIdConflictError:
                assert reading is clash
    engine.dispose()
    assert _serial_of(database_url, later.client_id) == "NEW-2"
