"""The viewer shows, not drops, a gloss nobody measured: stored measurements without a paired gloss meter
reach the QA screen as "not measured", with a visible warning, and their designs say so."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.domain import DEFAULT_GLOSS_GU
from ui.models.designer import DesignerModel
from ui.models.document import DesignDocument
from ui.models.instruments import MeasurementStore
from ui.models.measure_db import StoredMeasurement, gloss_warning
from ui.widgets.qa_screen import QAScreen

pytestmark = [pytest.mark.qt]

LAB = np.array([[90.0, 2.0, -5.0], [50.0, 1.0, -3.0], [30.0, 0.5, -1.0]])


@pytest.mark.parametrize(("gloss", "measured"), [(None, False), (88.0, True)])
def test_stored_measurement_fit_keeps_the_gloss_state_and_its_warning(gloss, measured):
    m = StoredMeasurement(1, "J-1 door", "2026-01-01", (15.0, 45.0, 110.0), LAB, gloss)
    fit = m.fit()
    assert fit is not None and fit.design.gloss_measured is measured
    assert any("gloss not measured" in w for w in fit.warnings) is not measured
    assert m.design() == fit.design


def test_gloss_warning_names_the_designs_and_the_default():
    assert gloss_warning([]) == ""
    text = gloss_warning(["#3", "B′"])
    assert "#3, B′" in text and f"{DEFAULT_GLOSS_GU:g} GU" in text and "no matting" in text


def test_qa_screen_shows_the_not_measured_warning(qtbot, tmp_path):
    from tests.ui.test_instruments import _spectral
    from ui.models.instruments import measurement_from_reading
    from ui.models.measure_db import LocalSink, PanelInfo

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    m = store.persist(measurement_from_reading(_spectral(), PanelInfo("J-3", "door", "steel"), "test"))
    screen = QAScreen(DesignerModel(DesignDocument()), store)
    qtbot.addWidget(screen)
    assert screen.load_stored() == 1
    assert m.receipt is not None
    assert f"gloss not measured for #{m.receipt.measurement_id}" in screen.details.text()
    label = next(lbl for lbl, _d in screen.sources() if lbl.startswith("stored #"))
    screen.panel_a.setCurrentText(label)
    assert screen.picked()[0].gloss_target_gu is None
    screen.close()
    sink.close()
