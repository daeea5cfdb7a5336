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
