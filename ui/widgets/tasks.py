"""Blocking core calls off the GUI thread: one QThread per task, joined on close."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PySide6.QtCore import QThread, Signal


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

    def run(self) -> None:
        """Run the task."""
        try:
            result = self._fn(lambda step, text: self.progress.emit(step, text))
        except Exception as exc:  # shown to the user verbatim
            self.failed.emit(f"{type(exc).__name__}: {exc}")
            return
        self.succeeded.emit(result)
