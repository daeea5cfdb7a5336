"""Instruments screen against the MA6 simulator subprocess (real pty, real driver): connect, calibrate,
scan with progress in a worker thread; the reading is stored once in a real (temporary) SQLite measurement
database through the ingest layer, with its panel metadata, shown and usable as the design."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
from sqlalchemy import create_engine, select
from sqlalchemy.orm import Session

from db.models import Measurement as MeasurementRow
from db.models import Panel
from station.drivers.readings import SpectralReading
from station.errors import InputError
from station.model.spectra import reflectance_to_lab
from tests.ui.dialogs import answer_calibration
from ui.models.document import DesignDocument
from ui.models.instruments import InstrumentSession, MeasurementStore, measurement_from_reading
from ui.models.measure_db import LocalSink, PanelInfo
from ui.widgets.instruments_screen import InstrumentsScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]


def _rows(url: str) -> list[tuple[MeasurementRow, Panel]]:
    engine = create_engine(url)
    try:
        with Session(engine) as s:
            return [(row, panel) for row, panel in s.execute(select(MeasurementRow, Panel).join(Panel)).all()]
    finally:
        engine.dispose()


def test_scan_with_simulator_stores_one_row_with_panel_metadata(qtbot, tmp_path):
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    store = MeasurementStore(LocalSink(url, tmp_path / "outbox.sqlite3"))
    doc = DesignDocument()
    screen = InstrumentsScreen(store, doc)
    qtbot.addWidget(screen)
    screen.show()
    screen.device.setCurrentText("sim:ma6")
    screen.connect_btn.click()
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert screen.session.connected, screen.log.toPlainText()
    assert screen.scan_btn.isEnabled()
    titles = answer_calibration(qtbot, screen, ["ok", "ok", "ok"])
    assert titles == ["Black trap", "White tile", "Verification tile"]
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert "calibration" in screen.log.toPlainText() and "passed" in screen.state.text(), (
        screen.log.toPlainText()
    )
    screen.job.setText("J-2026-0113")
    screen.part.setCurrentText("bumper")
    screen.substrate.setText("PP/EPDM")
    screen.notes.setPlainText("rear bumper, left of the plate")
    steps: list[int] = []
    screen.scan_btn.click()
    assert screen.task is not None
    screen.task.progress.connect(lambda s, _t: steps.append(s))
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert len(store.items) == 1, screen.log.toPlainText()
    m = store.items[0]
    assert screen.progress.value() == screen.progress.maximum()
    assert m.panel == PanelInfo("J-2026-0113", "bumper", "PP/EPDM", "rear bumper, left of the plate")
    assert m.device == "sim:ma6" and len(m.geometries) == 6 and m.lab.shape == (6, 3)
    assert m.receipt is not None and m.receipt.status == "stored", m.receipt
    assert f"stored as measurement {m.receipt.measurement_id}" == screen.state.text()
    # the database holds exactly this reading, once, on a panel with the typed metadata
    rows = _rows(url)
    assert len(rows) == 1
    row, panel = rows[0]
    assert m.reading is not None
    assert row.id == m.receipt.measurement_id and str(row.client_id) == str(m.reading.client_id)
    assert (panel.job, panel.part, panel.substrate, panel.notes) == (
        "J-2026-0113",
        "bumper",
        "PP/EPDM",
        "rear bumper, left of the plate",
    )
    # the stored Lab is the 45° block's, recomputed here from the stored spectra through the model
    np.testing.assert_allclose(row.lab, reflectance_to_lab(np.asarray(row.spectra)), atol=1e-3)
    assert row.geometries_deg == [float(a) for a in m.aspecular_deg]  # the MA6's six are all 45° illumination
    np.testing.assert_allclose(row.lab, m.lab, atol=1e-3)
    # shown: the table holds the Lab, the list one entry with the row id
    np.testing.assert_allclose(screen.lab_table(), np.round(m.lab, 2), atol=0.006)
    assert screen.stored.count() == 1 and f"#{row.id}" in screen.stored.item(0).text()
    assert screen.plot.points is not None
    assert screen.plot.design == m.design and screen.plot.points[1].shape == (6, 3)
    np.testing.assert_allclose(m.lab, reflectance_to_lab(m.spectra), atol=1e-9)
    # re-sending the same reading (a retry) stores nothing new
    again = store.persist(m)
    assert again.receipt is not None
    assert again.receipt.status == "duplicate" and again.receipt.measurement_id == row.id
    assert len(_rows(url)) == 1
    assert m.design is not None
    screen.use_btn.click()
    assert doc.design == m.design and doc.can_undo
    screen.close()
    assert not screen.session.connected


def _spectral(serial: str = "SIM-T-1") -> SpectralReading:
    """A reading built here (no device): a flat grey 0.3 at three 45° geometries."""
    refl = np.full((3, 31), 0.3)
    refl[0] *= 1.5
    return SpectralReading(
        ("45as15", "45as45", "45as110"),
        refl,
        23.0,
        serial,
        "CAL-1",
        dt.datetime(2026, 11, 23, 7, 0, tzinfo=dt.UTC),
        model="test",
    )


def test_unreachable_database_keeps_the_reading_then_stores_it_once(tmp_path):
    blocker = tmp_path / "db"
    blocker.write_text("a file where the database folder should be")
    url = f"sqlite:///{blocker / 'station.sqlite3'}"
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    m = measurement_from_reading(_spectral(), PanelInfo("J-1", "fender"), "test")
    r = store.persist(m).receipt
    assert r is not None
    assert (
        r.status == "queued" and "unreachable" in r.message and str(tmp_path / "outbox.sqlite3") in r.message
    )
    assert sink.pending() == 1
    blocker.unlink()  # the database comes back
    got = sink.flush()
    assert [x.status for x in got.values()] == ["stored"] and sink.pending() == 0
    again = store.persist(m).receipt
    assert again is not None and again.status == "duplicate"
    rows = _rows(url)
    assert len(rows) == 1 and rows[0][1].part == "fender"
    # the same client id with other panel metadata is a different payload: refused, kept in the dead letters
    moved = store.persist(m.__class__(**{**m.__dict__, "panel": PanelInfo("J-1", "door")}))
    assert moved.receipt is not None
    assert moved.receipt.status == "refused" and "already stored" in moved.receipt.message
    assert m.reading is not None
    assert [cid for cid, _e in sink.outbox.dead_letters()] == [str(m.reading.client_id)]
    assert len(_rows(url)) == 1
    sink.close()


def test_bad_panel_metadata_is_refused_with_the_field(qtbot, tmp_path):
    screen = InstrumentsScreen(
        MeasurementStore(LocalSink(f"sqlite:///{tmp_path / 's.sqlite3'}", tmp_path / "o"))
    )
    qtbot.addWidget(screen)
    screen.job.setText("  ")
    screen.scan()
    assert "job" in screen.log.toPlainText() and screen.state.text() == "failed"
    with pytest.raises(InputError, match="part"):
        PanelInfo("J-1", "wheel").validated()
    screen.close()


def test_session_refuses_bad_input_without_starting_anything():
    s = InstrumentSession()
    with pytest.raises(InputError, match="device"):
        s.connect("sim:nope")
    with pytest.raises(InputError, match="instrument"):
        s.scan(PanelInfo("J-1", "door"))
    assert not s.connected


def test_connect_failure_is_shown(qtbot, tmp_path):
    screen = InstrumentsScreen(MeasurementStore())
    qtbot.addWidget(screen)
    screen.device.setCurrentText(str(tmp_path / "no-such-port"))
    screen.connect_btn.click()
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert "ERROR" in screen.log.toPlainText() and screen.state.text() == "failed"
    assert not screen.scan_btn.isEnabled()
    screen.close()


def test_a_reading_queued_in_an_earlier_session_is_sent_by_retry(qtbot, tmp_path):
    blocker = tmp_path / "db"
    blocker.write_text("not a folder")
    url = f"sqlite:///{blocker / 'station.sqlite3'}"
    first = LocalSink(url, tmp_path / "outbox.sqlite3")
    m = MeasurementStore(first).persist(
        measurement_from_reading(_spectral(), PanelInfo("J-2", "roof"), "test")
    )
    assert m.receipt is not None
    assert m.receipt.status == "queued"
    first.close()  # the viewer quits with the reading on disk
    blocker.unlink()
    store = MeasurementStore(LocalSink(url, tmp_path / "outbox.sqlite3"))  # the next session
    screen = InstrumentsScreen(store)
    qtbot.addWidget(screen)
    assert "1 readings waiting" in screen.where.text()
    screen.retry_btn.click()
    qtbot.waitUntil(lambda: screen.idle, timeout=30000)
    assert screen.state.text() == "1 sent, 0 still queued", screen.log.toPlainText()
    assert "waiting" not in screen.where.text()
    rows = _rows(url)
    assert m.reading is not None
    assert (
        len(rows) == 1 and str(rows[0][0].client_id) == str(m.reading.client_id) and rows[0][1].part == "roof"
    )
    screen.close()
    assert store.sink is not None
    store.sink.close()


def test_default_store_is_the_station_serve_database(tmp_path, monkeypatch):
    from db.engine import default_database_url

    monkeypatch.setenv("CACAD_DATA_DIR", str(tmp_path / "data"))
    sink = LocalSink()
    assert sink.url == default_database_url(tmp_path / "data") and sink.url.endswith("/data/station.sqlite3")
    assert sink.outbox_path == (tmp_path / "data" / "viewer-outbox.sqlite3").resolve()
    assert not (tmp_path / "data").exists()  # nothing is created before the first scan
    monkeypatch.setenv("CACAD_DATABASE_URL", "postgresql://postgres@127.0.0.1/test")
    assert LocalSink().url == "postgresql://postgres@127.0.0.1/test"


def test_a_reading_queued_by_the_previous_viewer_layout_is_still_sent(tmp_path):
    """Outbox entries of the earlier layout (panel metadata beside the reading) are sent, not dead-lettered."""
    import json
    from dataclasses import asdict

    from station.ingest import Outbox

    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    reading = measurement_from_reading(_spectral(), PanelInfo("J-3", "hood"), "test").reading
    assert reading is not None
    body = {"panel": asdict(PanelInfo("J-3", "hood")), "reading": reading.model_dump(mode="json")}
    with Outbox(tmp_path / "outbox.sqlite3") as box:
        box.put(str(reading.client_id), json.dumps(body, sort_keys=True))
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    assert sink.pending() == 1
    assert [r.status for r in sink.flush().values()] == ["stored"] and sink.pending() == 0
    rows = _rows(url)
    assert [(str(m.client_id), p.job, p.part) for m, p in rows] == [(str(reading.client_id), "J-3", "hood")]
    sink.close()


def _gloss_reading():
    """A gloss meter's reading built here (no device)."""
    from station.drivers import GlossReading

    return GlossReading(
        {20: 80.5, 60: 90.25, 85: 97.0},
        12.5,
        1.1,
        88.0,
        91.0,
        "GM-T-1",
        "CAL-G",
        dt.datetime(2026, 11, 23, 7, 5, tzinfo=dt.UTC),
        23.0,
        model="test gloss",
    )


def test_a_gloss_only_reading_is_not_queued_while_the_database_is_away(tmp_path):
    """Gloss readings are stored directly on every front: with the database away the receipt says why and
    nothing waits in the outbox; once it is back the same reading is stored once on the typed panel."""
    from db.models import GlossReading as GlossRow

    blocker = tmp_path / "db"
    blocker.write_text("a file where the database folder should be")
    url = f"sqlite:///{blocker / 'station.sqlite3'}"
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    m = measurement_from_reading(_gloss_reading(), PanelInfo("J-G", "trunk"), "test")
    assert m.gloss_only and m.reading is None and m.gloss_gu == 90.25
    away = store.persist(m)
    assert away.gloss_receipt is not None
    assert away.gloss_receipt.status == "not stored" and "unreachable" in away.gloss_receipt.message
    assert away.receipt is None and sink.pending() == 0
    blocker.unlink()
    back = store.persist(m)
    assert back.gloss_receipt is not None
    again_gloss = store.persist(m).gloss_receipt
    assert (
        back.gloss_receipt.status == "stored"
        and again_gloss is not None
        and again_gloss.status == "duplicate"
    )
    engine = create_engine(url)
    with Session(engine) as s:
        rows = s.execute(select(GlossRow, Panel).join(Panel, Panel.id == GlossRow.panel_id)).all()
    engine.dispose()
    assert [(r.id, r.gloss_60_gu, r.haze_hu, p.job, p.part) for r, p in rows] == [
        (back.gloss_receipt.gloss_reading_id, 90.25, 12.5, "J-G", "trunk")
    ]
    assert _rows(url) == []  # no colour measurement
    sink.close()
