"""Regenerate the screenshots of every screen (``station viewer screenshots --out docs/screens``).

Runs the real main window on whatever Qt platform is current (under Xvfb/xcb the 3D views are GL on
llvmpipe), puts demo content on each screen — a design edit, the demo mood-board photo with the three
eyedroppers, a ColorSnap of the design in the synthetic demo library, a scan of the MA6 simulator paired with the gloss
meter simulator, a seam QA, its corrected paint formulated — and saves one PNG per screen. Returns the written paths.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from PySide6.QtCore import QCoreApplication, QEvent
from PySide6.QtWidgets import QApplication, QWidget

from ui.demo import demo_photo
from ui.widgets.render_view import GLRenderView, ImageRenderView
from ui.widgets.screens import LazyScreen

if TYPE_CHECKING:
    from station.formulate.library import Library
    from station.model import FaceFlopTravelGloss
    from ui.app import MainWindow
    from ui.widgets.instruments_screen import InstrumentsScreen
    from ui.widgets.qa_screen import QAScreen

Screen = TypeVar("Screen", bound=QWidget)

#: Window size of the screenshots: the smallest display the viewer is laid out for.
SIZE = (1280, 800)


def _settle(win, seconds: float = 0.3) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        QCoreApplication.processEvents()
        time.sleep(0.01)
    for v in (*win.findChildren(GLRenderView), *win.findChildren(ImageRenderView)):
        v.wait_idle()
        v.request_frame()
    QCoreApplication.processEvents()


def _wait(pred, timeout_s: float) -> bool:
    end = time.perf_counter() + timeout_s
    while time.perf_counter() < end:
        QCoreApplication.processEvents()
        if pred():
            return True
        time.sleep(0.02)
    return False


def _screen(win: MainWindow, title: str, kind: type[Screen]) -> Screen:
    """The screen of tab *title* (built now if needed), checked to be a *kind*."""
    page = win.screens[title]
    screen = page.content() if isinstance(page, LazyScreen) else page
    if not isinstance(screen, kind):
        raise TypeError(f"tab {title!r}: expected a {kind.__name__}, got {type(screen).__name__}")
    return screen


def file_menu_shot(win, path: Path) -> Path:
    """The window with its File menu open (the menu is its own window: the screen is grabbed)."""
    bar, menu = win.menuBar(), win.file_menu
    menu.popup(bar.mapToGlobal(bar.actionGeometry(menu.menuAction()).bottomLeft()))
    _settle(win)
    geo = win.frameGeometry()
    win.screen().grabWindow(0, geo.x(), geo.y(), geo.width(), geo.height()).save(str(path))
    menu.hide()
    QCoreApplication.processEvents()
    return path


def answer_calibration(win, inst) -> None:
    """Calibrate as the technician does: OK at each prompt (black trap, white tile, …), each followed by
    its reading, until the last step is read."""
    from PySide6.QtWidgets import QMessageBox

    inst.calibrate()
    while inst.calibration is not None:
        _wait(lambda: inst.calibration is None or (inst.prompt is not None and inst.prompt.isVisible()), 30)
        if inst.prompt is not None:
            inst.prompt.button(QMessageBox.StandardButton.Ok).click()
        QCoreApplication.processEvents()
    _wait(lambda: inst.idle, 60)


def qc_shot(win, inst) -> None:
    """The QC tab on the scanned job: the first scan of the door made its standard in the tab (the standard
    picker), a second scan of the same panel judged against it (pass/warn/fail per geometry, paired gloss)."""
    inst.scan()  # a second reading of the panel: the sample
    _wait(lambda: inst.idle, 60)
    win.tabs.setCurrentWidget(win.screens["QC"])
    qc = win.screens["QC"].content()
    qc.load_jobs()
    qc.job.setCurrentText("J-2026-0113")
    qc.judge()
    qc.part.setCurrentText("door")
    if qc.standard_pick.count():
        qc.standard_pick.setCurrentIndex(0)  # the oldest reading: the first scan
        qc.set_standard()
    qc.import_job.setText("J-2026-0113")
    qc.import_part.setCurrentText("door")


def take_screenshots(out: str | Path, scan: bool = True) -> list[Path]:
    """Write ``design.png``, ``file-menu.png``, ``tweaker.png``, ``moodboard.png``, ``library.png``,
    ``instruments.png``, ``qa.png``, ``qc.png`` (with *scan*), ``formulation.png`` to *out*."""
    from ui.app import MainWindow
    from ui.models.measure_db import LocalSink

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    app = QApplication.instance()
    if app is None:
        raise RuntimeError("create the QApplication before taking screenshots")
    scratch = tempfile.TemporaryDirectory()
    sink = LocalSink(
        f"sqlite:///{Path(scratch.name) / 'station.sqlite3'}", Path(scratch.name) / "outbox.sqlite3"
    )
    win = MainWindow(sink=sink, ask_on_close=False)
    win.resize(*SIZE)
    win.show()
    written: list[Path] = []

    def shot(name: str) -> None:
        _settle(win)
        path = out / f"{name}.png"
        win.grab().save(str(path))
        written.append(path)

    try:
        _design_shots(win, shot)
        file_menu_shot(win, out / "file-menu.png")
        written.append(out / "file-menu.png")
        _tweaker_shot(win, shot)
        _moodboard_shot(win, shot)
        _library_shot(win, shot)
        inst = _instruments_shot(win, shot, scan)
        qa = _qa_shot(win, shot, scan)
        if scan:
            qc_shot(win, inst)
            shot("qc")
            win.tabs.setCurrentWidget(win.screens["QA"])
        _formulation_shot(win, shot, qa)
    finally:
        win.close()
        win.deleteLater()
        # Delete the window now, while the application lives: a window still queued for deletion when
        # the caller shuts Qt down (``station viewer screenshots``) crashed the process in teardown.
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
        QApplication.processEvents()
        QCoreApplication.processEvents()
        scratch.cleanup()
    return written


Shot = Callable[[str], None]


def _design_shots(win: MainWindow, shot: Shot) -> None:
    """The designer with two kept designs (the second bluer and at 70 GU) on the speedshape."""
    d = win.designer
    d.keep("as designed")
    d.move_face(18.0, -44.0)
    d.end_drag()
    d.set_gloss(70.0)
    d.end_drag()
    d.keep("bluer face, 70 GU")
    win.view_panel.shape.setCurrentText("speedshape")
    win.view_panel.model.update(yaw_deg=-15.0, pitch_deg=5.0)
    shot("design")


def _tweaker_shot(win: MainWindow, shot: Shot) -> None:
    """The tweaker with the crosshair at 30° aspecular and the hue turned by 10°."""
    from ui.widgets.tweaker_screen import TweakerScreen

    win.tabs.setCurrentWidget(win.screens["Tweaker"])
    tw = _screen(win, "Tweaker", TweakerScreen).canvas
    _settle(win)
    tw.wait_idle()
    theta = np.where(tw.scene.mask, tw.scene.aspecular_deg, np.inf)
    y, x = np.unravel_index(np.argmin(np.abs(theta - 30.0)), theta.shape)
    tw.press((int(x), int(y)))
    tw.adjust("H", 10.0)
    shot("tweaker")


def _moodboard_shot(win: MainWindow, shot: Shot) -> None:
    """The mood board with the demo photo and the three eyedroppers dropped on it."""
    with tempfile.TemporaryDirectory() as tmp:
        photo = demo_photo(Path(tmp) / "demo-photo.png")
        mb = win.moodboard
        mb.add_image(str(photo), 20.0, 20.0, 2.0)
        win.tabs.setCurrentWidget(win.screens["Mood board"])
        mb.drop("face", 20 + 2 * 70, 20 + 2 * 60)
        mb.drop("flop", 20 + 2 * 125, 20 + 2 * 118)
        mb.drop("gloss", 20 + 2 * 58, 20 + 2 * 52)
        mb.end_drop()
        shot("moodboard")


def _library_shot(win: MainWindow, shot: Shot) -> None:
    """The library after a ColorSnap of the design (thumbnails and the search run in the background)."""
    from ui.widgets.library_screen import LibraryScreen

    win.tabs.setCurrentWidget(win.screens["Library"])
    lib = _screen(win, "Library", LibraryScreen)
    lib.snap()
    _wait(lambda: lib.idle, 300)
    shot("library")


def _instruments_shot(win: MainWindow, shot: Shot, scan: bool) -> InstrumentsScreen:
    """The instruments screen; with *scan*, after a paired MA6 + gloss-meter scan of the door."""
    from ui.widgets.instruments_screen import InstrumentsScreen

    win.tabs.setCurrentWidget(win.screens["Instruments"])
    inst = _screen(win, "Instruments", InstrumentsScreen)
    if scan:
        inst.device.setCurrentText("sim:ma6")
        inst.connect_device()
        _wait(lambda: inst.idle, 60)
        inst.gloss_device.setCurrentText("sim:gloss")
        inst.toggle_gloss()
        _wait(lambda: inst.idle, 60)
        answer_calibration(win, inst)
        inst.job.setText("J-2026-0113")
        inst.part.setCurrentText("door")
        inst.substrate.setText("steel, e-coat")
        inst.notes.setPlainText("front left door, centre")
        inst.scan()
        _wait(lambda: inst.idle, 60)
        inst.job_history()
        _wait(lambda: inst.idle, 60)
    shot("instruments")
    return inst


def _qa_shot(win: MainWindow, shot: Shot, scan: bool) -> QAScreen:
    """A seam QA of the two kept designs at β = 4° (the stored readings loaded with *scan*)."""
    from ui.widgets.qa_screen import QAScreen

    win.tabs.setCurrentWidget(win.screens["QA"])
    qa = _screen(win, "QA", QAScreen)
    if scan:
        qa.load_stored()
    qa.panel_a.setCurrentText("palette: as designed")
    qa.panel_b.setCurrentText("palette: bluer face, 70 GU")
    qa.beta.setValue(4)
    qa.run()
    _wait(lambda: qa.report is not None and (qa.task is None or not qa.task.isRunning()), 120)
    shot("qa")
    return qa


def _library_metallic(library: Library) -> FaceFlopTravelGloss:
    """A design fitted at 15/45/110° to one of *library*'s metallics."""
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.domain import ANGLES_3

    i = int(np.flatnonzero(library.types == "metallic")[3])
    cols = [library.angles_deg.index(a) for a in ANGLES_3]
    lab = library.lab[i][cols]
    fit = fit_fftg(AspecularMeasurements(ANGLES_3, lab, float(library.gloss_gu[i])))
    return fit.design.replace(name=f"{library.codes[i]} as a design")


def _formulation_shot(win: MainWindow, shot: Shot, qa: QAScreen) -> None:
    """The corrected paint of the QA sent on to formulation: ColorSnapped, formulated and run through the
    closed loop."""
    from ui.widgets.formulation_screen import FormulationScreen

    qa.send_btn.click()
    chem = _screen(win, "Formulation", FormulationScreen)
    if chem.library is not None:  # a metallic the colorants reach, so the closed loop shows its tinting
        chem.add_design("library metallic", _library_metallic(chem.library), select=True)
    for step in (chem.run_snap, chem.run_formulate, chem.run_loop):
        step()
        _wait(lambda: chem.idle, 120)
    shot("formulation")
