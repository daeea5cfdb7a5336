"""Blocking core calls off the GUI thread: one QThread per task, joined on close, and the progress
indicator every screen shows for it (:class:`TaskProgress`: shown once a task has run 0.5 s, with a
Cancel button once it has run 2 s).

Cancelling is cooperative: :meth:`TaskThread.cancel` sets a flag; the task's next ``progress`` call
raises :class:`Cancelled` and the task emits ``cancelled`` instead of ``succeeded`` (nothing is shown).
A task that reports no more progress runs to its end and its result is shown: a scan is not
cancellable once its reading is being stored, so a stored reading is never hidden.

While any worker thread runs (a task, or a view's basis or scene worker: :class:`GcPausingThread`),
Python's cyclic garbage collector is paused and re-enabled when the last one finishes (on the GUI
thread). A collection runs in whichever thread happens to allocate, and it destroys the Qt objects of the
cycles it frees there: a closed GL view collected inside a basis worker called
``QOpenGLContext::makeCurrent`` from that worker and Qt aborted the process ("Cannot make QOpenGLContext
current in a different thread"; the orbit benchmark, one view closed and the next one's ground
occlusion being compiled). For the same reason a GL view draws its frames with the collector paused
(:func:`collector_paused`): a collection in the GUI thread inside a frame destroyed a closed view there,
whose destructor made its own context current, and the frame's next texture failed ("cannot create
texture", then a segfault). The viewer's test runs also crashed intermittently (SIGSEGV) when the GUI
thread ran a collection while a worker was inside SQLAlchemy's session set-up. Reference counting still
frees everything acyclic meanwhile, and workers last seconds, so the pause costs nothing a user sees.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from PySide6.QtCore import QCoreApplication, QElapsedTimer, QThread, QTimer, Signal
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QPushButton, QWidget

SHOW_AFTER_MS = 500
"""A task that runs longer than this shows the progress indicator."""
CANCEL_AFTER_MS = 2000
"""... and offers Cancel once it has run this long."""


class Cancelled(Exception):
    """Raised in the worker by ``progress`` once the user cancelled the task."""


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


@contextmanager
def collector_paused() -> Iterator[None]:
    """The cyclic collector paused for the block (GUI thread), counted with the worker threads' pause: a
    view's GL work runs with it, so no collection destroys another view's Qt GL objects in the middle of it
    (their destructors make their own context current, and the view's next GL call then fails)."""
    pause = gc_pause()
    pause.enter()
    try:
        yield
    finally:
        pause.leave()


def gc_pause() -> GcPause:
    """The application's :class:`GcPause` (one per QCoreApplication, created on first use)."""
    app = QCoreApplication.instance()
    pause = getattr(app, "_cacad_gc_pause", None)
    if pause is None:
        pause = GcPause()
        if app is not None:
            app._cacad_gc_pause = pause  # type: ignore[attr-defined]  # one per application object
    return pause


class GcPausingThread(QThread):
    """A QThread that pauses the cyclic collector (:func:`gc_pause`) from :meth:`start` until it finishes
    (module docstring): no collection, and so no Qt destructor, runs inside the worker."""

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
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


class TaskThread(GcPausingThread):
    """Runs ``fn(progress)`` in a thread; ``succeeded(result)`` or ``failed(message)`` afterwards.

    *fn* receives a ``progress(step, text)`` callable that emits the ``progress`` signal (queued to the
    GUI thread). Any exception becomes ``failed`` with its message: errors are shown, never swallowed.
    """

    progress = Signal(int, str)
    succeeded = Signal(object)
    failed = Signal(str)
    cancelled = Signal()

    def __init__(
        self, fn: Callable[[Callable[[int, str], None]], Any], parent=None, pure: bool = False
    ) -> None:
        """*pure*: *fn* only computes (changes nothing outside): a cancelled run's result is dropped
        even when it reports no progress, so Cancel takes effect at once for the user."""
        super().__init__(parent)
        self._fn = fn
        self.pure = pure
        self._cancel = False
        self._sent = False

    def cancel(self) -> None:
        """Ask the task to stop: its next progress report raises :class:`Cancelled`; its result is dropped."""
        self._cancel = True

    @property
    def cancel_requested(self) -> bool:
        """Whether :meth:`cancel` was called."""
        return self._cancel

    @property
    def result_sent(self) -> bool:
        """Whether the task has sent its outcome (``succeeded``, ``failed`` or ``cancelled``): it is then only
        returning, and ``finished`` follows, queued behind the outcome."""
        return self._sent

    def _report(self, step: int, text: str) -> None:
        if self._cancel:
            raise Cancelled
        self.progress.emit(step, text)

    def run(self) -> None:
        """Run the task."""
        try:
            result = self._fn(self._report)
        except Cancelled:
            self._sent = True
            self.cancelled.emit()
            return
        except Exception as exc:  # shown to the user verbatim
            self._sent = True
            self.failed.emit(f"{type(exc).__name__}: {exc}")
            return
        self._sent = True
        if self._cancel and self.pure:
            self.cancelled.emit()
        else:
            self.succeeded.emit(result)  # a task with effects: Cancel came after its last step


class TaskProgress(QWidget):
    """Busy or step bar, what the task is doing, how long it has run, and Cancel (after 2 s).

    Hidden until the watched task has run :data:`SHOW_AFTER_MS`; hidden again when it ends. *steps* 0
    shows a busy bar (a task of unknown length), else steps done of *steps*."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.bar = QProgressBar()
        self.text = QLabel()
        self.cancel_btn = QPushButton("Cancel")
        self.cancel_btn.setToolTip("stop the running task; its result is not shown")
        lay = QHBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.bar, 1)
        lay.addWidget(self.text, 2)
        lay.addWidget(self.cancel_btn)
        self.task: TaskThread | None = None
        self.label = ""
        self.cancellable = True
        self._clock = QElapsedTimer()
        self._tick = QTimer(self)
        self._tick.setInterval(100)
        self._tick.timeout.connect(self._update)
        self.cancel_btn.clicked.connect(self._on_cancel)
        self.hide()

    def watch(self, task: TaskThread, label: str, steps: int = 0, cancellable: bool = True) -> None:
        """Follow *task* (call before ``task.start()``); *cancellable* False: no Cancel button (a task
        that cannot stop part-way, e.g. opening a device)."""
        self.task = task
        self.label = label
        self.cancellable = cancellable
        self.bar.setRange(0, steps)
        self.bar.setValue(0)
        self.text.setText(label)
        self.cancel_btn.setEnabled(True)
        self.cancel_btn.hide()
        task.progress.connect(self._on_progress)
        task.finished.connect(lambda: self._on_finished(task))
        self._clock.start()
        self._tick.start()

    @property
    def running_ms(self) -> int:
        """Milliseconds the watched task has run (0 when none runs)."""
        return int(self._clock.elapsed()) if self._tick.isActive() else 0

    def _on_progress(self, step: int, text: str) -> None:
        if self.bar.maximum() > 0:
            self.bar.setValue(step)
        self.label = text
        self._update()

    def _update(self) -> None:
        ms = self.running_ms
        if ms >= SHOW_AFTER_MS and not self.isVisible():
            self.show()
        if ms >= CANCEL_AFTER_MS and self.cancellable and not self.cancel_btn.isVisible():
            self.cancel_btn.show()
        self.text.setText(f"{self.label} ({ms / 1000:.1f} s)")

    def _on_cancel(self) -> None:
        if self.task is not None:
            self.task.cancel()
            self.cancel_btn.setEnabled(False)
            self.label = "cancelling…"
            self._update()

    def _on_finished(self, task: TaskThread) -> None:
        """*task* ended: stop and hide, unless a newer task is watched since (its own end hides it)."""
        if task is not self.task:
            return
        self._tick.stop()
        self.hide()
        self.task = None
