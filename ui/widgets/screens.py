"""The tabs beside the design view; each screen is built only when its module imports."""

from __future__ import annotations

from PySide6.QtWidgets import QWidget


def build_screens(window) -> list[tuple[str, QWidget]]:
    """(title, widget) of every secondary screen."""
    out: list[tuple[str, QWidget]] = []
    return out
