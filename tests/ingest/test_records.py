"""The one reading → record conversion, panel metadata in the record, and the Ingestor's outbox-first mode."""

from __future__ import annotations

import datetime as dt
import json
import uuid
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError
from sqlalchemy import select

from db.models import Measurement, Panel
from station.drivers.readings import GlossReading, InstrumentInfo, SpectralReading
from station.errors import InputError
from station.ingest import (
    DestinationUnreachableError,
    Ingestor,
    PanelRef,
    Reading,
    Receipt,
    calibration_client_id,
    record_from_reading,
)
from tests.ingest._readings import make_reading

T = dt.datetime(2026, 11, 23, 7, 0, tzinfo=dt.UTC)


def _flat(rho: float = 0.3) -> SpectralReading:
    """A spectrally flat sample: three 45° geometries and one 15° one (another illumination)."""
    return SpectralReading(
        ("45as15", "45as45", "45as110", "15as15"),
        np.full((4, 31), rho),
        23.0,
        "SN-1",
        "CAL-7",
        T,
        model="MA-T",
    )


def test_flat_reflectance_gives_the_closed_form_lab() -> None:
    """A flat reflectance ρ under any illuminant has the white's chromaticity: a* = b* = 0 and
    L* = 116 ρ^(1/3) − 16 (CIE 1976, ρ > 0.008856)."""
    rec = record_from_reading(_flat(0.3), operator="ana")
    assert rec.geometries_deg == [15.0, 45.0, 110.0]  # the 45° block only
    expected_l = 116 * 0.3 ** (1 / 3) - 16
    np.testing.assert_allclose(np.asarray(rec.lab), [[expected_l, 0, 0]] * 3, atol=2e-3)
    assert rec.spectra is not None and np.asarray(rec.spectra).shape == (3, 31)
    assert rec.wavelengths_nm == [400.0 + 10 * k for k in range(31)]
    assert rec.instrument.serial == "SN-1" and rec.instrument.model == "MA-T"
    assert rec.calibration is not None
    assert rec.calibration.client_id == uuid.uuid5(
        uuid.UUID("0b9e8c1e-5d0c-4c7b-8f5e-2b7c3f1d9a11"), "SN-1/CAL-7"
    )
    assert rec.calibration.client_id == calibration_client_id("SN-1", "CAL-7")
    assert rec.gloss_gu is None and rec.operator == "ana" and rec.measured_at == T


def test_record_options_and_refusals() -> None:
    cid = uuid.uuid4()
    info = InstrumentInfo("MA6", "SN-9", "2.1")
    gloss = GlossReading({20: 80.0, 60: 91.5, 85: 99.0}, 10.0, 1.0, 90.0, 80.0, "G-1", "", T, 23.0)
    rec = record_from_reading(
        _flat(), operator="ana", illumination_deg=15, client_id=cid, instrument=info, gloss=gloss, panel_id=3
    )
    assert rec.client_id == cid and rec.geometries_deg == [15.0] and rec.panel_id == 3
    assert rec.illumination_deg == 15.0  # the block it is, stored with it
    assert (rec.gloss_gu, rec.gloss_geometry_deg) == (91.5, 60)
    assert rec.instrument.model == "MA6" and rec.instrument.firmware == "2.1"
    with pytest.raises(InputError, match="illumination_deg") as err:
        record_from_reading(_flat(), operator="ana", illumination_deg=25)
    assert "[15, 45]" in str(err.value)
    with pytest.raises(InputError, match="gloss"):
        record_from_reading(
            _flat(), operator="ana", gloss=GlossReading({20: 1.0}, 0, 0, 0, 0, "G", "", T, 23.0)
        )
    with pytest.raises(ValidationError, match="operator"):
        record_from_reading(_flat(), operator="")


def test_panel_metadata_names_one_panel_and_is_part_of_the_payload(database_url: str, tmp_path: Path) -> None:
    ref = PanelRef(job="J-1", part="door", substrate="steel", notes="left")
    with pytest.raises(ValidationError, match="part"):
        PanelRef(job="J-1", part="wheel")
    with pytest.raises(ValidationError, match="not both"):
        Reading.model_validate(
            {**make_reading(1, 0).model_dump(mode="json"), "panel_id": 1, "panel": ref.model_dump()}
        )
    plain = make_reading(1, 0)
    assert "panel" not in json.loads(plain.canonical_json())  # hashes of readings without panels unchanged
    a = Reading.model_validate({**make_reading(1, 1).model_dump(mode="json"), "panel": ref.model_dump()})
    b = Reading.model_validate({**make_reading(1, 2).model_dump(mode="json"), "panel": ref.model_dump()})
    assert a.payload_sha256() != make_reading(1, 1).payload_sha256()
    with Ingestor(database_url, tmp_path / "o.sqlite3") as ing:
        assert [ing.submit(r).status for r in (a, b, a)] == ["stored", "stored", "duplicate"]
        with ing.engine.connect() as conn:
            panels = conn.execute(select(Panel.id, Panel.job, Panel.part, Panel.substrate, Panel.notes)).all()
            linked = conn.execute(select(Measurement.panel_id)).scalars().all()
        assert [tuple(p[1:]) for p in panels] == [("J-1", "door", "steel", "left")]
        assert linked == [panels[0].id, panels[0].id]


class _Flaky:
    """A destination that is away, then refuses one client id, then stores (in memory)."""

    where = "test destination"

    def __init__(self) -> None:
        self.away = True
        self.refuse: set[str] = set()
        self.rows: dict[str, int] = {}

    def store(self, reading: Reading, *, actor_id: int | None = None, replayed: bool = False) -> Receipt:
        cid = str(reading.client_id)
        if self.away:
            raise DestinationUnreachableError("no answer")
        if cid in self.refuse:
            raise ValueError("bad reading")
        if cid in self.rows:
            return Receipt(cid, "duplicate", self.rows[cid])
        self.rows[cid] = len(self.rows) + 1
        return Receipt(cid, "stored", self.rows[cid])

    def find(self, client_id: uuid.UUID) -> int | None:
        return self.rows.get(str(client_id))

    def close(self) -> None:
        return None


def test_queue_first_keeps_every_reading_on_disk_and_reports_each(tmp_path: Path) -> None:
    dest = _Flaky()
    r0, r1, r2 = (make_reading(3, i) for i in range(3))
    with Ingestor(dest, tmp_path / "o.sqlite3", queue_first=True) as ing:
        first = ing.submit(r0)
        assert first.status == "queued" and "no answer" in first.message and len(ing.outbox) == 1
        assert ing.find(r0.client_id) == Receipt(str(r0.client_id), "queued", None, "kept in the outbox")
        dest.away = False
        dest.refuse = {str(r1.client_id)}
        got = ing.submit(r1)  # drains r0 first, then refuses r1 into the dead letters
        assert got.status == "refused" and "bad reading" in got.message
        assert ing.outbox.dead_letters() == [(str(r1.client_id), "bad reading")]
        assert ing.submit(r2).status == "stored" and len(ing.outbox) == 0
        assert list(dest.rows) == [str(r0.client_id), str(r2.client_id)]  # stream order kept
        assert ing.find(r0.client_id) == Receipt(str(r0.client_id), "duplicate", 1)
        with pytest.raises(TypeError, match="not a database"):
            _ = ing.engine
