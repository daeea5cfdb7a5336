"""Typing into a file dialog the way a person does, shared by the journey tests."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtTest import QTest
from PySide6.QtWidgets import QLineEdit


def enter_file_name(edit: QLineEdit, path: str | Path) -> None:
    """Replace the dialog's file name with *path* and press Enter.

    The file-name completer may pop up with a file of the folder (``blue.json`` for ``…/blue.``); it is
    dismissed first, so Enter takes what was typed, not its suggestion (which could open an overwrite
    prompt and hang the test in that dialog's event loop)."""
    QTest.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClick(edit, Qt.Key.Key_Delete)
    QTest.keyClicks(edit, str(path))
    popup = edit.completer().popup() if edit.completer() is not None else None
    if popup is not None and popup.isVisible():
        QTest.keyClick(popup, Qt.Key.Key_Escape)
    QTest.keyClick(edit, Qt.Key.Key_Return)
