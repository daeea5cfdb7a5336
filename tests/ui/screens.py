"""Typed access to the viewer's widgets for tests: a tab's screen by its class, a table's cell."""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

from PySide6.QtWidgets import QTableWidget, QTableWidgetItem, QWidget

from ui.widgets.screens import LazyScreen

if TYPE_CHECKING:
    from ui.app import MainWindow

Screen = TypeVar("Screen", bound=QWidget)


def screen_of(win: MainWindow, title: str, kind: type[Screen]) -> Screen:
    """The screen of the tab *title* (built now if it was not yet shown), checked to be a *kind*."""
    page = win.screens[title]
    assert isinstance(page, LazyScreen), f"tab {title!r} is not a lazily built screen"
    screen = page.content()
    assert isinstance(screen, kind), f"tab {title!r} holds a {type(screen).__name__}, not a {kind.__name__}"
    return screen


def item_at(table: QTableWidget, row: int, column: int) -> QTableWidgetItem:
    """The item at (*row*, *column*) of *table*, which must be there."""
    item = table.item(row, column)
    assert item is not None, f"no item at row {row}, column {column}"
    return item
