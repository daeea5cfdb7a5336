"""QA screen: two designs and a misalignment give the core's seam report, the verdict and the renderings."""

from __future__ import annotations

import pytest

from station.analysis.qa import seam_qa
from station.model import FaceFlopTravelGloss
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
    sent: list[FaceFlopTravelGloss] = []
    screen = QAScreen(designer, MeasurementStore(), sent.append)
    qtbot.addWidget(screen)
    screen.resize(900, 600)
    screen.show()
    screen.panel_a.setCurrentText("palette: A")
    screen.panel_b.setCurrentText("palette: B")
    screen.beta.setValue(6)
    assert screen.beta_label.text() == "+6°"
    screen.run_btn.click()
    qtbot.waitUntil(lambda: screen.report is not None, timeout=60000)
    assert screen.task is not None
    screen.task.wait()
    expected = seam_qa(DEFAULT_DESIGN, DEFAULT_DESIGN.replace(gloss_gu=60.0), 6.0)
    assert screen.report is not None and screen.report.seam_de == pytest.approx(expected.seam_de)
    assert screen.verdict.text() == ("PASS" if expected.passed else "FAIL")
    assert screen.table.rowCount() == len(expected.geometries)
    # the correction is an optimisation: equal to a separate run to its convergence (≈1e-6), not bit for bit
    shown = screen.report.correction.paint
    for field in ("face", "flop"):
        assert expected is not None
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


def test_stored_measurements_from_the_local_database_are_panels(qtbot, tmp_path):
    from tests.ui.test_instruments import _spectral
    from ui.models.instruments import measurement_from_reading
    from ui.models.measure_db import LocalSink, PanelInfo

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    m = store.persist(measurement_from_reading(_spectral(), PanelInfo("J-3", "door", "steel"), "test"))
    assert m.receipt is not None
    assert m.receipt.status == "stored"
    screen = QAScreen(DesignerModel(DesignDocument()), store)
    qtbot.addWidget(screen)
    assert screen.load_stored() == 1
    label = f"stored #{m.receipt.measurement_id}: J-3 door"
    picked = [lbl for lbl, _d in screen.sources() if lbl.startswith(label)]
    assert len(picked) == 1 and screen.panel_a.findText(picked[0]) >= 0
    screen.panel_a.setCurrentText(picked[0])
    got = screen.picked()[0]
    for f in ("face", "flop", "travel_deg"):
        assert getattr(got, f) == pytest.approx(getattr(m.design, f), abs=1e-3)
    screen.close()
    sink.close()


def test_stored_measurements_failure_is_shown(qtbot, tmp_path):
    from ui.models.measure_db import LocalSink

    blocker = tmp_path / "f"
    blocker.write_text("not a folder")
    screen = QAScreen(
        DesignerModel(DesignDocument()),
        MeasurementStore(LocalSink(f"sqlite:///{blocker / 'x.sqlite3'}", tmp_path / "o.sqlite3")),
    )
    qtbot.addWidget(screen)
    assert screen.load_stored() == 0
    assert screen.verdict.text() == "error" and "unreachable" in screen.details.text()
    screen.close()


def _stored_labels(screen) -> list[str]:
    """Entries of panel A's picker that are stored measurements, as the user sees them."""
    items = [screen.panel_a.itemText(i) for i in range(screen.panel_a.count())]
    return [t for t in items if t.startswith("stored #")]


def test_clicking_load_stored_offers_every_stored_measurement(qtbot, tmp_path):
    """A click (Qt sends ``checked=False``) loads the default number, not 0 rows."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from tests.ui.test_instruments import _spectral
    from ui.models.instruments import measurement_from_reading
    from ui.models.measure_db import LocalSink, PanelInfo

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    store = MeasurementStore(sink)
    panels = [
        PanelInfo("J-9", "bumper", "PP"),
        PanelInfo("J-9", "fender", "steel"),
        PanelInfo("J-10", "door"),
    ]
    ids = []
    for i, panel in enumerate(panels):
        m = store.persist(measurement_from_reading(_spectral(f"SIM-T-{i}"), panel, "test"))
        assert m.receipt is not None
        assert m.receipt.status == "stored", m.receipt
        ids.append(m.receipt.measurement_id)
    screen = QAScreen(DesignerModel(DesignDocument()), store)
    qtbot.addWidget(screen)
    screen.show()
    assert _stored_labels(screen) == []
    QTest.mouseClick(screen.load_btn, Qt.MouseButton.LeftButton)
    shown = _stored_labels(screen)
    assert len(shown) == len(panels)
    for mid, p in zip(ids, panels, strict=True):
        assert sum(t.startswith(f"stored #{mid}: {p.job} {p.part} ") for t in shown) == 1
    assert screen.details.text().startswith(f"{len(panels)} stored measurements offered")
    assert screen.verdict.text() != "error"
    screen.close()
    sink.close()


@pytest.mark.parametrize("bad", [False, True, 0, -1, 1001, 2.5, "10", None])
def test_load_stored_refuses_a_limit_that_is_not_a_row_count(qtbot, tmp_path, bad):
    from station.errors import InputError
    from ui.models.measure_db import RECENT_MAX, LocalSink

    sink = LocalSink(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path / "outbox.sqlite3")
    screen = QAScreen(DesignerModel(DesignDocument()), MeasurementStore(sink))
    qtbot.addWidget(screen)
    with pytest.raises(InputError) as err:
        screen.load_stored(bad)
    assert err.value.field == "limit" and f"1 ≤ limit ≤ {RECENT_MAX}" in str(err.value)
    with pytest.raises(InputError):
        sink.recent(bad)
    screen.close()
    sink.close()


def _type(qtbot, edit, text: str) -> None:
    """Select the field's text and type *text* over it, as a person does."""
    from PySide6.QtCore import Qt

    qtbot.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    qtbot.keyClicks(edit, text)


def test_bad_lights_clear_the_last_answer_and_name_the_field(qtbot):
    from PySide6.QtCore import Qt

    designer = DesignerModel(DesignDocument())
    designer.keep("A")
    designer.set_gloss(60.0)
    designer.keep("B")
    screen = QAScreen(designer, MeasurementStore(), lambda _p: None)
    qtbot.addWidget(screen)
    screen.resize(900, 600)
    screen.show()
    screen.panel_a.setCurrentText("palette: A")
    screen.panel_b.setCurrentText("palette: B")
    _type(qtbot, screen.aspecular, "15, 45")
    qtbot.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.report is not None, timeout=60000)
    qtbot.waitUntil(screen.run_btn.isEnabled, timeout=10000)
    assert screen.export_btn.isEnabled() and screen.table.rowCount() > 0
    assert screen.as_is.pixmap() is not None and not screen.as_is.pixmap().isNull()
    assert "ΔE" in screen.as_is_title.text()
    # another misalignment: the answer of the last run leaves the screen too
    qtbot.keyClick(screen.beta, Qt.Key.Key_Right)
    assert screen.beta_label.text() == "+6°" and screen.verdict.text() == "—"
    assert screen.report is None and screen.table.rowCount() == 0 and not screen.export_btn.isEnabled()
    assert screen.caption.text() == "the panels or β changed: run QA again"
    qtbot.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.report is not None, timeout=60000)
    qtbot.waitUntil(screen.run_btn.isEnabled, timeout=10000)
    assert screen.report is not None and screen.report.beta_deg == 6.0 and screen.export_btn.isEnabled()
    _type(qtbot, screen.lights, "30, abc, 95")
    qtbot.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    assert screen.verdict.text() == "error"
    message = screen.details.text()
    assert message.startswith("lights: expected") and "-90 < angle < 90" in message and "abc" in message
    assert screen.report is None and screen.pictures is None
    assert screen.table.rowCount() == 0
    assert screen.as_is.pixmap().isNull() and screen.fixed.pixmap().isNull()
    assert "ΔE" not in screen.as_is_title.text() and "ΔE" not in screen.fixed_title.text()
    assert screen.caption.text() == ""
    assert not screen.export_btn.isEnabled() and not screen.send_btn.isEnabled()
    # a number out of range is named too: the light at 95° is below the horizon
    _type(qtbot, screen.lights, "30, 95")
    qtbot.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    assert screen.details.text() == "lights: expected comma-separated angles, -90 < angle < 90, got 95.0"
    _type(qtbot, screen.lights, "30")
    _type(qtbot, screen.aspecular, "15, 400")
    qtbot.mouseClick(screen.run_btn, Qt.MouseButton.LeftButton)
    assert "aspecular range: expected" in screen.details.text() and "400" in screen.details.text()
    assert screen.report is None and not screen.export_btn.isEnabled()
    screen.close()
