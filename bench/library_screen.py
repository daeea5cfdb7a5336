"""Library screen benchmark: all thumbnails of a 3000-paint filter, in the viewer, on llvmpipe.

Run: ``.venv/bin/python -m bench.library_screen`` (starts its own Xvfb; Qt on xcb, GL on Mesa llvmpipe).

The main window is sized so that its 3D view is 1024×1024 (the viewer's normal size), then the Library
tab is opened on the full 6000-paint demo library and its "metallics+pearls" hierarchy node is clicked
(3000 paints) the way a user does, right after the screen appears.

* Library screen → all thumbnails: from the click until every one of the 3000 paints is listed with its
  thumbnail (fits in one batch per step of 50, booklet renders, list filled step by step by the GUI
  thread; the first task of the screen, all 6000 paints, is stopped by the click). Also: until the first
  thumbnails are listed, and the GUI thread's longest stall meanwhile (a 5 ms timer's largest gap).
* Baseline in the same run: the same 3000 thumbnails made the way the screen made them before, one
  paint at a time on the GUI thread (``fit_fftg`` per paint, ``booklet``, list item); the GUI thread is
  blocked throughout.
* The fit alone: ``fit_fftg_batch`` over the 3000 paints against the per-paint ``fit_fftg`` loop (a
  sample of 300 paints, scaled), per paint.
* ColorSnap of the current design on the library screen: click → matches listed, and the GUI thread's
  longest stall meanwhile.
"""

from __future__ import annotations

import os
import time

SIZE = 1024
FILTER_NODE = "metallics+pearls"
FIT_SAMPLE = 300


class StallClock:
    """A 5 ms timer on the GUI thread; the largest gap between its ticks is the longest stall."""

    def __init__(self) -> None:
        from PySide6.QtCore import QTimer

        self.timer = QTimer()
        self.timer.setInterval(5)
        self.timer.timeout.connect(self._tick)
        self.last = 0.0
        self.worst = 0.0

    def _tick(self) -> None:
        now = time.perf_counter()
        self.worst = max(self.worst, now - self.last)
        self.last = now

    def start(self) -> None:
        self.last, self.worst = time.perf_counter(), 0.0
        self.timer.start()

    def stop(self) -> float:
        self.timer.stop()
        self._tick()
        return self.worst


def _wait(app, until, timeout_s: float = 900.0) -> None:
    t0 = time.perf_counter()
    while not until():
        app.processEvents()
        time.sleep(0.001)
        if time.perf_counter() - t0 > timeout_s:
            raise TimeoutError("benchmark step did not finish")


def _window(app):
    from ui.app import MainWindow

    win = MainWindow(ask_on_close=False)
    win.resize(1500, 1150)
    win.show()
    view = win.view_panel.view
    for _ in range(4):  # grow the window until the 3D view is SIZE × SIZE
        app.processEvents()
        dw, dh = SIZE - view.width(), SIZE - view.height()
        if dw == 0 and dh == 0:
            break
        win.resize(win.width() + dw, win.height() + dh)
    _wait(app, lambda: view.frames > 0)
    view.wait_idle(120000)
    return win, f"{view.width()}x{view.height()}"


def _node(tree, name: str):
    root = tree.topLevelItem(0)
    return next(root.child(i) for i in range(root.childCount()) if root.child(i).text(0) == name)


def measure_screen(app, win) -> dict[str, float]:
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    win.tabs.setCurrentWidget(win.screens["Library"])
    screen = win.screens["Library"].content()
    app.processEvents()
    node = _node(screen.tree, FILTER_NODE)
    n = int(node.text(1))
    stall = StallClock()
    stall.start()
    t0 = time.perf_counter()
    QTest.mouseClick(
        screen.tree.viewport(), Qt.MouseButton.LeftButton, pos=screen.tree.visualItemRect(node).center()
    )
    _wait(app, lambda: screen.thumbs.count() > 0)
    first = time.perf_counter() - t0
    _wait(app, lambda: screen.idle)
    total = time.perf_counter() - t0
    worst = stall.stop()
    listed = screen.thumbs.count()
    icons = sum(not screen.thumbs.item(i).icon().isNull() for i in range(listed))
    if listed != n or icons != n:
        raise RuntimeError(f"{listed} listed, {icons} with a thumbnail, of {n}")
    # ColorSnap of the current design
    stall.start()
    t0 = time.perf_counter()
    QTest.mouseClick(screen.snap_btn, Qt.MouseButton.LeftButton)
    _wait(app, lambda: screen.idle and screen.matches.count() > 0)
    snap = time.perf_counter() - t0
    snap_stall = stall.stop()
    return {"n": n, "total": total, "first": first, "stall": worst, "snap": snap, "snap_stall": snap_stall}


def measure_baseline(app, rows) -> float:
    """The former way: per paint, on the GUI thread, fit → booklet → list item."""
    import numpy as np
    from PySide6.QtGui import QIcon
    from PySide6.QtWidgets import QListWidget, QListWidgetItem

    from station.design.palette import booklet
    from station.formulate.demo import demo_library
    from station.model import AspecularMeasurements, fit_fftg
    from ui.widgets.common import pixmap_from_array

    lib = demo_library()
    order = np.argsort(lib.angles_deg)
    angles = tuple(float(lib.angles_deg[j]) for j in order)
    lst = QListWidget()
    lst.resize(400, 600)
    lst.show()
    t0 = time.perf_counter()
    for r in rows:
        fit = fit_fftg(AspecularMeasurements(angles, lib.lab[r][order], float(lib.gloss_gu[r])))
        img = booklet(fit.design, 40)
        lst.addItem(QListWidgetItem(QIcon(pixmap_from_array(img)), f"{lib.codes[r]}"))
    app.processEvents()
    total = time.perf_counter() - t0
    lst.close()
    return total


def measure_fit(rows) -> tuple[float, float]:
    """(batch fit per paint (s), per-paint fit_fftg per paint (s)) over *rows*."""
    import numpy as np

    from station.formulate.demo import demo_library
    from station.model import AspecularMeasurements, fit_fftg
    from station.model.fit import fit_fftg_batch

    lib = demo_library()
    order = np.argsort(lib.angles_deg)
    angles = tuple(float(lib.angles_deg[j]) for j in order)
    lab = lib.lab[:, order]
    batch = []
    for _ in range(3):
        t0 = time.perf_counter()
        fit_fftg_batch(angles, lab[rows], lib.gloss_gu[rows])
        batch.append((time.perf_counter() - t0) / len(rows))
    sample = rows[:: max(1, len(rows) // FIT_SAMPLE)]
    t0 = time.perf_counter()
    for r in sample:
        fit_fftg(AspecularMeasurements(angles, lab[r], float(lib.gloss_gu[r])))
    single = (time.perf_counter() - t0) / len(sample)
    return min(batch), single


def main() -> None:
    from bench._report import Case, write_section
    from ui.xvfb import start_xvfb

    xvfb = start_xvfb("2048x1536x24")
    os.environ["QT_QPA_PLATFORM"] = "xcb"
    try:
        import numpy as np
        from PySide6.QtWidgets import QApplication

        from station.formulate.demo import demo_library
        from station.formulate.library import LibraryFilter
        from ui.widgets.render_view import configure_default_format

        configure_default_format()
        app = QApplication([])
        win, view_size = _window(app)
        renderer = getattr(win.view_panel.view, "gl_renderer", "")
        got = measure_screen(app, win)
        win.close()
        app.processEvents()
        lib = demo_library()
        rows = np.flatnonzero(LibraryFilter(set_name=FILTER_NODE).mask(lib))
        if rows.size != got["n"]:
            raise RuntimeError(f"baseline rows {rows.size} != filter {got['n']}")
        base = measure_baseline(app, rows)
        fit_batch, fit_single = measure_fit(rows)
        n = int(got["n"])
        size = f"{n} paints"
        cases = [
            Case(
                "library screen -> all thumbnails (background, batch fit)",
                size,
                got["total"],
                "s",
                f"click on '{FILTER_NODE}' until all {n} are listed; 3D view {view_size}",
            ),
            Case("  first thumbnails listed", "", got["first"], "s", "after the click"),
            Case(
                "  GUI thread longest stall meanwhile",
                "",
                got["stall"] * 1e3,
                "ms",
                "5 ms timer's largest gap",
            ),
            Case(
                "per-paint fit + booklet on the GUI thread (baseline)",
                size,
                base,
                "s",
                "the former way; the GUI thread blocked throughout",
            ),
            Case("  baseline / background batch", "", base / got["total"], "ratio"),
            Case("fit_fftg_batch, per paint", size, fit_batch * 1e3, "ms", "best of 3"),
            Case(
                "fit_fftg one paint at a time, per paint (baseline)",
                f"{FIT_SAMPLE} paints",
                fit_single * 1e3,
                "ms",
                "sample of the same paints",
            ),
            Case("  per-paint / batch", "", fit_single / fit_batch, "ratio", "bar >= 20"),
            Case("ColorSnap on the library screen: click -> matches", "6000 paints", got["snap"], "s"),
            Case("  GUI thread longest stall meanwhile", "", got["snap_stall"] * 1e3, "ms"),
        ]
        app.shutdown()
        load = os.getloadavg()[0]
        write_section(
            "library_screen",
            "Library screen: thumbnails of a 3000-paint filter, ColorSnap (ui/)",
            cases,
            f"Main window with its 3D view at {view_size}, GL renderer: {renderer} under Xvfb (xcb). "
            "Thumbnails are 40² booklet renders (station.design.palette.booklet); after the batch fit "
            "they are most of the time. The per-paint baseline is today's fit_fftg, itself the batch's "
            "one-paint case (no scipy search any more). Machine shared with other jobs: load average "
            f"{load:.1f} on {os.cpu_count()} CPUs at the end.",
        )
    finally:
        xvfb.terminate()
        xvfb.wait(5)


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "library_screen")
    main()
