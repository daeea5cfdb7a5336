"""Chemist's day on the Formulation screen of the main window, on the full 6000-paint demo library, driven
by clicks: open a design file, ColorSnap with a type filter, formulate, see the recipe (mass per batch),
run the closed loop, export; and the QA engineer's corrected paint arriving there with one click.
Every number shown is checked against the same core call made here (``station snap`` / ``formulate``
/ ``export`` call these too)."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6.QtCore import Qt, QTimer
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QApplication, QFileDialog, QLineEdit, QMenu

from station.formulate.demo import demo_library
from station.formulate.formulation import formulate_from_library
from station.formulate.snap import color_snap
from station.model import AspecularMeasurements, FaceFlopTravelGloss, fit_fftg
from station.model.design_io import save_design
from station.model.domain import ANGLES_3
from tests.ui.dialogs import enter_file_name
from tests.ui.screens import item_at, screen_of
from ui.app import MainWindow
from ui.models.measure_db import LocalSink
from ui.widgets.formulation_screen import FormulationScreen
from ui.widgets.qa_screen import QAScreen

pytestmark = [pytest.mark.qt, pytest.mark.slow]


def _library_metallic() -> FaceFlopTravelGloss:
    """A design fitted to one of the demo library's metallics at 15/45/110° (formulable by construction:
    its paint has a recipe in the SYNTHETIC colorants)."""
    lib = demo_library()
    i = int(np.flatnonzero(lib.types == "metallic")[40])
    cols = [lib.angles_deg.index(a) for a in ANGLES_3]
    fit = fit_fftg(AspecularMeasurements(ANGLES_3, lib.lab[i][cols], float(lib.gloss_gu[i])))
    return fit.design.replace(name=f"{lib.codes[i]} as a design")


def _click(qtbot, screen, button) -> None:
    assert button.isEnabled(), button.text()
    QTest.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: screen.idle, timeout=120_000)


def _with_dialog(qtbot, button, path, done) -> None:
    """Click *button*, type *path* into the file dialog it opens and press Enter; wait for *done*()."""

    def fill() -> None:
        dialog = QApplication.activeModalWidget()
        if isinstance(dialog, QFileDialog) and dialog.isVisible():
            name = dialog.findChild(QLineEdit, "fileNameEdit")
            assert name is not None
            enter_file_name(name, path)
        if not done():
            QTimer.singleShot(300, fill)

    QTimer.singleShot(50, fill)
    QTest.mouseClick(button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(done, timeout=60_000)


def _close_discarding(win) -> None:
    """Close the window as the user does after the day's work: the unsaved design is discarded."""
    from PySide6.QtWidgets import QMessageBox

    def answer() -> None:
        box = getattr(win, "unsaved_box", None)
        if box is not None and box.isVisible():
            QTest.mouseClick(box.button(QMessageBox.StandardButton.Discard), Qt.MouseButton.LeftButton)
        elif win.isVisible():
            QTimer.singleShot(100, answer)

    QTimer.singleShot(100, answer)
    win.close()
    assert not win.isVisible()


def _text(table, row: int, col: int) -> str:
    """A cell's text ("" for a cell under a span, which holds no item)."""
    item = table.item(row, col)
    return "" if item is None else item.text()


def _toggle(box) -> None:
    """Tick or untick a check box with the keyboard (focus, space)."""
    box.setFocus()
    QTest.keyClick(box, Qt.Key.Key_Space)


def test_chemist_day(qtbot, tmp_path):
    BLUE_METALLIC = _library_metallic()
    save_design(BLUE_METALLIC, tmp_path / "blue.json")
    win = MainWindow(sink=LocalSink(f"sqlite:///{tmp_path / 's.sqlite3'}", tmp_path / "o.sqlite3"))
    # not qtbot.addWidget: its teardown close would ask about the unsaved design again
    win.resize(1400, 900)
    win.show()
    win.tabs.setCurrentWidget(win.screens["Formulation"])
    screen = screen_of(win, "Formulation", FormulationScreen)
    lib = demo_library()
    assert screen.library is not None and len(screen.library) == len(lib) == 6000
    # open the design file
    _with_dialog(
        qtbot,
        screen.open_btn,
        tmp_path / "blue.json",
        lambda: screen.design.currentText() == "file: blue.json",
    )
    assert screen.picked() == BLUE_METALLIC
    # ColorSnap in the metallics only: untick solid and pearl
    for t in ("solid", "pearl"):
        _toggle(screen.types[t])
    assert screen.chosen_types() == ["metallic"]
    _click(qtbot, screen, screen.snap_btn)
    metallic = lib.subset(lib.types == "metallic")
    expected = color_snap(metallic, BLUE_METALLIC.lab_at(np.array(ANGLES_3)), k=5, method="cie2000")
    shown = [item_at(screen.matches, i, 0).text() for i in range(screen.matches.rowCount())]
    assert shown == [m.code for m in expected.matches]
    assert {item_at(screen.matches, i, 1).text() for i in range(screen.matches.rowCount())} == {"metallic"}
    # formulate: the recipe, per colorant, as mass % and grams for a 500 g batch
    _click(qtbot, screen, screen.formulate_btn)
    result, _snap = formulate_from_library(
        BLUE_METALLIC.lab_at(np.array(ANGLES_3)), metallic, gloss_gu=BLUE_METALLIC.gloss_gu
    )
    screen.batch.setFocus()
    screen.batch.selectAll()
    QTest.keyClicks(screen.batch, "500")
    QTest.keyClick(screen.batch, Qt.Key.Key_Return)
    assert screen.batch.value() == 500.0
    rows = {
        item_at(screen.recipe, i, 0).text(): (
            float(item_at(screen.recipe, i, 1).text()),
            float(item_at(screen.recipe, i, 2).text()),
        )
        for i in range(screen.recipe.rowCount())
    }
    # m_i = c_i · M per colorant, the binder the rest of the batch (thesis-free hand calculation)
    assert set(rows) == {*result.recipe, "binder"}
    for name, frac in result.recipe.items():
        assert rows[name][0] == pytest.approx(100 * frac, abs=0.006)
        assert rows[name][1] == pytest.approx(500.0 * frac, abs=0.06)
    assert rows["binder"][1] == pytest.approx(500.0 * (1 - sum(result.recipe.values())), abs=0.06)
    assert sum(g for _p, g in rows.values()) == pytest.approx(500.0, abs=0.5)
    assert f"mean {result.mean_de:.2f}" in screen.status.text() and "SYNTHETIC" in screen.status.text()
    # the closed loop: steps until within tolerance (or the correction limit), mean ΔE shown per step
    _click(qtbot, screen, screen.loop_btn)
    job = screen.job
    heads = [i for i in range(screen.loop.rowCount()) if _text(screen.loop, i, 0)]
    assert job is not None and len(heads) == len(job.steps) >= 1
    assert [float(item_at(screen.loop, i, 2).text()) for i in heads] == pytest.approx(
        [round(s.mean_de, 2) for s in job.steps], abs=0.006
    )
    state = "converged" if job.status == "converged" else "did not converge"
    assert screen.status.text().startswith(f"Closed loop {state} after {job.corrections} correction")
    # export as thesis XML, with the metallic match
    _with_dialog(qtbot, screen.export_btn, tmp_path / "blue.xml", lambda: screen.exported is not None)
    text = (tmp_path / "blue.xml").read_text()
    assert screen.exported == tmp_path / "blue.xml" and expected.matches[0].code in text
    assert f"match {expected.matches[0].code}" in screen.status.text()
    # QA hands a corrected paint on: one click lands it here, picked
    qa = screen_of(win, "QA", QAScreen)
    win.tabs.setCurrentWidget(win.screens["QA"])
    qa.beta.setValue(3)
    QTest.mouseClick(qa.run_btn, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(
        lambda: qa.report is not None and qa.task is not None and not qa.task.isRunning(), timeout=60_000
    )
    QTest.mouseClick(qa.send_btn, Qt.MouseButton.LeftButton)
    assert win.tabs.currentWidget() is win.screens["Formulation"]
    assert qa.report is not None and qa.report.correction is not None
    assert screen.picked() is qa.report.correction.paint
    assert screen.design.currentText().startswith("sent: ") and screen.matches.rowCount() == 0
    # a filter with no type is refused with the field named, nothing runs
    _toggle(screen.types["metallic"])
    QTest.mouseClick(screen.snap_btn, Qt.MouseButton.LeftButton)
    assert screen.status.text().startswith("error: types") and screen.idle
    _close_discarding(win)


@pytest.mark.parametrize("role", ["qa", "chemist"])
def test_qa_and_chemist_store_the_paint_on_the_service(qtbot, tmp_path, role):
    """Service mode: QA's corrected paint (or the chemist's design) is stored on the service from the
    viewer's Service menu with the user's own token — no administrator needed (was 403)."""
    from tests.api.conftest import make_api
    from ui.models.measure_db import ServiceSink
    from ui.models.service import ServiceClient

    gen = make_api(f"sqlite:///{tmp_path / 'station.sqlite3'}", tmp_path)
    api = next(gen)
    try:
        token = api.tokens[next(r for r in api.tokens if r.value == role)]
        service = ServiceClient("http://testserver", token, client=api.http)
        win = MainWindow(service=service, sink=ServiceSink(service, tmp_path / "outbox.sqlite3"))
        # not qtbot.addWidget: its teardown close would ask about the unsaved design again
        paint = _library_metallic()
        win.document.set_design(paint, "the paint to keep")
        menu = next(a.menu() for a in win.menuBar().actions() if a.text() == "&Service")
        assert isinstance(menu, QMenu)
        save = next(a for a in menu.actions() if a.text() == "Save current design")
        save.trigger()
        assert win.statusBar().currentMessage().startswith("saved as design "), (
            win.statusBar().currentMessage()
        )
        rows = api.client.get("/api/v1/designs", headers=api.auth("chemist")).json()["data"]
        assert len(rows) == 1 and rows[0]["design"]["face"] == pytest.approx(list(paint.face))
        _close_discarding(win)
    finally:
        gen.close()


def test_chemist_day_in_service_mode_uses_the_services_library(qtbot, tmp_path):
    """Service mode against a real ``station serve``: ColorSnap, formulation, the closed loop and the
    export run on the service, against the SERVICE's library. A paint uploaded only to the service (its
    Lab = the design's at every angle, so ΣΔE00 = 0) is the best match and the export's match; picking
    that one stored library searches its single paint; the other matches are the demo library's
    metallics in the core's own ColorSnap order."""
    from station.model.design_io import design_to_dict
    from tests.ui.real_service import paint_csv, station_service
    from ui.models.measure_db import ServiceSink
    from ui.models.service import ServiceClient

    design = _library_metallic()
    save_design(design, tmp_path / "blue.json")
    angles = (15.0, 25.0, 45.0, 75.0, 110.0)
    lab = {a: tuple(float(v) for v in design.lab_at(np.array([a]))[0]) for a in angles}
    lib = demo_library()
    assert "SVC-ONLY-1" not in set(lib.codes)
    with station_service(tmp_path, "chemist") as (base, tokens):
        service = ServiceClient(base, tokens["chemist"], timeout_s=120.0)
        up = service.checked(
            "POST",
            "/library/import",
            params={"name": "service-only"},
            content=paint_csv([("SVC-ONLY-1", "metallic", design.gloss_gu, lab)]),
            headers={"Content-Type": "text/csv"},
        )
        assert up.status_code == 201 and up.json()["paints"] == 1
        win = MainWindow(service=service, sink=ServiceSink(service, tmp_path / "outbox.sqlite3"))
        try:
            win.resize(1400, 900)
            win.show()
            win.tabs.setCurrentWidget(win.screens["Formulation"])
            screen = screen_of(win, "Formulation", FormulationScreen)
            assert screen.remote is not None and screen.library is None  # no local library in use
            offered = [screen.source.itemText(i) for i in range(screen.source.count())]
            assert offered[0] == "every stored library" and "service-only" in offered
            assert "6001 paints in 2 stored libraries" in screen.status.text()
            _with_dialog(
                qtbot,
                screen.open_btn,
                tmp_path / "blue.json",
                lambda: screen.design.currentText() == "file: blue.json",
            )
            for t in ("solid", "pearl"):
                _toggle(screen.types[t])
            _click(qtbot, screen, screen.snap_btn)
            rows = [
                [item_at(screen.matches, i, j).text() for j in range(4)]
                for i in range(screen.matches.rowCount())
            ]
            assert rows[0][0] == "SVC-ONLY-1" and rows[0][3] == "service-only"
            assert float(rows[0][2]) == pytest.approx(0.0, abs=0.01)
            metallic = lib.subset(lib.types == "metallic")
            expected = color_snap(metallic, design.lab_at(np.array(ANGLES_3)), k=4, method="cie2000")
            assert [r[0] for r in rows[1:]] == [m.code for m in expected.matches]
            assert [float(r[2]) for r in rows[1:]] == pytest.approx(
                [round(m.sum_de, 2) for m in expected.matches], abs=0.011
            )
            assert {r[1] for r in rows} == {"metallic"}
            assert "2001 paints" in screen.status.text()  # the demo's 2000 metallics and the upload
            # the one stored library picked with the keyboard: its single paint searched
            screen.source.setFocus()
            QTest.keyClicks(screen.source, "service-only")
            assert screen.source.currentText() == "service-only"
            _click(qtbot, screen, screen.snap_btn)
            assert screen.matches.rowCount() == 1 and item_at(screen.matches, 0, 0).text() == "SVC-ONLY-1"
            assert "service-only (metallic), 1 paints" in screen.status.text()
            # formulating from that library is refused, naming it: its paint carries no recipe
            _click(qtbot, screen, screen.formulate_btn)
            assert screen.formulation is None
            assert "error" in screen.status.text() and "library" in screen.status.text()
            # formulate on the service from every stored library's metallics (the ticked type): its
            # recipe, weighed out per batch as the core does
            screen.source.setCurrentIndex(0)
            assert screen.source.currentText() == "every stored library"
            _click(qtbot, screen, screen.formulate_btn)
            got = service.call(
                "POST",
                "/formulation/formulate",
                json={"design": design_to_dict(design), "types": ["metallic"]},
            )
            assert {m["type"] for m in got["matches"]} == {"metallic"}
            f = screen.formulation
            assert f is not None and f.result.recipe == pytest.approx(got["recipe"], abs=1e-9)
            shown = {
                screen.recipe.item(i, 0).text(): float(screen.recipe.item(i, 2).text())
                for i in range(screen.recipe.rowCount())
            }
            for name, frac in got["recipe"].items():
                assert shown[name] == pytest.approx(screen.batch.value() * frac, abs=0.06)
            assert f"mean {got['mean_de']:.2f}" in screen.status.text()
            # the closed loop on the service: the design and the job stored there; the progress indicator
            # shows while it runs past 0.5 s (SHOW_AFTER_MS), with no Cancel (it cannot stop part-way)
            seen: list[tuple[int, bool, bool, str]] = []
            poll = QTimer()
            poll.timeout.connect(
                lambda: seen.append(
                    (
                        screen.busy.running_ms,
                        screen.busy.isVisible(),
                        screen.busy.cancel_btn.isVisible(),
                        screen.busy.text.text(),
                    )
                )
            )
            poll.start(50)
            _click(qtbot, screen, screen.loop_btn)
            poll.stop()
            # shown only past SHOW_AFTER_MS, then for as long as it runs, never with Cancel; shown for certain
            # a second later (the indicator updates on its own 100 ms tick, which a busy machine delays)
            from ui.widgets.tasks import SHOW_AFTER_MS

            shown = [i for i, s in enumerate(seen) if s[1]]
            assert all(seen[i][0] >= SHOW_AFTER_MS for i in shown)
            assert all(not cancel and "on the service" in text for _ms, vis, cancel, text in seen if vis)
            if shown:
                assert all(vis for ms, vis, *_ in seen[shown[0] :] if ms > 0)
            assert all(vis for ms, vis, *_ in seen if ms >= SHOW_AFTER_MS + 1000)
            job = screen.job
            assert job is not None and screen.loop.rowCount() >= len(job.steps) >= 1
            stored = service.call("GET", f"/recipes/{job.recipe_id}")
            assert stored["id"] == job.recipe_id
            assert f"Stored on the service as job {job.recipe_id}" in screen.status.text()
            # the export's match is the service-only paint
            _with_dialog(qtbot, screen.export_btn, tmp_path / "blue.xml", lambda: screen.exported is not None)
            assert "SVC-ONLY-1" in (tmp_path / "blue.xml").read_text()
            assert "match SVC-ONLY-1" in screen.status.text()
        finally:
            _close_discarding(win)
            service.close()
