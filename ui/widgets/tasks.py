"""Blocking core calls off the GUI thread: one QThread per task, joined on close.

While any task thread runs, Python's cyclic garbage collector is paused and re-enabled when the last
one finishes (on the GUI thread). The viewer's test runs crashed the process intermittently (SIGSEGV)
when the GUI thread ran a collection while a worker was inside SQLAlchemy's session set-up (a scan
storing its reading, or a retry draining the outbox); reference counting still frees everything
acyclic meanwhile, and tasks last seconds, so the pause costs nothing a user sees. The root cause in
the Qt / SQLAlchemy extension modules is not identified.
"""

from __future__ import annotations

import gc
from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QCoreApplication, QThread, Signal


class GcPause:
    """Counts running task threads; the collector is off while the count is above zero."""

    def __init__(self) -> None:
        self.active = 0
        self._was_enabled = True

    def enter(self) -> None:
        """A task starts (GUI thread)."""
        if self.active == 0:
            self._was_enabled = gc.isenabled()
            gc.disable()
        self.active += 1

    def leave(self) -> None:
        """A task ended (GUI thread); the last one re-enables the collector if it was on."""
        self.active = max(0, self.active - 1)
        if self.active == 0 and self._was_enabled:
            gc.enable()


def gc_pause() -> GcPause:
    """The application's :class:`GcPause` (one per QCoreApplication, created on first use)."""
    app = QCoreApplication.instance()
    pause = getattr(app, "_cacad_gc_pause", None)
    if pause is None:
        pause = GcPause()
        if app is not None:
            app._cacad_gc_pause = pause  # type: ignore[attr-defined]  # one per application object
    return pause


class TaskThread(QThread):
    """Runs ``fn(progress)`` in a thread; ``succeeded(result)`` or ``failed(message)`` afterwards.

    *fn* receives a ``progress(step, text)`` callable that emits the ``progress`` signal (queued to the
    GUI thread). Any exception becomes ``failed`` with its message: errors are shown, never swallowed.
    """

    progress = Signal(int, str)
    succeeded = Signal(object)
    failed = Signal(str)

    def __init__(self, fn: Callable[[Callable[[int, str], None]], Any], parent=None) -> None:
        super().__init__(parent)
        self._fn = fn
        self._paused: GcPause | None = None
        self.finished.connect(self._resume_gc)

    def start(self, *args: Any) -> None:
        """Start the thread (GUI thread), pausing the cyclic collector until it finishes."""
        if self._paused is None:
            self._paused = gc_pause()
            self._paused.enter()
        super().start(*args)

    def _resume_gc(self) -> None:
        if self._paused is not None:
            self._paused.leave()
            self._paused = None

    def run(self) -> None:
        """Run the task."""
        try:
            result = self._fn(lambda step, text: self.progress.emit(step, text))
        except Exception as exc:  # shown to the user verbatim
            self.failed.emit(f"{type(exc).__name__}: {exc}")
            return
        self.succeeded.emit(result)
