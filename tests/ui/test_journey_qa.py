"""QA engineer's day on the QA screen, driven by clicks and key presses: open the stored bumper and fender
scans (a real SQLite database locally, the real FastAPI service in service mode), run the seam analysis,
see the seam pictured at the analysed geometry — and that the picture agrees with the verdict and says
which geometry it shows — pick another geometry, export the report, send the corrected paint on.

The agreement is checked on the shown pixels: the colours beside the seam, decoded from the displayed
sRGB back to Lab with the shown exposure undone, differ by the seam ΔE the report gives there."""

from __future__ import annotations

import datetime as dt
import json

import numpy as np
import pytest
from PySide6.QtCore import Qt, QTimer
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QFileDialog, QLineEdit

from station.analysis.qa import seam_qa
from station.drivers.readings import SpectralReading
from station.model.colorimetry import linear_srgb_to_lab
from station.model.display import decode_display
from station.model.spectra import reflectance_to_lab
from tests.ui.dialogs import enter_file_name
from tests.ui.screens import item_at
from ui.models.designer import DesignerModel
from ui.models.document import DesignDocument
from ui.models.instruments import MeasurementStore, measurement_from_reading
from ui.models.measure_db import LocalSink, PanelInfo, ServiceSink
from ui.widgets.qa_screen import PICTURE_SIZE, QAScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]

WAVELENGTHS = np.arange(400.0, 701.0, 10.0)


def _metallic(serial: str, shift: float) -> SpectralReading:
    """A red metallic as an MA6 reads it (six 45° geometries): bright near specular, dark at 110°;
    *shift* lightens the whole reading (the fender's batch)."""
    red = 0.15 + 0.75 / (1.0 + np.exp(-(WAVELENGTHS - 600.0) / 15.0))
    scale = {-15: 1.1, 15: 1.0, 25: 0.62, 45: 0.26, 75: 0.09, 110: 0.05}
    refl = np.array([np.clip(red * k * (1.0 + shift), 0.0, 2.0) for k in scale.values()])
    return SpectralReading(
        tuple(f"45as{a}" for a in scale),
        refl,
        23.0,
        serial,
        "CAL-1",
        dt.datetime(2026, 11, 23, 7, 0, tzinfo=dt.UTC),
        model="MA-T6",
    )


def _store_scans(store: MeasurementStore) -> None:
    for serial, panel, shift in (
        ("SIM-Q-1", PanelInfo("J-2026-0300", "bumper", "PP/EPDM"), 0.0),
        ("SIM-Q-2", PanelInfo("J-2026-0300", "fender", "steel"), 0.04),
    ):
        m = store.persist(measurement_from_reading(_metallic(serial, shift), panel, "sim:ma6"))
        assert m.receipt is not None
        assert m.receipt.status == "stored", m.receipt


def _pick(combo, prefix: str) -> None:
    """Choose the entry starting with *prefix* with the keyboard (focus, then arrow keys)."""
    target = next(i for i in range(combo.count()) if combo.itemText(i).startswith(prefix))
    combo.setFocus()
    key = Qt.Key.Key_Down if target > combo.currentIndex() else Qt.Key.Key_Up
    while combo.currentIndex() != target:
        QTest.keyClick(combo, key)


def _run(qtbot, screen: QAScreen) -> None:
    screen.report = None
    QTest.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.report is not None and not screen.task.isRunning(), timeout=60000)
    qtbot.waitUntil(screen.run_btn.isEnabled, timeout=5000)


def _seam_de_shown(screen: QAScreen) -> float:
    """ΔE*ab between the displayed pixels just left and right of the seam (exposure undone)."""
    img = screen.as_is.pixmap().toImage()
    h, w = PICTURE_SIZE
    assert (img.height(), img.width()) == (h, w)
    assert screen.pictures is not None
    scale = screen.pictures[2]
    rgb = []
    for x in (w // 2 - 1, w // 2):
        c = img.pixelColor(x, h // 2)
        rgb.append([c.redF(), c.greenF(), c.blueF()])
    lab = linear_srgb_to_lab(decode_display(np.array(rgb)) / scale)
    return float(np.linalg.norm(lab[1] - lab[0]))


def _click_row(screen: QAScreen, row: int) -> None:
    rect = screen.table.visualItemRect(item_at(screen.table, row, 0))
    QTest.mouseClick(screen.table.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())


def _export_via_dialog(qtbot, screen: QAScreen, path) -> None:
    """Click Export, type the file name into the dialog and press Enter."""

    def fill() -> None:
        dialog = QApplication.activeModalWidget()
        if isinstance(dialog, QFileDialog) and dialog.isVisible():
            name = dialog.findChild(QLineEdit, "fileNameEdit")
            assert name is not None
            enter_file_name(name, path)
        if screen.exported is None:  # the dialog not up yet, or still reading its folder: again
            QTimer.singleShot(300, fill)

    QTimer.singleShot(50, fill)
    QTest.mouseClick(screen.export_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.exported is not None, timeout=60000)


def _day(qtbot, screen: QAScreen, sent: list, tmp_path) -> None:
    screen.resize(1200, 700)
    screen.show()
    QTest.mouseClick(screen.load_btn, Qt.MouseButton.LeftButton)
    assert screen.details.text().startswith("2 stored measurements offered"), screen.details.text()
    _pick(screen.panel_a, "stored #1: J-2026-0300 bumper")
    _pick(screen.panel_b, "stored #1: J-2026-0300 bumper")  # the same scan on both panels first
    screen.beta.setFocus()
    QTest.keyClick(screen.beta, Qt.Key.Key_Right)  # +5° → +6°
    QTest.keyClick(screen.beta, Qt.Key.Key_Left)  # back to +5°
    assert screen.beta_label.text() == "+5°"
    _run(qtbot, screen)
    r = screen.report
    a, b = screen.picked()
    expected = seam_qa(a, b, 5.0, tolerance=screen.tolerance.value())
    assert r is not None
    assert r.seam_de == pytest.approx(expected.seam_de) and max(r.formulation_de) == 0.0
    # a 5° tilt of one metallic panel is a geometric seam: FAIL, and the picture shows it at the
    # worst geometry, saying which
    assert screen.verdict.text() == ("PASS" if expected.passed else "FAIL") == "FAIL"
    w = r.worst
    geo = r.geometries[w]
    assert screen.shown_geometry == w
    caption = screen.caption.text()
    assert "worst geometry" in caption and f"light {geo.light_deg:g}°, view {geo.view_deg:g}°" in caption
    assert f"seam ΔE {r.seam_de[w]:.2f}" in caption and "β = +5°" in caption
    assert _seam_de_shown(screen) == pytest.approx(r.seam_de[w], rel=0.05, abs=0.6)
    assert f"ΔE {r.seam_de[w]:.2f} FAIL here" in screen.as_is_title.text()
    # another geometry by clicking its row: the picture and caption follow, and still agree
    best = int(np.argmin(r.seam_de))
    _click_row(screen, best)
    assert screen.shown_geometry == best and "worst geometry" not in screen.caption.text()
    assert _seam_de_shown(screen) == pytest.approx(r.seam_de[best], rel=0.05, abs=0.6)
    # bumper against fender, aligned better: the fender's batch is lighter (formulation ΔE)
    _pick(screen.panel_b, "stored #2: J-2026-0300 fender")
    QTest.keyClick(screen.beta, Qt.Key.Key_Home)  # −45°: the slider's minimum
    for _ in range(46):
        QTest.keyClick(screen.beta, Qt.Key.Key_Right)
    assert screen.beta_label.text() == "+1°"
    _run(qtbot, screen)
    r = screen.report
    assert r is not None
    assert max(r.formulation_de) > 1.0 and r.beta_deg == 1.0
    assert _seam_de_shown(screen) == pytest.approx(r.seam_de[r.worst], rel=0.05, abs=0.6)
    # export: JSON and PNG written where the dialog was told
    _export_via_dialog(qtbot, screen, tmp_path / "out" / "bumper-fender.json")
    assert screen.exported is not None
    js, png = screen.exported
    doc = json.loads(js.read_text())
    assert js == tmp_path / "out" / "bumper-fender.json" and png.stat().st_size > 10_000
    assert doc["seam_de_max"] == pytest.approx(max(r.seam_de)) and doc["passed"] == r.passed
    assert str(js) in screen.details.text()
    QTest.mouseClick(screen.send_btn, Qt.MouseButton.LeftButton)
    assert sent == [r.correction.paint]
    screen.close()


def test_qa_day_local(qtbot, tmp_path):
    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    _store_scans(store)
    sent: list = []
    screen = QAScreen(DesignerModel(DesignDocument()), store, sent.append)
    qtbot.addWidget(screen)
    _day(qtbot, screen, sent, tmp_path)
    sink.close()


def test_qa_day_service_mode(qtbot, tmp_path):
    from tests.api.conftest import make_api
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        tech = ServiceClient("http://testserver", api.tokens[_role(api, "technician")], client=api.http)
        tech_sink = ServiceSink(tech, tmp_path / "tech-outbox.sqlite3")
        _store_scans(MeasurementStore(tech_sink))
        tech_sink.close()
        qa = ServiceClient("http://testserver", api.tokens[_role(api, "qa")], client=api.http)
        sink = ServiceSink(qa, tmp_path / "outbox.sqlite3")
        sent: list = []
        screen = QAScreen(DesignerModel(DesignDocument()), MeasurementStore(sink), sent.append)
        qtbot.addWidget(screen)
        _day(qtbot, screen, sent, tmp_path)
        sink.close()
    finally:
        gen.close()


def _role(api, name: str):
    return next(r for r in api.tokens if r.value == name)


def test_the_metallic_reading_is_what_the_scans_store():
    """The hand-made reading is in the Lab domain and metallic (lighter near specular)."""
    lab = reflectance_to_lab(_metallic("S", 0.0).reflectance)
    assert np.all(np.diff(lab[1:, 0]) < 0) and 0 < lab[-1, 0] < lab[1, 0] <= 100.0
