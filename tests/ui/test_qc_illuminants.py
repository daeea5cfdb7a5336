"""QC screen's illuminant limits: typed and judged with real clicks over a real database.

The job holds a metameric pair (equal under D65, different under A); its indices come from
colour-science's own integration of the same spectra (tests.qc.test_illuminant_rows).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog, QTableWidgetItem

from db.engine import make_engine, make_sessionmaker
from db.migrate import ensure_at_head
from tests.qc.test_illuminant_rows import _job, _mi_cs, _pair
from ui.models.qc import LocalQc, QcModel
from ui.widgets.qc_screen import COLUMNS, QcScreen

pytestmark = [pytest.mark.qt]


def _cell(screen: QcScreen, row: int, column: int) -> QTableWidgetItem:
    item = screen.table.item(row, column)
    assert item is not None
    return item


def _column(screen: QcScreen, name: str) -> list[str]:
    j = COLUMNS.index(name)
    return [_cell(screen, i, j).text() for i in range(screen.table.rowCount())]


def test_illuminant_limits_fail_the_metameric_sample(qtbot, tmp_path: Path, monkeypatch) -> None:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    ensure_at_head(url)
    engine = make_engine(url)
    with make_sessionmaker(engine)() as session:
        _, metameric, equal = _job(session)
    engine.dispose()
    std, smp = _pair()
    mi_a = _mi_cs(std, smp, "A")
    limit = float(np.median(mi_a))  # the rows split: geometries above it fail

    screen = QcScreen(QcModel(LocalQc(url)))
    qtbot.addWidget(screen)
    screen.show()
    qtbot.mouseClick(screen.load_btn, Qt.MouseButton.LeftButton)
    screen.job.setCurrentText("J-300")
    screen.part.setCurrentText("door")
    screen.formula.setCurrentText("cie2000")
    qtbot.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
    assert _column(screen, "verdict") == ["pass"] * 6  # equal under D65

    qtbot.keyClicks(screen.limits, f"A={limit}")
    qtbot.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
    samples = _column(screen, "sample")
    verdicts = dict(
        zip(zip(samples, _column(screen, "geometry"), strict=True), _column(screen, "verdict"), strict=True)
    )
    for geo, mi in zip(("45as15", "45as45", "45as110"), mi_a, strict=True):
        assert verdicts[(str(metameric), geo)] == ("fail" if mi > limit else "pass")
        assert verdicts[(str(equal), geo)] == "pass"
    reasons = _column(screen, "reason")
    assert f"A 45as15: MI {mi_a[0]:.2f} > {limit:.2f} fail" in reasons[samples.index(str(metameric))]
    assert "pass 1 · warn 0 · fail 1" in screen.standard.text()
    row = COLUMNS.index("verdict")
    assert _cell(screen, samples.index(str(metameric)), row).background().color().name() == "#f4a09a"

    pdf = tmp_path / "report.pdf"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", staticmethod(lambda *a, **k: (str(pdf), "")))
    qtbot.mouseClick(screen.pdf_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.last_report == pdf, timeout=60000)
    assert screen.task is not None
    screen.task.wait()
    body = pdf.read_bytes()
    assert body.startswith(b"%PDF")
    assert (
        body.count(b"/Type /Page ") + body.count(b"/Type /Page\n") == 1 + 4
    )  # with the illuminant rows page

    screen.limits.clear()
    qtbot.keyClicks(screen.limits, "Q9=1")
    qtbot.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
    assert screen.status.text().startswith("error: illuminant_limits.Q9")
    screen.close()
