"""QA screen: two designs and a misalignment give the core's seam report, the verdict and the renderings."""

from __future__ import annotations

import pytest

from station.analysis.qa import seam_qa
from ui.models.designer import DesignerModel
from ui.models.document import DEFAULT_DESIGN, DesignDocument
from ui.models.instruments import MeasurementStore
from ui.widgets.qa_screen import QAScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]


def test_qa_report_verdict_and_send(qtbot):
    doc = DesignDocument()
    designer = DesignerModel(doc)
    designer.keep("A")
    designer.set_gloss(60.0)
    designer.keep("B")
    sent = []
    screen = QAScreen(designer, MeasurementStore(), sent.append)
    qtbot.addWidget(screen)
    screen.resize(900, 600)
    screen.show()
    screen.panel_a.setCurrentText("palette: A")
    screen.panel_b.setCurrentText("palette: B")
    screen.beta.setValue(6)
    assert screen.as_is_model.settings.misalignment_deg == 6.0
    screen.run_btn.click()
    qtbot.waitUntil(lambda: screen.report is not None, timeout=60000)
    screen.task.wait()
    expected = seam_qa(DEFAULT_DESIGN, DEFAULT_DESIGN.replace(gloss_gu=60.0), 6.0)
    assert screen.report.seam_de == pytest.approx(expected.seam_de)
    assert screen.verdict.text() == ("PASS" if expected.passed else "FAIL")
    assert screen.table.rowCount() == len(expected.geometries)
    # the correction is an optimisation: equal to a separate run to its convergence (≈1e-6), not bit for bit
    shown = screen.fixed_model.designs[1]
    assert shown is screen.report.correction.paint
    for field in ("face", "flop"):
        assert getattr(shown, field) == pytest.approx(getattr(expected.correction.paint, field), abs=1e-3)
    screen.send_btn.click()
    assert sent == [screen.report.correction.paint]
    # a range the user typed reaches the core; bad text is refused with the field named
    screen.aspecular.setText("15, 45")
    qtbot.waitUntil(screen.run_btn.isEnabled, timeout=10000)  # the finished signal of the first run
    screen.run_btn.click()
    qtbot.waitUntil(lambda: len(screen.report.geometries) == 6, timeout=60000)
    screen.task.wait()
    screen.lights.setText("30, abc")
    qtbot.waitUntil(screen.run_btn.isEnabled, timeout=10000)
    screen.run_btn.click()
    assert screen.verdict.text() == "error" and "lights" in screen.details.text()
    screen.close()
