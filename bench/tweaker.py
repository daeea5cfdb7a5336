"""Tweaker tab: click to the object on screen (ui/widgets/tweaker_screen.py).

``python -m bench.tweaker`` opens the main window at 1280 × 800 (offscreen), waits for the Design view's
first frame, clicks the Tweaker tab and times the first drawn object (the 160-pixel preview), then the
full-size scene. Baseline in the same run: the main scene computed at the canvas size alone (what the
tab waited for before the preview), with the environment prefilter already in memory. Bar: ready ≤ 1 s.
"""

from __future__ import annotations

import os
import statistics
import time

#: Runs (each a fresh window).
RUNS = 3
#: Window size, pixels: the smallest display the viewer is laid out for.
DISPLAY = (1280, 800)
BAR_READY_S = 1.0


def _spin(pred, timeout_s: float) -> float:
    """Process Qt events until *pred* holds; returns the time it took (seconds)."""
    from PySide6.QtCore import QCoreApplication

    start = time.perf_counter()
    while not pred():
        if time.perf_counter() - start > timeout_s:
            raise TimeoutError(f"not ready within {timeout_s} s")
        QCoreApplication.processEvents()
        time.sleep(0.002)
    return time.perf_counter() - start


def measure_once() -> tuple[float, float, tuple[int, int]]:
    """(click → preview drawn, click → full-size scene, full scene size) of one fresh window."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    from ui.app import MainWindow
    from ui.widgets.tweaker_screen import TweakerScreen

    win = MainWindow(ask_on_close=False)
    win.resize(*DISPLAY)
    win.show()
    view = win.view_panel.view
    _spin(lambda: view.frames >= 1, 120)
    bar = win.tabs.tabBar()
    start = time.perf_counter()
    QTest.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(1).center())
    screen = win.screens["Tweaker"].content()  # type: ignore[attr-defined]
    assert isinstance(screen, TweakerScreen)
    canvas = screen.canvas
    _spin(lambda: canvas.scenes_shown >= 1, 120)
    ready = time.perf_counter() - start
    _spin(lambda: canvas.zoom <= 1.01, 300)
    full = time.perf_counter() - start
    size = canvas.scene.shape[1], canvas.scene.shape[0]
    canvas.wait_idle()
    view.wait_idle()
    win.close()
    win.deleteLater()
    return ready, full, size


def main() -> None:
    from bench._report import Case, write_section

    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PySide6.QtWidgets import QApplication

    from ui.models.tweaker import main_scene
    from ui.models.view import ViewModel

    app = QApplication.instance() or QApplication([])
    runs = [measure_once() for _ in range(RUNS)]
    ready = [r[0] for r in runs]
    full = [r[1] for r in runs]
    w, h = runs[-1][2]
    settings = ViewModel().settings
    base = []
    for _ in range(RUNS):
        t = time.perf_counter()
        main_scene(settings, w, h)
        base.append(time.perf_counter() - t)
    load = os.getloadavg()[0]
    cases = [
        Case(
            "click Tweaker tab -> object drawn, median",
            f"{w}x{h}",
            statistics.median(ready),
            "s",
            f"bar <= {BAR_READY_S:g} s (the preview)",
        ),
        Case("click Tweaker tab -> object drawn, worst", f"{w}x{h}", max(ready), "s"),
        Case(
            "click Tweaker tab -> full-size scene, median",
            f"{w}x{h}",
            statistics.median(full),
            "s",
            "computed off the GUI thread while the preview is usable",
        ),
        Case(
            "main scene at canvas size alone (baseline)",
            f"{w}x{h}",
            statistics.median(base),
            "s",
            "what the tab waited for before the preview (warm prefilter)",
        ),
    ]
    write_section(
        "tweaker",
        "Viewer: Tweaker tab ready (ui/widgets/tweaker_screen.py)",
        cases,
        f"{QApplication.platformName()} platform, window {DISPLAY[0]}x{DISPLAY[1]}, {RUNS} runs. Machine "
        f"shared with other jobs: load average {load:.1f} on {os.cpu_count()} CPUs at the end.",
    )
    del app


if __name__ == "__main__":
    from bench._report import bench_cli

    bench_cli(__doc__, "tweaker")
    main()
