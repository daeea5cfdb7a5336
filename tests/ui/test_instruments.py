"""Instruments screen against the MA6 simulator subprocess (real pty, real driver): connect, calibrate,
scan with progress in a worker thread, the measurement is stored, shown and usable as the design."""

from __future__ import annotations

import json

import numpy as np
import pytest

from station.errors import InputError
from ui.models.document import DesignDocument
from ui.models.instruments import InstrumentSession, MeasurementStore
from ui.widgets.instruments_screen import InstrumentsScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]


def test_scan_with_simulator_stores_and_shows_measurement(qtbot, tmp_path):
    store = MeasurementStore(tmp_path / "m.jsonl")
    doc = DesignDocument()
    screen = InstrumentsScreen(store, doc)
    qtbot.addWidget(screen)
    screen.show()
    screen.device.setCurrentText("sim:ma6")
    screen.connect_btn.click()
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert screen.session.connected, screen.log.toPlainText()
    assert screen.scan_btn.isEnabled()
    screen.calibrate_btn.click()
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert "calibration" in screen.log.toPlainText() and "passed" in screen.state.text(), screen.log.toPlainText()
    screen.panel.setText("door-7")
    steps: list[int] = []
    screen.scan_btn.click()
    screen.task.progress.connect(lambda s, _t: steps.append(s))
    qtbot.waitUntil(lambda: screen.idle, timeout=90000)
    assert len(store.items) == 1, screen.log.toPlainText()
    m = store.items[0]
    assert screen.progress.value() == screen.progress.maximum()
    assert m.panel == "door-7" and m.device == "sim:ma6"
    assert len(m.geometries) == 6 and m.lab.shape == (6, 3)
    # shown: the table holds the stored Lab, the list one entry, the file one JSON line
    np.testing.assert_allclose(screen.lab_table(), np.round(m.lab, 2), atol=0.006)
    assert screen.stored.count() == 1
    assert screen.plot.design == m.design and screen.plot.points[1].shape == (6, 3)
    rec = json.loads((tmp_path / "m.jsonl").read_text().splitlines()[0])
    assert rec["panel"] == "door-7" and len(rec["lab"]) == 6
    # Lab comes from the spectra through the model, independently recomputed here
    from station.model.spectra import reflectance_to_lab

    np.testing.assert_allclose(m.lab, reflectance_to_lab(m.spectra), atol=1e-9)
    assert m.design is not None
    screen.use_btn.click()
    assert doc.design == m.design and doc.can_undo
    screen.close()
    assert not screen.session.connected


def test_session_refuses_bad_input_without_starting_anything():
    s = InstrumentSession()
    with pytest.raises(InputError, match="device"):
        s.connect("sim:nope")
    with pytest.raises(InputError, match="instrument"):
        s.scan("p1")
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
