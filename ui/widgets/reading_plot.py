"""A measured reading against aspecular angle: L*, a*, b* points per geometry and the fitted design's curves."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QPainter, QPainterPath, QPen
from PySide6.QtWidgets import QWidget

from station.model import FaceFlopTravelGloss
from station.model.domain import LAB_PLOT_RANGES, plot_range

#: Channel label, colour and default axis (display only: widened to show every value, see paintEvent).
CHANNELS = (
    ("L*", QColor(40, 40, 40), LAB_PLOT_RANGES["L"]),
    ("a*", QColor(200, 40, 60), LAB_PLOT_RANGES["a"]),
    ("b*", QColor(40, 90, 200), LAB_PLOT_RANGES["b"]),
)
ANGLES = np.linspace(-20.0, 120.0, 141)


class ReadingPlot(QWidget):
    """Three stacked panels (L*, a*, b*) over aspecular −20…120°: measured points and the fit's curve."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.points: tuple[np.ndarray, np.ndarray] | None = None
        self.design: FaceFlopTravelGloss | None = None
        self.setMinimumSize(260, 220)

    def set_reading(self, angles, lab, design: FaceFlopTravelGloss | None) -> None:
        """Show aspecular *angles* (n,), *lab* (n, 3) and the fitted *design* (or None)."""
        self.points = (np.asarray(angles, float), np.asarray(lab, float))
        self.design = design
        self.update()

    def _values(self, k: int) -> np.ndarray:
        """Every value of channel *k* on show (measured points and the fitted curve)."""
        vals = [np.zeros(0)]
        if self.points is not None:
            vals.append(self.points[1][:, k])
        if self.design is not None:
            vals.append(self.design.lab_at(np.clip(ANGLES, 0.0, None))[:, k])
        return np.concatenate(vals)

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.fillRect(self.rect(), QColor(250, 250, 250))
        h = (self.height() - 16) / 3
        for k, (name, col, _default) in enumerate(CHANNELS):
            lo, hi = plot_range(name[0], self._values(k))
            r = QRectF(30, 4 + k * h, self.width() - 36, h - 8)
            p.setPen(QPen(QColor(180, 180, 180), 1))
            p.drawRect(r)
            p.setPen(col)
            p.drawText(QRectF(0, r.top(), 28, 14), Qt.AlignmentFlag.AlignRight, name)

            def px(a: float, v: float, r=r, lo=lo, hi=hi) -> QPointF:
                return QPointF(
                    r.left() + (a + 20.0) / 140.0 * r.width(),
                    r.bottom() - (min(max(v, lo), hi) - lo) / (hi - lo) * r.height(),
                )

            if self.design is not None:
                vals = self.design.lab_at(np.clip(ANGLES, 0.0, None))[:, k]
                path = QPainterPath(px(ANGLES[0], vals[0]))
                for a, v in zip(ANGLES[1:], vals[1:], strict=True):
                    path.lineTo(px(a, v))
                p.setPen(QPen(col, 1.5))
                p.drawPath(path)
            if self.points is not None:
                p.setPen(QPen(col, 1))
                p.setBrush(QColor(255, 255, 255))
                for a, v in zip(self.points[0], self.points[1][:, k], strict=True):
                    p.drawEllipse(px(a, v), 4, 4)
                p.setBrush(Qt.BrushStyle.NoBrush)
        p.setPen(QColor(90, 90, 90))
        p.drawText(
            QRectF(30, self.height() - 14, self.width() - 36, 14),
            Qt.AlignmentFlag.AlignCenter,
            "aspecular angle −20…120° (points: measured, line: fitted design)",
        )
        p.end()
