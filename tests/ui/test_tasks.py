"""Task threads pause Python's cyclic collector while they run and restore it after the last one."""

from __future__ import annotations

import gc
import threading

from ui.widgets.tasks import TaskThread, gc_pause


def test_collector_is_off_while_tasks_run_and_back_on_after_the_last(qtbot) -> None:
    assert gc.isenabled()
    release = threading.Event()
    seen: list[bool] = []

    def work(_progress) -> str:
        seen.append(gc.isenabled())  # read inside the worker, while the task runs
        release.wait(5)
        return "done"

    first, second = TaskThread(work), TaskThread(work)
    first.start()
    second.start()
    assert not gc.isenabled() and gc_pause().active == 2
    with qtbot.waitSignals([first.finished, second.finished], timeout=10_000):
        release.set()
    qtbot.waitUntil(lambda: gc_pause().active == 0, timeout=5_000)
    assert seen == [False, False]
    assert gc.isenabled()


def test_a_failing_task_restores_the_collector_too(qtbot) -> None:
    def boom(_progress) -> None:
        raise ValueError("no")

    task = TaskThread(boom)
    with qtbot.waitSignal(task.failed, timeout=10_000) as blocker:
        task.start()
    assert blocker.args == ["ValueError: no"]
    qtbot.waitUntil(gc.isenabled, timeout=5_000)


def test_a_collector_switched_off_by_the_caller_stays_off(qtbot) -> None:
    gc.disable()
    try:
        task = TaskThread(lambda _p: None)
        with qtbot.waitSignal(task.finished, timeout=10_000):
            task.start()
        qtbot.waitUntil(lambda: gc_pause().active == 0, timeout=5_000)
        assert not gc.isenabled()
    finally:
        gc.enable()


def _press_cancel_when_offered(qtbot, progress) -> float:
    """Wait for the Cancel button as the user would see it, click it; seconds the task had run."""
    from PySide6.QtCore import Qt
    from PySide6.QtTest import QTest

    qtbot.waitUntil(progress.cancel_btn.isVisible, timeout=10_000)
    ran = progress.running_ms / 1000
    QTest.mouseClick(progress.cancel_btn, Qt.MouseButton.LeftButton)
    return ran


def test_progress_shows_after_half_a_second_and_cancel_after_two(qtbot) -> None:
    from ui.widgets.tasks import CANCEL_AFTER_MS, SHOW_AFTER_MS, TaskProgress

    progress = TaskProgress()
    qtbot.addWidget(progress)
    steps_done: list[int] = []
    ended = threading.Event()  # set when the test ends, so the task never outlives it

    def work(report) -> str:
        i = 0
        while not ended.wait(0.05):  # a step of work, until Cancel (the next report raises)
            report(min(i, 199), f"step {i}")
            steps_done.append(i)
            i += 1
        return "done"

    task = TaskThread(work)
    outcome: list[str] = []
    task.succeeded.connect(lambda _r: outcome.append("succeeded"))
    task.cancelled.connect(lambda: outcome.append("cancelled"))
    progress.watch(task, "counting", 200)
    task.start()
    try:
        assert not progress.isVisible()
        qtbot.waitUntil(progress.isVisible, timeout=5_000)
        assert progress.running_ms >= SHOW_AFTER_MS and not progress.cancel_btn.isVisible()
        ran = _press_cancel_when_offered(qtbot, progress)
        assert ran >= CANCEL_AFTER_MS / 1000
        qtbot.waitUntil(task.isFinished, timeout=10_000)
        qtbot.waitUntil(lambda: outcome == ["cancelled"], timeout=5_000)
    finally:
        ended.set()
        task.wait(10_000)
    assert steps_done
    # the bar hides on the thread's finished signal, delivered through the event loop after the outcome
    qtbot.waitUntil(lambda: not progress.isVisible(), timeout=5_000)


def test_a_pure_task_cancelled_without_progress_drops_its_result(qtbot) -> None:
    release = threading.Event()
    task = TaskThread(lambda _r: release.wait(5) and "result", pure=True)
    outcome: list[object] = []
    task.succeeded.connect(outcome.append)
    task.cancelled.connect(lambda: outcome.append("cancelled"))
    task.start()
    task.cancel()
    with qtbot.waitSignal(task.finished, timeout=10_000):
        release.set()
    qtbot.waitUntil(lambda: outcome == ["cancelled"], timeout=5_000)


def test_the_views_workers_pause_the_collector_too(qtbot) -> None:
    """A collection inside a view's worker destroyed a closed GL view there and Qt aborted the process
    ("Cannot make QOpenGLContext current in a different thread"): the basis and scene workers run with
    the collector off, like the tasks."""
    from ui.widgets.tasks import GcPausingThread
    from ui.widgets.tweaker_screen import SceneWorker
    from ui.widgets.view_logic import BasisWorker

    assert issubclass(BasisWorker, GcPausingThread) and issubclass(SceneWorker, GcPausingThread)
    seen: list[bool] = []

    class Probe(BasisWorker):
        def run(self) -> None:
            seen.append(gc.isenabled())

    from ui.models.view import ViewSettings

    worker = Probe(ViewSettings(), 16, 16)
    with qtbot.waitSignal(worker.finished, timeout=10_000):
        worker.start()
    qtbot.waitUntil(lambda: gc_pause().active == 0, timeout=5_000)
    assert seen == [False]
    assert gc.isenabled()


def test_a_gl_views_frame_runs_with_the_collector_paused(qtbot, monkeypatch) -> None:
    """A collection inside a frame's GL work destroyed a closed view's Qt GL objects there, which made their
    own context current, and the frame's next texture failed ("cannot create texture", then a segfault):
    the frame is drawn with the collector paused, and it is back on after."""
    from ui.models.view import ViewModel
    from ui.widgets.gl_render_view import GLRenderView
    from ui.widgets.tasks import collector_paused

    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled()
    seen: list[bool] = []
    monkeypatch.setattr(GLRenderView, "_paint_gl", lambda self, target=None: seen.append(gc.isenabled()))
    view = GLRenderView(ViewModel())
    qtbot.addWidget(view)
    view.resize(64, 64)
    view.show()
    qtbot.waitUntil(lambda: bool(seen), timeout=10_000)
    assert not any(seen)
    qtbot.waitUntil(gc.isenabled, timeout=5_000)
