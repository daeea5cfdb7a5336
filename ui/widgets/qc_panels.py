"""Parts of the QC screen (:mod:`ui.widgets.qc_screen`): the SPC page, the texture table and pictures.

Thin widgets over :mod:`ui.models.qc_views`: the SPC page shows a :class:`station.qc.spc_part.PartSpc`
(the table per geometry, the drift and rule hits in words, the chart as ``station qc spc`` draws it),
the texture table the rows of :func:`ui.models.qc_views.texture_lines`.
"""

from __future__ import annotations

from collections.abc import Sequence

from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QPixmap
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QPlainTextEdit,
    QPushButton,
    QScrollArea,
    QSpinBox,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from station.qc.spc_part import PartSpc
from ui.models.qc_views import SUBGROUPS, TextureLine, spc_hit_lines, spc_png, spc_rows

VERDICT_COLOURS = {"pass": "#b7e1b0", "warn": "#ffe08a", "fail": "#f4a09a"}
SPC_COLUMNS = ("geometry", "centre", "LCL", "UCL", "limit", "Cp", "Cpk", "Ppk", "R̄ / R UCL", "rule hits")
TEXTURE_COLUMNS = (
    "sample",
    "panel",
    "vendor",
    "quantity",
    "geometry",
    "standard",
    "value",
    "Δ",
    "tolerance",
    "verdict",
)


def scrolled(label: QLabel) -> QScrollArea:
    """*label* (a picture) in a scroll area."""
    area = QScrollArea()
    area.setWidget(label)
    area.setWidgetResizable(True)
    return area


def picture() -> QLabel:
    """A label for a PNG, its top-left corner at the top left."""
    label = QLabel()
    label.setAlignment(Qt.AlignmentFlag.AlignTop | Qt.AlignmentFlag.AlignLeft)
    return label


def show_png(label: QLabel, png: bytes) -> None:
    """Show the PNG bytes *png* on *label*."""
    pix = QPixmap()
    pix.loadFromData(png, "PNG")
    label.setPixmap(pix)


class SpcPage(QWidget):
    """Baseline and subgroup pickers, "Draw SPC", the per-geometry table, the words and the chart."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.baseline = QSpinBox()
        self.baseline.setRange(0, 10_000)
        self.baseline.setSpecialValueText("all points")
        self.baseline.setToolTip("points (subgroups) that set the centre and control limits")
        self.subgroup = QComboBox()
        for n in SUBGROUPS:
            self.subgroup.addItem("1 (individuals chart)" if n == 1 else f"{n} (X̄/R chart)", n)
        self.draw_btn = QPushButton("Draw SPC")
        self.draw_btn.setEnabled(False)
        self.table = QTableWidget(0, len(SPC_COLUMNS))
        self.table.setHorizontalHeaderLabels(list(SPC_COLUMNS))
        self.table.horizontalHeader().setSectionResizeMode(
            len(SPC_COLUMNS) - 1, QHeaderView.ResizeMode.Stretch
        )
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        self.table.setMaximumHeight(150)
        self.text = QPlainTextEdit("Judge a job, then Draw SPC for the part shown.")
        self.text.setReadOnly(True)
        self.text.setMaximumHeight(110)
        self.chart = picture()
        self.png = b""
        box = QVBoxLayout(self)
        box.setContentsMargins(0, 0, 0, 0)
        row = QHBoxLayout()
        row.addWidget(QLabel("baseline"))
        row.addWidget(self.baseline)
        row.addWidget(QLabel("subgroup"))
        row.addWidget(self.subgroup)
        row.addWidget(self.draw_btn)
        row.addStretch(1)
        box.addLayout(row)
        box.addWidget(self.table)
        box.addWidget(self.text)
        box.addWidget(scrolled(self.chart), 1)

    def choice(self) -> tuple[int | None, int]:
        """(baseline points or ``None`` for all, subgroup size) as picked."""
        return self.baseline.value() or None, int(self.subgroup.currentData())

    def clear(self, text: str) -> None:
        """Nothing shown but *text* (an error, or blank)."""
        self.table.setRowCount(0)
        self.text.setPlainText(text)
        self.chart.clear()
        self.png = b""

    def show_spc(self, spc: PartSpc) -> None:
        """The table per geometry, the drift and rule hits in words, the chart with the hits ringed."""
        rows = spc_rows(spc)
        self.table.setRowCount(len(rows))
        for i, r in enumerate(rows):
            for j, text in enumerate(r.cells()):
                item = QTableWidgetItem(text)
                item.setToolTip(text)
                self.table.setItem(i, j, item)
        self.table.resizeRowsToContents()
        self.text.setPlainText("\n".join(spc_hit_lines(spc)))
        self.png = spc_png(spc)
        show_png(self.chart, self.png)


def texture_table() -> QTableWidget:
    """The texture table (hidden until a part has texture rows)."""
    table = QTableWidget(0, len(TEXTURE_COLUMNS))
    table.setHorizontalHeaderLabels(list(TEXTURE_COLUMNS))
    table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
    table.setVisible(False)
    return table


def fill_texture(table: QTableWidget, lines: Sequence[TextureLine]) -> None:
    """*lines* in *table*, the verdict coloured; the table hidden when there are none."""
    table.setVisible(bool(lines))
    table.setRowCount(len(lines))
    for i, t in enumerate(lines):
        for j, text in enumerate(t.cells()):
            item = QTableWidgetItem(text)
            if j == TEXTURE_COLUMNS.index("verdict"):
                item.setBackground(QColor(VERDICT_COLOURS.get(t.verdict, "#ffffff")))
            table.setItem(i, j, item)
