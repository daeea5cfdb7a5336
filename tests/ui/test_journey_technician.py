"""Lab technician's day on the instruments screen, driven by clicks and key presses on the real widgets:
connect the MA6 simulator and pair the gloss meter simulator, calibrate both, type the panel (job, part,
substrate), scan; one measurement with colour at every geometry and the gloss values, the labelled
L*/a*/b* vs aspecular plot, the job's history; re-scan; each reading stored once (a real SQLite
database locally, the real FastAPI service in service mode)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtTest import QTest
from sqlalchemy import create_engine, select
from sqlalchemy.orm import Session

from db.models import Measurement as MeasurementRow
from station.model.spectra import reflectance_to_lab
from tests.ui.dialogs import answer_calibration
from ui.models.instruments import STEPS, MeasurementStore
from ui.models.measure_db import LocalSink, ServiceSink
from ui.widgets.instruments_screen import InstrumentsScreen
from ui.widgets.reading_plot import ANGLE_TICKS, TITLE, X_TITLE

pytestmark = [pytest.mark.qt, pytest.mark.slow]


def _click(qtbot, screen, button) -> None:
    """Click *button* and wait until the task it started has finished and its result is shown."""
    assert button.isEnabled(), button.text()
    QTest.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)


def _type(widget, text: str) -> None:
    """Select the field's text and type *text* over it, key by key."""
    widget.setFocus()
    QTest.keyClick(widget, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClicks(widget, text)


def _day(qtbot, screen: InstrumentsScreen) -> list:
    """Connect, pair, calibrate, scan twice; returns the two measurements."""
    screen.show()
    _type(screen.device.lineEdit(), "sim:ma6")
    _click(qtbot, screen, screen.connect_btn)
    assert screen.session.connected, screen.log.toPlainText()
    _type(screen.gloss_device.lineEdit(), "sim:gloss")
    _click(qtbot, screen, screen.pair_btn)
    assert screen.session.gloss_meter is not None, screen.log.toPlainText()
    assert screen.pair_btn.text() == "Unpair gloss meter"
    # the screen asks for the black trap and the white tile first; a cancel calibrates nothing
    assert answer_calibration(qtbot, screen, ["ok", "cancel"]) == ["Black trap", "White tile"]
    assert screen.state.text() == "calibration cancelled" and screen.calibrate_btn.isEnabled()
    assert "calibration of" not in screen.log.toPlainText()
    titles = answer_calibration(qtbot, screen, ["ok"] * 4)
    assert titles == ["Black trap", "White tile", "Verification tile", "Gloss standard"]
    # the last step (the gloss standard) runs after its prompt closes: wait for its outcome on the state line
    qtbot.waitUntil(lambda: screen.idle and not screen.state.text().startswith("calibration:"), timeout=90000)
    log = screen.log.toPlainText()
    assert screen.state.text() == "calibration passed", log
    assert "calibration of sim:ma6" in log and "calibration of sim:gloss" in log
    _type(screen.job, "J-2026-0200")
    screen.part.setFocus()
    screen.part.setCurrentIndex(screen.part.findText("bumper"))
    _type(screen.substrate, "PP/EPDM")
    seen: list[tuple[int, int]] = []  # (value, maximum) of the bar at every progress report
    screen.progress.valueChanged.connect(lambda v: seen.append((v, screen.progress.maximum())))
    _click(qtbot, screen, screen.scan_btn)
    first = screen.store.items[-1]
    # the bar counted the steps as they were done: 0 → 1 → 2 in the worker, full only once shown
    steps = [v for v, mx in seen if mx == STEPS]
    assert steps == sorted(steps) and steps[-1] == STEPS and {1, 2} <= set(steps), seen
    assert screen.progress.value() == screen.progress.maximum() == STEPS
    _click(qtbot, screen, screen.scan_btn)  # re-scan the same panel
    second = screen.store.items[-1]
    # the job's history from the store: both scans, newest first, with their row ids
    _click(qtbot, screen, screen.history_btn)
    rows = [screen.history.item(i).text() for i in range(screen.history.count())]
    assert second.receipt is not None and first.receipt is not None
    ids = [second.receipt.measurement_id, first.receipt.measurement_id]
    assert [r.split()[0] for r in rows] == [f"#{i}" for i in ids], rows
    assert all("J-2026-0200 bumper" in r and "6 geometries" in r for r in rows)
    assert screen.history_title.text() == "job history (stored): 2 measurements of job J-2026-0200"
    # a history row opens: a double click hands its job, part and measurement to the QC tab
    opened: list[tuple[str, str, int]] = []
    screen.open_job = lambda job, part, mid: opened.append((job, part, mid))
    row = screen.history.visualItemRect(screen.history.item(1)).center()
    QTest.mouseClick(screen.history.viewport(), Qt.MouseButton.LeftButton, pos=row)
    QTest.mouseDClick(screen.history.viewport(), Qt.MouseButton.LeftButton, pos=row)
    assert opened == [("J-2026-0200", "bumper", ids[1])]
    return [first, second]


def _check_shown(screen: InstrumentsScreen, m) -> None:
    # colour at every geometry: the table holds the model's Lab of each measured spectrum
    assert m.geometries == ("45as-15", "45as15", "45as25", "45as45", "45as75", "45as110")
    np.testing.assert_allclose(screen.lab_table(), np.round(reflectance_to_lab(m.spectra), 2), atol=0.006)
    # the gloss meter's values, shown, and its 60° gloss in the design fit
    g = m.gloss
    assert g is not None and set(g.gloss_gu) == {20, 60, 85}
    text = screen.gloss.text()
    for k in (20, 60, 85):
        assert f"{k}° {g.gloss_gu[k]:.1f} GU" in text
    assert f"haze {g.haze_hu:.1f} HU" in text and f"DOI {g.doi:.1f}" in text
    assert (
        m.gloss_gu == g.gloss_gu[60]
        and m.design is not None
        and m.design.gloss_gu == pytest.approx(g.gloss_gu[60])
    )
    # the plot: its titles, ticks, and the fitted curve over the measured range −15…110°
    plot = screen.plot
    assert TITLE.startswith("L*, a*, b* against aspecular angle") and X_TITLE == "aspecular angle (°)"
    assert set(m.aspecular_deg) <= set(ANGLE_TICKS)
    a = plot.curve_angles()
    assert a[0] == -15.0 and a[-1] == 110.0
    # the model is a function of the unsigned angle: the curve at −15° is the fit's value at 15°
    np.testing.assert_allclose(plot.curve()[0], m.design.lab_at(15.0), atol=1e-9)
    lo, hi = plot.y_axis(0)
    assert lo <= plot.curve()[:, 0].min() and plot.curve()[:, 0].max() <= hi
    img = plot.grab().toImage()
    assert (
        img.width() == plot.width() and len({img.pixel(x, img.height() // 2) for x in range(img.width())}) > 3
    )


def test_technician_day_local(qtbot, tmp_path):
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    screen = InstrumentsScreen(MeasurementStore(sink))
    qtbot.addWidget(screen)
    first, second = _day(qtbot, screen)
    _check_shown(screen, second)
    # the job's history: both scans listed with their row ids
    history = [screen.stored.item(i).text() for i in range(screen.stored.count())]
    ids = [m.receipt.measurement_id for m in (first, second)]
    assert len(history) == 2 and all("J-2026-0200 bumper" in h for h in history)
    assert [f"#{i}" in h for i, h in zip(ids, history, strict=True)] == [True, True]
    # each reading stored once, with the paired gloss meter's 60° value
    engine = create_engine(url)
    with Session(engine) as s:
        rows = s.execute(select(MeasurementRow).order_by(MeasurementRow.id)).scalars().all()
        got: list[tuple[object, ...]] = [(r.id, r.gloss_gu, r.gloss_geometry_deg) for r in rows]
    engine.dispose()
    assert got == [
        (i, pytest.approx(m.gloss_gu, abs=1e-6), 60) for i, m in zip(ids, (first, second), strict=True)
    ]
    assert first.receipt.status == second.receipt.status == "stored" and ids[0] != ids[1]
    again = screen.store.persist(second).receipt
    assert again is not None and again.status == "duplicate"
    screen.close()
    sink.close()


def _gloss_alone(qtbot, screen: InstrumentsScreen, job: str):
    """Connect the gloss meter alone, type the panel and scan by clicks; the measurement shown."""
    screen.show()
    _type(screen.device.lineEdit(), "sim:gloss")
    _click(qtbot, screen, screen.connect_btn)
    _type(screen.job, job)
    screen.part.setCurrentIndex(screen.part.findText("roof"))
    _click(qtbot, screen, screen.scan_btn)
    m = screen.store.items[-1]
    assert m.gloss_only and m.receipt is None and m.gloss is not None
    assert "ERROR" not in screen.log.toPlainText(), screen.log.toPlainText()
    assert f"60° {m.gloss.gloss_gu[60]:.1f} GU" in screen.gloss.text()
    return m


def _expected_gloss_row(m) -> tuple:
    """The row a gloss-only reading must become: its own record, the meter's values as it read them."""
    g = m.gloss
    return (str(m.gloss_record.client_id), g.gloss_gu[20], g.gloss_gu[60], g.gloss_gu[85], g.haze_hu, g.doi)


def _check_row(got: tuple, m) -> None:
    want = _expected_gloss_row(m)
    assert str(got[0]) == want[0] and got[1:] == pytest.approx(want[1:], abs=1e-9)


def test_a_gloss_meter_alone_is_stored_as_a_gloss_reading_of_the_panel(qtbot, tmp_path):
    """As ``station measure sim:gloss --store`` and the service's gloss measure: a gloss reading of its own
    (gloss_readings), on the panel typed, no colour measurement; a re-send stores nothing new."""
    from db.models import GlossReading, Panel

    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    sink = LocalSink(url, tmp_path / "outbox.sqlite3")
    screen = InstrumentsScreen(MeasurementStore(sink))
    qtbot.addWidget(screen)
    m = _gloss_alone(qtbot, screen, "J-2026-0300")
    g = m.gloss_receipt
    assert g is not None and g.status == "stored" and g.gloss_reading_id is not None
    assert screen.state.text() == f"stored as gloss reading {g.gloss_reading_id}"
    assert f"gloss #{g.gloss_reading_id}" in screen.stored.item(0).text() and sink.pending() == 0
    engine = create_engine(url)
    with Session(engine) as s:
        rows = s.execute(select(GlossReading, Panel).join(Panel, Panel.id == GlossReading.panel_id)).all()
        colour = s.scalars(select(MeasurementRow)).all()
    engine.dispose()
    assert colour == [] and len(rows) == 1
    row, panel = rows[0]
    assert (panel.job, panel.part) == ("J-2026-0300", "roof") and row.id == g.gloss_reading_id
    _check_row((row.client_id, row.gloss_20_gu, row.gloss_60_gu, row.gloss_85_gu, row.haze_hu, row.doi), m)
    again_gloss = screen.store.persist(m).gloss_receipt
    assert again_gloss is not None and again_gloss.status == "duplicate"
    screen.close()
    sink.close()


def test_a_gloss_meter_alone_in_service_mode_is_stored_by_the_service(qtbot, tmp_path):
    from tests.api.conftest import make_api
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        token = api.tokens[next(r for r in api.tokens if r.value == "technician")]
        sink = ServiceSink(ServiceClient("http://testserver", token, client=api.http), tmp_path / "o.sqlite3")
        screen = InstrumentsScreen(MeasurementStore(sink))
        qtbot.addWidget(screen)
        m = _gloss_alone(qtbot, screen, "J-2026-0301")
        g = m.gloss_receipt
        assert g is not None and g.status == "stored", screen.log.toPlainText()
        tech = api.auth("technician")
        rows = api.client.get("/api/v1/qc/gloss", params={"job": "J-2026-0301"}, headers=tech).json()
        assert [r["id"] for r in rows["data"]] == [g.gloss_reading_id]
        r = rows["data"][0]
        _check_row(
            (r["client_id"], r["gloss_20_gu"], r["gloss_60_gu"], r["gloss_85_gu"], r["haze_hu"], r["doi"]), m
        )
        assert api.client.get("/api/v1/measurements", headers=tech).json()["data"] == []
        screen.close()
        sink.close()
    finally:
        gen.close()


def test_technician_day_service_mode(qtbot, tmp_path):
    from tests.api.conftest import make_api
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        token = api.tokens[next(r for r in api.tokens if r.value == "technician")]
        service = ServiceClient("http://testserver", token, client=api.http)
        sink = ServiceSink(service, tmp_path / "outbox.sqlite3")
        screen = InstrumentsScreen(MeasurementStore(sink))
        qtbot.addWidget(screen)
        first, second = _day(qtbot, screen)
        _check_shown(screen, second)
        rows = api.client.get("/api/v1/measurements", headers=api.auth("technician")).json()["data"]
        by_id = {r["id"]: r for r in rows}
        for m in (first, second):
            assert m.receipt.status == "stored", m.receipt
            row = by_id[m.receipt.measurement_id]
            assert row["gloss_gu"] == pytest.approx(m.gloss_gu, abs=1e-6)
        assert len(rows) == 2
        screen.close()
        sink.close()
    finally:
        gen.close()
