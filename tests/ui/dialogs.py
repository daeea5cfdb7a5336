"""Typing into a file dialog the way a person does, shared by the journey tests."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QLineEdit


def enter_file_name(edit: QLineEdit, path: str | Path) -> None:
    """Replace the dialog's file name with *path* and press Enter.

    The dialog's file-name completer is taken off the field first: it offers a file of the folder
    (``blue.json`` for ``…/blue.``) as the folder's listing arrives, which on a busy machine can be after
    any check for its popup, and Enter would then take the suggestion — an existing file, whose
    overwrite prompt hangs the test in that dialog's event loop. Enter takes what was typed."""
    edit.setCompleter(None)  # type: ignore[arg-type]  # Qt takes no completer; the stubs omit None
    QTest.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClick(edit, Qt.Key.Key_Delete)
    QTest.keyClicks(edit, str(path))
    QTest.keyClick(edit, Qt.Key.Key_Return)


def answer_calibration(qtbot, screen, answers: list[str]) -> list[str]:
    """Click the instruments screen's Calibrate button and answer its prompts in turn, as a person does:
    each of *answers* is ``"ok"`` or ``"cancel"`` for the next prompt shown. Returns the prompts' titles."""
    from PySide6.QtWidgets import QMessageBox

    buttons = {"ok": QMessageBox.StandardButton.Ok, "cancel": QMessageBox.StandardButton.Cancel}
    QTest.mouseClick(screen.calibrate_btn, Qt.MouseButton.LeftButton)
    titles = []
    for answer in answers:
        qtbot.waitUntil(lambda: screen.prompt is not None and screen.prompt.isVisible(), timeout=10000)
        box = screen.prompt
        titles.append(box.windowTitle())
        QTest.mouseClick(box.button(buttons[answer]), Qt.MouseButton.LeftButton)
        qtbot.waitUntil(lambda b=box: screen.prompt is not b, timeout=10000)
    return titles
