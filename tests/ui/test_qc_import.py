"""The QC tab without a terminal: vendor files imported by button and by drag and drop (through the one
ingest path into a real SQLite database), the standard chosen in the tab, a job opened from its history.

Expected values are independent of the product: the Lab values the test wrote into the files, and
CIEDE2000 of those values computed by colour-science."""

from __future__ import annotations

import math
from pathlib import Path

import colour
import numpy as np
import pytest
from PySide6.QtCore import QMimeData, QPointF, Qt, QUrl
from PySide6.QtGui import QDragEnterEvent, QDropEvent
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QFileDialog
from sqlalchemy import select

from db.engine import make_engine
from db.models import Measurement, Panel
from station.ingest.formats import write_measurement_file
from station.model.domain import ANGLES_6, aspecular_name
from tests.readings import lab_reading
from tests.ui.screens import item_at, screen_of
from ui.models.measure_db import LocalSink
from ui.models.qc import LocalQc, QcModel
from ui.widgets.instruments_screen import InstrumentsScreen
from ui.widgets.qc_screen import COLUMNS, QcScreen

pytestmark = [pytest.mark.qt]

GEOMETRIES = [aspecular_name(a) for a in ANGLES_6]
#: The master panel's Lab at the six geometries, and each trial's offset from it (ΔL*, Δa*, Δb*).
MASTER = [[92.0 - 9 * i, -1.5 + 0.2 * i, -6.0 + 0.5 * i] for i in range(len(GEOMETRIES))]
TRIALS = {"trial 1": (0.4, 0.1, -0.2), "trial 2": (-1.2, 0.6, 0.9), "trial 3": (0.05, -0.05, 0.1)}


def _sample(name: str, offset: tuple[float, float, float]):
    lab = [[v + d for v, d in zip(row, offset, strict=True)] for row in MASTER]
    return lab_reading(name, GEOMETRIES, lab)


def _files(folder: Path) -> dict[str, Path]:
    """The master as CxF3, the trials as CGATS, MA-T12-style workbook and CSV template, and a bad file."""
    out = {"master": folder / "master.cxf"}
    write_measurement_file([_sample("master", (0.0, 0.0, 0.0))], out["master"])
    for (name, off), suffix in zip(TRIALS.items(), ("cgats", "xlsx", "csv"), strict=True):
        out[name] = folder / f"{name.replace(' ', '')}.{suffix}"
        write_measurement_file([_sample(name, off)], out[name])
    out["bad"] = folder / "broken.cgats"
    out["bad"].write_text("CGATS.17\nBEGIN_DATA_FORMAT\nSAMPLE_ID LAB_L\nEND_DATA_FORMAT\n", encoding="utf-8")
    return out


def _stored(url: str) -> list[tuple[int, str, str, str, list]]:
    engine = make_engine(url)
    try:
        with engine.connect() as conn:
            rows = conn.execute(
                select(Measurement.id, Panel.job, Panel.part, Panel.notes, Measurement.lab)
                .join(Panel, Panel.id == Measurement.panel_id)
                .order_by(Measurement.id)
            ).all()
    finally:
        engine.dispose()
    return [tuple(r) for r in rows]  # type: ignore[misc]


def _screen(qtbot, tmp_path: Path) -> tuple[QcScreen, str]:
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    screen = QcScreen(QcModel(LocalQc(url)), sink=LocalSink(url, tmp_path / "outbox.sqlite3"))
    qtbot.addWidget(screen)
    screen.resize(1100, 700)
    screen.show()
    return screen, url


def _type(edit, text: str) -> None:
    edit.setFocus()
    QTest.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClicks(edit, text)


def _drop(widget, paths: list[Path]) -> bool:
    """Drag *paths* over *widget* and drop them, as a file manager does; whether the drag was accepted."""
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(p)) for p in paths])
    at = QPointF(widget.rect().center())
    action = Qt.DropAction.CopyAction
    enter = QDragEnterEvent(
        at.toPoint(), action, mime, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier
    )
    QApplication.sendEvent(widget, enter)
    if not enter.isAccepted():
        return False
    drop = QDropEvent(at, action, mime, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
    QApplication.sendEvent(widget, drop)
    return drop.isAccepted()


def _column(screen: QcScreen, name: str) -> list[str]:
    j = COLUMNS.index(name)
    return [item_at(screen.table, i, j).text() for i in range(screen.table.rowCount())]


def test_import_choose_the_standard_judge_and_open_a_row(qtbot, tmp_path, monkeypatch):
    files = _files(tmp_path)
    screen, url = _screen(qtbot, tmp_path)
    _type(screen.import_job, "J-300")
    screen.import_part.setCurrentIndex(screen.import_part.findText("door"))
    # the button: the master and two trials, plus a broken file that is named and stores nothing
    picked = [files["master"], files["trial 1"], files["bad"], files["trial 2"]]
    monkeypatch.setattr(
        QFileDialog, "getOpenFileNames", staticmethod(lambda *a, **k: ([str(p) for p in picked], ""))
    )
    QTest.mouseClick(screen.import_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: len(screen.imports) == 4 and screen.import_btn.isEnabled(), timeout=30000)
    lines = screen.import_result.text().splitlines()
    assert lines[0] == "imported 3 of 4 files: 3 readings stored; not imported: broken.cgats"
    assert lines[1] == "master.cxf (cxf): 1 samples, 1 readings: 1 stored"
    assert lines[3].startswith("broken.cgats: NOT IMPORTED — ") and ": expected" in lines[3], lines[3]
    # a file dropped on the tab; a file of no known kind is not taken
    other = tmp_path / "notes.docx"
    other.write_bytes(b"not a measurement")
    assert not _drop(screen, [other])
    assert _drop(screen, [files["trial 3"], other])
    qtbot.waitUntil(lambda: len(screen.imports) == 1 and screen.import_btn.isEnabled(), timeout=30000)
    assert screen.imports[0].statuses == ("stored",)
    assert screen.import_result.text().splitlines()[-1] == "not measurement files (skipped): notes.docx"
    # the database holds each sample once, on job J-300 / door, with the Lab written into its file
    rows = _stored(url)
    assert [(r[1], r[2], r[3]) for r in rows] == [
        ("J-300", "door", f"sample: {n}") for n in ("master", "trial 1", "trial 2", "trial 3")
    ]
    offsets = [(0.0, 0.0, 0.0), *TRIALS.values()]
    for r, off in zip(rows, offsets, strict=True):
        np.testing.assert_allclose(r[4], np.asarray(MASTER) + off, atol=1e-3)
    # importing the same file again stores nothing new
    assert _drop(screen, [files["trial 3"]])
    assert screen.task is not None
    qtbot.waitUntil(lambda: screen.import_btn.isEnabled() and screen.task.isFinished(), timeout=30000)
    assert screen.imports[0].statuses == ("duplicate",) and len(_stored(url)) == 4

    # the job is listed; no standard yet: Judge lists the part unjudged, the picker offers its readings
    assert screen.job.currentText() == "J-300"
    screen.formula.setCurrentIndex(screen.formula.findText("cie2000"))
    QTest.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
    screen.part.setCurrentIndex(screen.part.findText("door"))
    assert "no standard set" in screen.standard.text() and screen.table.rowCount() == 0
    ids = [r[0] for r in rows]
    assert [screen.standard_pick.itemData(i) for i in range(screen.standard_pick.count())] == ids
    screen.standard_pick.setCurrentIndex(0)  # the master
    QTest.mouseClick(screen.set_standard_btn, Qt.MouseButton.LeftButton)
    assert screen.status.text().startswith(f"measurement {ids[0]} is now the standard of door")
    assert f"standard: measurement {ids[0]}" in screen.standard.text()
    # every trial judged against the master: ΔE00 at each geometry as colour-science computes it
    master = np.asarray(MASTER)
    expected = [
        float(colour.delta_E(master[g], master[g] + off, method="CIE 2000"))
        for off in TRIALS.values()
        for g in range(len(GEOMETRIES))
    ]
    assert _column(screen, "sample") == [str(i) for i in ids[1:] for _ in GEOMETRIES]
    assert [float(v) for v in _column(screen, "ΔE")] == pytest.approx(expected, abs=0.006)
    # a row picks the standard; another trial becomes the standard and the job is judged again
    row = 2 * len(GEOMETRIES)  # trial 3
    QTest.mouseClick(
        screen.table.viewport(),
        Qt.MouseButton.LeftButton,
        pos=screen.table.visualItemRect(item_at(screen.table, row, 0)).center(),
    )
    assert screen.standard_pick.currentData() == ids[3]
    QTest.mouseClick(screen.set_standard_btn, Qt.MouseButton.LeftButton)
    assert f"standard: measurement {ids[3]}" in screen.standard.text()
    assert sorted(set(_column(screen, "sample"))) == sorted(str(i) for i in ids[:3])
    d0 = float(colour.delta_E(master[0] + TRIALS["trial 3"], master[0], method="CIE 2000"))
    assert float(_column(screen, "ΔE")[0]) == pytest.approx(d0, abs=0.006)
    # a job-history row opened: that job's verdicts, that measurement's rows selected
    screen.job.clear()
    screen.open_job("J-300", "door", ids[1])
    assert screen.job.currentText() == "J-300" and screen.part.currentText() == "door"
    assert cell_of_selected(screen) == str(ids[1])
    screen.open_job("J-300", "door", ids[3])  # the standard's own row: said, not selected
    assert screen.status.text().endswith(f"measurement {ids[3]} is the standard of door")
    screen.open_job("J-999", "door", 1)
    assert screen.status.text() == "error: job: expected a stored job, got 'J-999'"
    screen.close()


def cell_of_selected(screen: QcScreen) -> str:
    rows = {i.row() for i in screen.table.selectedItems()}
    assert len(rows) == 1
    return item_at(screen.table, rows.pop(), 0).text()


def test_an_import_without_a_job_names_the_field(qtbot, tmp_path, monkeypatch):
    files = _files(tmp_path)
    screen, _url = _screen(qtbot, tmp_path)
    monkeypatch.setattr(
        QFileDialog, "getOpenFileNames", staticmethod(lambda *a, **k: ([str(files["master"])], ""))
    )
    QTest.mouseClick(screen.import_btn, Qt.MouseButton.LeftButton)
    assert screen.import_result.text().startswith("error: import job: expected a job name")
    assert screen.task is None and screen.imports == []
    screen.close()


@pytest.mark.slow  # the whole main window, its 3D view included
def test_the_window_imports_from_the_file_menu_and_drops_and_opens_history_rows(qtbot, tmp_path, monkeypatch):
    from ui.app import MainWindow

    files = _files(tmp_path)
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    win = MainWindow(sink=LocalSink(url, tmp_path / "outbox.sqlite3"), ask_on_close=False)
    qtbot.addWidget(win)
    win.resize(1280, 800)
    win.show()
    qtbot.waitExposed(win)
    qc = win.qc_screen.content()
    _type(qc.import_job, "J-400")
    monkeypatch.setattr(
        QFileDialog, "getOpenFileNames", staticmethod(lambda *a, **k: ([str(files["master"])], ""))
    )
    win.tabs.setCurrentIndex(0)
    win.file_actions["Import measurement files"].trigger()
    assert win.tabs.currentWidget() is win.qc_screen
    qtbot.waitUntil(lambda: len(qc.imports) == 1 and qc.import_btn.isEnabled(), timeout=30000)
    win.tabs.setCurrentIndex(0)
    assert _drop(win, [files["trial 1"]])  # dropped anywhere on the window
    assert win.tabs.currentWidget() is win.qc_screen
    qtbot.waitUntil(lambda: qc.imports[0].file == "trial1.cgats" and qc.import_btn.isEnabled(), timeout=30000)
    ids = [r[0] for r in _stored(url)]
    assert len(ids) == 2
    # the technician's job history in the Instruments tab: a double click opens the job in the QC tab
    win.tabs.setCurrentWidget(win.screens["Instruments"])
    inst = screen_of(win, "Instruments", InstrumentsScreen)
    _type(inst.job, "J-400")
    QTest.mouseClick(inst.history_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: inst.idle and inst.history.count() == 2, timeout=30000)
    item = inst.history.item(0)  # newest first: trial 1
    at = inst.history.visualItemRect(item).center()
    QTest.mouseClick(inst.history.viewport(), Qt.MouseButton.LeftButton, pos=at)
    QTest.mouseDClick(inst.history.viewport(), Qt.MouseButton.LeftButton, pos=at)
    assert win.tabs.currentWidget() is win.qc_screen
    assert qc.job.currentText() == "J-400" and qc.part.currentText() == "test_panel"
    assert "no standard set" in qc.standard.text()
    assert [qc.standard_pick.itemData(i) for i in range(qc.standard_pick.count())] == ids
    win.view_panel.view.wait_idle()
    win.close()


def test_import_and_set_the_standard_through_the_service(qtbot, tmp_path, monkeypatch):
    from station.api.security import Role
    from tests.api.conftest import make_api
    from ui.models.measure_db import ServiceSink
    from ui.models.qc import ServiceQc
    from ui.models.service import ServiceClient

    files = _files(tmp_path)
    url = f"sqlite:///{tmp_path / 'station.sqlite3'}"
    gen = make_api(url, tmp_path)
    api = next(gen)
    try:
        service = ServiceClient("http://testserver", api.tokens[Role.ADMIN], client=api.http)
        sink = ServiceSink(service, tmp_path / "service-outbox.sqlite3")
        screen = QcScreen(QcModel(ServiceQc(service)), sink=sink)
        qtbot.addWidget(screen)
        screen.show()
        _type(screen.import_job, "J-500")
        picked = [str(files["master"]), str(files["trial 2"])]
        monkeypatch.setattr(QFileDialog, "getOpenFileNames", staticmethod(lambda *a, **k: (picked, "")))
        QTest.mouseClick(screen.import_btn, Qt.MouseButton.LeftButton)
        qtbot.waitUntil(lambda: len(screen.imports) == 2 and screen.import_btn.isEnabled(), timeout=30000)
        assert [r.statuses for r in screen.imports] == [("stored",), ("stored",)], screen.import_result.text()
        ids = [r[0] for r in _stored(url)]
        assert screen.job.currentText() == "J-500"
        screen.formula.setCurrentIndex(screen.formula.findText("cie76"))
        QTest.mouseClick(screen.judge_btn, Qt.MouseButton.LeftButton)
        screen.part.setCurrentIndex(screen.part.findText("test_panel"))
        assert [screen.standard_pick.itemData(i) for i in range(screen.standard_pick.count())] == ids
        assert screen.standard_pick.currentIndex() == -1  # nothing chosen yet: the button refuses
        QTest.mouseClick(screen.set_standard_btn, Qt.MouseButton.LeftButton)
        assert screen.status.text().startswith("error: standard:"), screen.status.text()
        screen.standard_pick.setCurrentIndex(0)  # the first: the master
        QTest.mouseClick(screen.set_standard_btn, Qt.MouseButton.LeftButton)
        assert f"standard: measurement {ids[0]}" in screen.standard.text(), screen.status.text()
        # judged again in the judged formula (CIE76): ΔE*ab of trial 2 is |offset| at every geometry
        de = math.sqrt(sum(v * v for v in TRIALS["trial 2"]))
        assert _column(screen, "ΔE") == [f"{de:.2f}"] * len(GEOMETRIES)
        screen.close()
        sink.close()
    finally:
        gen.close()
