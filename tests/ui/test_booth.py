"""Booth screen: real widgets driven by clicks over a real database holding a metameric pair."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from station.model.booth import metameric_pair
from station.model.difference import delta_e
from station.model.domain import ANGLES_5
from station.model.examples import SILVER
from station.model.spectra import reflectance_from_lab, reflectance_to_lab
from station.render.booth import BoothRenderer
from tests.qc.conftest import populate
from tests.ui.screens import item_at, screen_of
from ui.booth_figures import add_pair
from ui.models.booth import BoothModel, LocalBoothSource
from ui.widgets.booth_screen import COLUMNS, BoothScreen

pytestmark = [pytest.mark.qt]

ANGLES = list(ANGLES_5)
SIZE = 128


def _click(qtbot, widget) -> None:
    qtbot.mouseClick(widget, Qt.MouseButton.LeftButton)


def _column(screen: BoothScreen, name: str) -> list[float]:
    j = COLUMNS.index(name)
    return [float(item_at(screen.table, i, j).text()) for i in range(screen.table.rowCount())]


@pytest.fixture(scope="module")
def spectra() -> tuple[np.ndarray, np.ndarray]:
    std, smp = metameric_pair(reflectance_from_lab(SILVER.lab_at(ANGLES)), strength=0.3)
    return std.round(6), smp.round(6)


def _database(tmp_path: Path, spectra) -> tuple[str, int, int]:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as session:
        populate(session)  # a job history without spectra around the pair
        ids = add_pair(session, spectra, job="J-300", serial="900001", operator="ana")
        session.commit()
    engine.dispose()
    return url, ids[0], ids[1]


def _pick(qtbot, screen: BoothScreen, role: str, measurement_id: int) -> None:
    """Open the role's picker and choose the measurement with the keyboard, as a person does."""
    picker = screen.pickers[role]
    index = picker.findData(measurement_id)
    assert index > 0
    picker.setFocus()
    _click(qtbot, picker)
    view = picker.view()
    view.setCurrentIndex(picker.model().index(index, 0))
    qtbot.keyClick(view, Qt.Key.Key_Return)


@pytest.fixture
def screen(qtbot, tmp_path, spectra):
    url, std_id, smp_id = _database(tmp_path, spectra)
    s = BoothScreen(BoothModel(LocalBoothSource(url), BoothRenderer(SIZE)))
    qtbot.addWidget(s)
    s.show()
    s.ids = (std_id, smp_id)  # type: ignore[attr-defined]
    return s


def test_metameric_pair_from_the_job_history_d65_then_a(qtbot, screen, spectra) -> None:
    std_id, smp_id = screen.ids
    assert screen.pickers["standard"].count() > 10  # the job history, newest first
    assert screen.pickers["standard"].itemData(1) == smp_id
    _pick(qtbot, screen, "standard", std_id)
    assert screen.table.rowCount() == 0 and "trial" in screen.message.text()
    _pick(qtbot, screen, "trial", smp_id)
    assert screen.table.rowCount() == len(ANGLES)
    # Under D65 the pair is a metameric match: ΔE00 ≈ 0 at every geometry.
    assert max(_column(screen, "ΔE00")) < 0.01
    d65_picture = screen.last_view.image.copy()
    _click(qtbot, screen.illuminant_btns["A"])
    # Under A: the difference colour-science's CIEDE2000 gives for the stored spectra, per geometry.
    std, smp = spectra
    expected = delta_e(reflectance_to_lab(std, "A"), reflectance_to_lab(smp, "A"), "cie2000")
    np.testing.assert_allclose(_column(screen, "ΔE00"), expected, atol=0.006)
    assert min(_column(screen, "ΔE00")) > 2.0
    # The special index: the trial corrected additively by its D65 difference (CIE 15), then ΔE00 under A.
    d65_offset = reflectance_to_lab(smp, "D65") - reflectance_to_lab(std, "D65")
    mi = delta_e(reflectance_to_lab(std, "A"), reflectance_to_lab(smp, "A") - d65_offset, "cie2000")
    np.testing.assert_allclose(_column(screen, "MI"), mi, atol=0.006)
    a_picture = screen.last_view.image
    assert np.abs(a_picture.astype(int) - d65_picture.astype(int)).max() > 10  # the picture changed
    assert "A" in screen.message.text()
    _click(qtbot, screen.illuminant_btns["F11"])
    assert _column(screen, "ΔE00") != list(expected.round(2))
    assert screen.illuminant_btns["F11"].isChecked() and not screen.illuminant_btns["A"].isChecked()


def test_shape_observer_and_a_user_spd(qtbot, screen, tmp_path, monkeypatch) -> None:
    std_id, smp_id = screen.ids
    _pick(qtbot, screen, "standard", std_id)
    _pick(qtbot, screen, "trial", smp_id)
    panels = screen.last_view.image.copy()
    screen.shape.setFocus()
    qtbot.keyClick(screen.shape, Qt.Key.Key_Down)  # panels → seam
    assert screen.booth.shape == "seam"
    assert not np.array_equal(screen.last_view.image, panels)
    screen.observer.setFocus()
    qtbot.keyClick(screen.observer, Qt.Key.Key_Down)  # 10° → 2°
    assert screen.booth.observer == "2"
    lamp = tmp_path / "lamp.csv"
    lamp.write_text("wavelength_nm,value\n" + "".join(f"{w:g},{50 + w / 10:g}\n" for w in range(380, 781, 5)))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(lamp), ""))
    _click(qtbot, screen.spd_btn)
    assert screen.booth.illuminant_name == "lamp" and screen.spd_btn.text() == "SPD: lamp"
    assert screen.table.rowCount() == len(ANGLES) and "lamp" in screen.message.text()


def test_bad_input_is_a_visible_message(qtbot, screen, tmp_path, monkeypatch) -> None:
    std_id, _ = screen.ids
    no_spectra = screen.pickers["trial"].findData(std_id - 1)  # a measurement of the job without spectra
    assert "no spectra" in screen.pickers["trial"].itemText(no_spectra)
    _pick(qtbot, screen, "trial", std_id - 1)
    assert "error" in screen.message.text() and "spectra" in screen.message.text()
    assert screen.message.isVisible()
    bad = tmp_path / "lamp.csv"
    bad.write_text("wavelength_nm,value\n500,1\n")
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(bad), ""))
    _click(qtbot, screen.spd_btn)
    assert "error" in screen.message.text() and "lamp.csv" in screen.message.text()
    assert screen.illuminant_btns["D65"].isChecked()  # the choice stays on the illuminant in use
    junk = tmp_path / "trial.json"
    junk.write_text("{not json")
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(junk), ""))
    _click(qtbot, screen.file_btns["trial"])
    assert "error" in screen.message.text() and "trial.json" in screen.message.text()


def test_no_database_says_so(qtbot) -> None:
    s = BoothScreen(BoothModel(None, BoothRenderer(SIZE)))
    qtbot.addWidget(s)
    assert "from files" in s.message.text()


def test_the_main_window_booth_tab_reads_the_scans_database(qtbot, tmp_path, spectra) -> None:
    from ui.app import MainWindow
    from ui.models.measure_db import LocalSink

    url, std_id, _ = _database(tmp_path, spectra)
    win = MainWindow(sink=LocalSink(url, tmp_path / "outbox.sqlite3"), ask_on_close=False)
    qtbot.addWidget(win)
    win.show()
    qtbot.waitExposed(win)
    bar = win.tabs.tabBar()
    k = next(i for i in range(win.tabs.count()) if win.tabs.tabText(i) == "Booth")
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(k).center())
    booth = screen_of(win, "Booth", BoothScreen)
    assert win.tabs.widget(k) is win.screens["Booth"]
    assert booth.pickers["standard"].findData(std_id) > 0
    win.view_panel.view.wait_idle()
    win.close()


def test_pair_from_a_services_measurements(qtbot, tmp_path, spectra) -> None:
    from station.qc.booth import booth_compare_spectra
    from tests.api.conftest import make_api
    from tests.ingest._readings import make_reading
    from ui.models.booth import ServiceBoothSource
    from ui.models.service import ServiceClient

    angles = [15.0, 45.0, 110.0]
    rows = [ANGLES.index(a) for a in angles]
    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        tech = api.auth("technician")
        panel = api.client.post("/api/v1/panels", json={"job": "J-SVC", "part": "door"}, headers=tech)
        ids = []
        for k, sp in enumerate(spectra):
            body = make_reading(7, k, panel_id=panel.json()["id"]).model_dump(mode="json")
            body["lab"] = reflectance_to_lab(sp[rows]).round(4).tolist()
            body["spectra"] = sp[rows].tolist()
            r = api.client.post("/api/v1/measurements", json=body, headers=tech)
            assert r.status_code == 201, r.text
            ids.append(r.json()["id"])
        service = ServiceClient("http://testserver", api.tokens[next(iter(api.tokens))], client=api.http)
        s = BoothScreen(BoothModel(ServiceBoothSource(service), BoothRenderer(SIZE)))
        qtbot.addWidget(s)
        s.show()
        assert "J-SVC door" in s.pickers["standard"].itemText(s.pickers["standard"].findData(ids[0]))
        _pick(qtbot, s, "standard", ids[0])
        _pick(qtbot, s, "trial", ids[1])
        _click(qtbot, s.illuminant_btns["F11"])
        expected = booth_compare_spectra(spectra[0][rows], spectra[1][rows], angles, ["F11"]).illuminants[0]
        np.testing.assert_allclose(_column(s, "ΔE00"), [g.de00 for g in expected.per_geometry], atol=0.006)
        assert min(_column(s, "ΔE00")) > 2.0
        r = api.client.get("/api/v1/measurements/999999", headers=tech)
        assert r.status_code == 404
        s.pickers["trial"].addItem("#999999 gone", 999999)
        _pick(qtbot, s, "trial", 999999)
        assert "error" in s.message.text() and "404" in s.message.text()
    finally:
        gen.close()
