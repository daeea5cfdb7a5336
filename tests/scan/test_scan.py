"""``station.scan`` against the simulator subprocesses (real ptys, real drivers) and a real SQLite database:
connect, pair (the gloss meter read first), records, store or queue, and a retry answered from the first
attempt. The fronts' side is tests/scan/test_gloss_only_fronts.py and tests/ui/test_journey_technician.py."""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import colour
import numpy as np
import pytest
from sqlalchemy import create_engine, select
from sqlalchemy.orm import Session

from db.models import GlossReading as GlossRow
from db.models import Measurement, Panel
from station import scan
from station.errors import InputError
from station.ingest import DatabaseDestination, Ingestor, PanelRef, Receipt, is_unreachable

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def pair() -> Iterator[tuple[scan.Device, scan.Device]]:
    with scan.open_device("sim:ma6") as spectro, scan.open_gloss_meter("sim:gloss") as meter:
        yield spectro, meter


def _target(url: str, outbox: Path) -> scan.DatabaseTarget:
    return scan.DatabaseTarget(Ingestor(DatabaseDestination(url, migrate=True), outbox))


def _lab_colour_science(wavelengths: list[float], curve: np.ndarray) -> np.ndarray:
    """CIE L*a*b* of one reflectance curve, D65 / CIE 1964 10°, computed here with colour-science."""
    shape = colour.SpectralShape(400, 700, 10)
    cmfs = colour.MSDS_CMFS["CIE 1964 10 Degree Standard Observer"].copy().align(shape)
    d65 = colour.SDS_ILLUMINANTS["D65"].copy().align(shape)
    sd = colour.SpectralDistribution(dict(zip(wavelengths, curve, strict=True)))
    xyz = colour.sd_to_XYZ(sd, cmfs, d65) / 100.0
    white = colour.sd_to_XYZ(colour.sd_ones(shape), cmfs, d65) / 100.0
    return np.asarray(colour.XYZ_to_Lab(xyz, colour.XYZ_to_xy(white)))


def test_bad_devices_are_refused_with_the_field() -> None:
    for bad in ("", "   ", "sim:nope"):
        with pytest.raises(scan.ScanInputError, match="device") as err:
            scan.open_device(bad)
        assert isinstance(err.value, InputError) and err.value.field == "device"
    with pytest.raises(InputError, match="--design"):
        scan.open_device("/dev/ttyNOPE0", design_file=Path("d.json"))
    with pytest.raises(scan.ScanInputError) as err:
        scan.open_gloss_meter("sim:ma3")
    assert err.value.field == "gloss_device" and "gloss meter" in str(err.value)


def test_take_reads_the_gloss_meter_first_and_pairs_it(pair) -> None:
    spectro, meter = pair
    said: list[tuple[int, str]] = []
    result = scan.take(
        spectro.instrument,
        meter.instrument,
        device="sim:ma6",
        gloss_device="sim:gloss",
        progress=lambda s, t: said.append((s, t)),
    )
    assert said == [(0, "reading the gloss meter sim:gloss"), (0, "measuring with sim:ma6"), (1, "measured")]
    assert result.colour is not None and result.gloss is not None and not result.gloss_only
    assert result.gloss.time <= result.colour.time  # the gloss meter was read first
    assert result.gloss_60_gu == result.gloss.gloss_gu[60]
    wl = [float(w) for w in result.colour.wavelengths_nm]
    for curve, lab in zip(result.colour.reflectance, result.lab, strict=True):
        np.testing.assert_allclose(lab, _lab_colour_science(wl, curve), atol=0.05)
    alone = scan.take(meter.instrument, device="sim:gloss")
    assert alone.gloss_only and alone.colour is None and alone.lab.shape == (0, 3)


def test_records_carry_the_60_degree_gloss_and_a_derived_gloss_client_id(pair) -> None:
    spectro, meter = pair
    taken = scan.take(spectro.instrument, meter.instrument)
    cid = uuid.uuid4()
    result = scan.make_records(taken, operator="ana", client_id=cid)
    assert result.record is not None and result.gloss_record is not None
    assert result.record.client_id == cid and result.record.gloss_gu == taken.gloss_60_gu
    assert result.record.gloss_geometry_deg == 60
    # a retry of the scan names the same gloss record; another scan another one
    assert result.gloss_record.client_id == scan.gloss_client_id(cid) != scan.gloss_client_id(uuid.uuid4())
    assert result.gloss_record.client_id != cid
    assert taken.gloss is not None
    assert result.gloss_record.gloss_gu() == {g: float(v) for g, v in taken.gloss.gloss_gu.items()}
    refused = scan.make_records(taken, operator="ana", illumination_deg=15, refused="note")
    assert refused.record is None and "illumination_deg" in refused.note
    with pytest.raises(InputError, match="illumination_deg"):
        scan.make_records(taken, operator="ana", illumination_deg=15)


def test_store_pairs_then_a_retry_stores_nothing_new(pair, tmp_path: Path) -> None:
    spectro, meter = pair
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    target = _target(url, tmp_path / "outbox.sqlite3")
    cid = uuid.uuid4()
    result = scan.make_records(scan.take(spectro.instrument, meter.instrument), operator="ana", client_id=cid)
    stored = scan.store(result, target)
    assert stored.receipt is not None and stored.receipt.status == "stored"
    assert stored.gloss_receipt is not None and stored.gloss_receipt.status == "stored"
    again = scan.store(stored, target)
    assert again.receipt is not None and again.gloss_receipt is not None
    assert again.receipt.status == "duplicate" and again.gloss_receipt.status == "duplicate"
    prior = scan.prior(target, cid)
    assert (
        isinstance(prior, Receipt)
        and prior.status == "duplicate"
        and prior.measurement_id == stored.receipt.measurement_id
    )
    assert scan.prior(target, uuid.uuid4()) is None and scan.prior(target, None) is None
    engine = create_engine(url)
    with Session(engine) as s:
        rows = s.scalars(select(Measurement)).all()
        gloss = s.scalars(select(GlossRow)).all()
        assert [r.id for r in rows] == [stored.receipt.measurement_id]
        assert [(g.id, g.measurement_id, g.gloss_60_gu) for g in gloss] == [
            (stored.gloss_receipt.gloss_reading_id, rows[0].id, rows[0].gloss_gu)
        ]
    engine.dispose()
    target.ingestor.close()


def test_a_gloss_only_reading_is_stored_on_its_panel_and_found_by_a_retry(pair, tmp_path: Path) -> None:
    _spectro, meter = pair
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    target = _target(url, tmp_path / "outbox.sqlite3")
    cid = uuid.uuid4()
    panel = PanelRef(job="J-S-1", part="hood")
    result = scan.make_records(scan.take(meter.instrument), operator="ana", client_id=cid, panel=panel)
    assert result.record is None and result.gloss_record is not None
    stored = scan.store(result, target)
    assert stored.gloss_receipt is not None
    assert stored.receipt is None and stored.gloss_receipt.status == "stored"
    prior = scan.prior(target, cid)
    assert (
        isinstance(prior, scan.GlossReceipt)
        and prior.gloss_reading_id == stored.gloss_receipt.gloss_reading_id
    )
    engine = create_engine(url)
    with Session(engine) as s:
        (row, p), *rest = s.execute(select(GlossRow, Panel).join(Panel, Panel.id == GlossRow.panel_id)).all()
        assert rest == [] and s.scalars(select(Measurement)).all() == []
        assert (p.job, p.part, row.measurement_id, str(row.client_id)) == ("J-S-1", "hood", None, str(cid))
    engine.dispose()
    target.ingestor.close()


def test_database_away_queues_the_colour_and_says_the_gloss_row_is_not_stored(pair, tmp_path: Path) -> None:
    spectro, meter = pair
    blocker = tmp_path / "db"
    blocker.write_text("a file where the database folder should be")
    target = _target(f"sqlite:///{blocker / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    paired = scan.make_records(scan.take(spectro.instrument, meter.instrument), operator="ana")
    stored = scan.store(paired, target)
    assert stored.receipt is not None
    assert stored.receipt.status == "queued" and len(target.ingestor.outbox) == 1
    assert stored.gloss_receipt is not None
    assert stored.gloss_receipt.status == "not stored" and "queued" in stored.gloss_receipt.message
    assert paired.record is not None
    queued = scan.prior(target, paired.record.client_id)
    assert queued is not None and queued.status == "queued"
    alone = scan.make_records(scan.take(meter.instrument), operator="ana")
    with pytest.raises(Exception) as err:  # gloss readings are not queued: the front says so
        scan.store(alone, target)
    assert is_unreachable(err.value)
    told: list[BaseException] = []
    away = scan.DatabaseTarget(target.ingestor, on_unreachable=told.append)
    assert away.prior(uuid.uuid4()) is None and len(told) == 1 and is_unreachable(told[0])
    target.ingestor.close()
