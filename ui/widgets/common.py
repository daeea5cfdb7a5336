"""Small Qt helpers shared by the widgets: NumPy images to pixmaps, Lab to display colours, table cells."""

from __future__ import annotations

import numpy as np
from PySide6.QtGui import QColor, QImage, QPixmap
from PySide6.QtWidgets import QTableWidget

from station.model.display import lab_to_display


def pixmap_from_array(img: np.ndarray) -> QPixmap:
    """(H, W, 3) uint8 → QPixmap (copied)."""
    a = np.ascontiguousarray(img, dtype=np.uint8)
    h, w = a.shape[:2]
    return QPixmap.fromImage(QImage(a.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy())


def lab_colour(lab) -> QColor:
    """Display colour of one Lab triple (D65/10°; out-of-gamut values clipped for display only)."""
    rgb = np.round(lab_to_display(np.asarray(lab, float)) * 255).astype(int)
    return QColor(*(int(v) for v in rgb))


def lab_colours(lab: np.ndarray) -> np.ndarray:
    """Display sRGB uint8 (..., 3) of Lab values (..., 3)."""
    return np.round(lab_to_display(np.asarray(lab, float)) * 255).astype(np.uint8)


def cell_text(table: QTableWidget, row: int, column: int) -> str:
    """The text of a filled cell of *table* (LookupError naming the cell when it holds no item)."""
    item = table.item(row, column)
    if item is None:
        raise LookupError(f"table cell (row {row}, column {column}) is empty")
    return item.text()
