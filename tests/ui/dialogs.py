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
    edit.setCompleter(None)
    QTest.keyClick(edit, Qt.Key.Key_A, Qt.KeyboardModifier.ControlModifier)
    QTest.keyClick(edit, Qt.Key.Key_Delete)
    QTest.keyClicks(edit, str(path))
    QTest.keyClick(edit, Qt.Key.Key_Return)
