"""A measured reading against aspecular angle: L*, a*, b* points per geometry and the fitted design's curves.

The fitted curve is drawn over the measured range of angles (a −15° geometry included): the model is a
function of the unsigned aspecular angle (``FaceFlopTravelGloss.lab_at``, thesis §2.2), so at −15° it
is evaluated as at 15°, and between −15° and 15° it rises towards the specular direction as the model
does. Every panel has tick labels on both axes and names its channel; the x axis is titled.
"""

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
#: Axis of aspecular angles shown (degrees) when nothing is measured, and its tick marks.
ANGLE_AXIS = (-20.0, 120.0)
ANGLE_TICKS = (-15.0, 0.0, 15.0, 25.0, 45.0, 75.0, 110.0)
TITLE = "L*, a*, b* against aspecular angle (points: measured, line: fitted design)"
X_TITLE = "aspecular angle (°)"
LEFT, RIGHT, TOP, BOTTOM = 58.0, 8.0, 18.0, 30.0  # margins in pixels (tick labels, titles)


class ReadingPlot(QWidget):
    """Three stacked panels (L*, a*, b*) over aspecular angle: measured points and the fit's curve."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.points: tuple[np.ndarray, np.ndarray] | None = None
        self.design: FaceFlopTravelGloss | None = None
        self.setMinimumSize(300, 260)

    def set_reading(self, angles, lab, design: FaceFlopTravelGloss | None) -> None:
        """Show aspecular *angles* (n,), *lab* (n, 3) and the fitted *design* (or None)."""
        self.points = (np.asarray(angles, float), np.asarray(lab, float))
        self.design = design
        self.update()

    def curve_angles(self) -> np.ndarray:
        """Aspecular angles (degrees) the fitted curve is drawn at: the measured range, 1° apart or finer."""
        if self.points is not None and self.points[0].size:
            lo, hi = float(self.points[0].min()), float(self.points[0].max())
        else:
            lo, hi = 15.0, 110.0
        return np.linspace(lo, hi, max(2, int(round(hi - lo)) + 1))

    def curve(self) -> np.ndarray:
        """Lab of the fitted design along :meth:`curve_angles` (n, 3); empty without a design."""
        if self.design is None:
            return np.zeros((0, 3))
        return np.asarray(self.design.lab_at(self.curve_angles()), float)

    def angle_axis(self) -> tuple[float, float]:
        """The x axis (degrees): −20…120°, widened to the measured range."""
        lo, hi = ANGLE_AXIS
        if self.points is not None and self.points[0].size:
            lo, hi = min(lo, float(self.points[0].min()) - 5), max(hi, float(self.points[0].max()) + 5)
        return lo, hi

    def _values(self, k: int) -> np.ndarray:
        """Every value of channel *k* on show (measured points and the fitted curve)."""
        vals = [np.zeros(0), self.curve()[:, k]]
        if self.points is not None:
            vals.append(self.points[1][:, k])
        return np.concatenate(vals)

    def y_axis(self, k: int) -> tuple[float, float]:
        """The axis of channel *k*: :func:`station.model.domain.plot_range` of what is shown."""
        return plot_range(CHANNELS[k][0][0], self._values(k))

    def title_rect(self) -> QRectF:
        """Where the title is drawn: the top of the widget, wrapped to as many lines as its width needs."""
        r = self.fontMetrics().boundingRect(
            0, 0, max(self.width() - 8, 1), 10_000, Qt.TextFlag.TextWordWrap, TITLE
        )
        return QRectF(4, 1, self.width() - 8, r.height())

    def tick_rect(self, x: float, top: float, height: float) -> QRectF:
        """The rectangle of an angle tick label centred at *x* (pixels), kept inside the widget."""
        return QRectF(min(max(x - 18, 0.0), self.width() - 36.0), top, 36, height)

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.fillRect(self.rect(), QColor(250, 250, 250))
        fm = p.fontMetrics()
        p.setPen(QColor(60, 60, 60))
        title = self.title_rect()
        p.drawText(title, Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap, TITLE)
        top = max(TOP, title.bottom() + 2)
        a_lo, a_hi = self.angle_axis()
        h = (self.height() - top - BOTTOM) / 3
        curve_a, curve = self.curve_angles(), self.curve()
        for k, (name, col, _default) in enumerate(CHANNELS):
            lo, hi = self.y_axis(k)
            r = QRectF(LEFT, top + k * h + 2, self.width() - LEFT - RIGHT, h - 6)

            def px(a: float, v: float, r=r, lo=lo, hi=hi) -> QPointF:
                return QPointF(
                    r.left() + (a - a_lo) / (a_hi - a_lo) * r.width(),
                    r.bottom() - (min(max(v, lo), hi) - lo) / (hi - lo) * r.height(),
                )

            grid = QPen(QColor(225, 225, 225), 1)
            p.setPen(grid)
            for a in ANGLE_TICKS:
                if a_lo <= a <= a_hi:
                    p.drawLine(px(a, lo), px(a, hi))
            p.setPen(QPen(QColor(170, 170, 170), 1))
            p.drawRect(r)
            # y tick labels: bottom, middle, top of the axis (inside the panel's height: no overlap)
            p.setPen(QColor(90, 90, 90))
            for v, dy in ((lo, -fm.height()), ((lo + hi) / 2, -fm.height() / 2), (hi, 0.0)):
                y = px(a_lo, v).y()
                p.drawText(
                    QRectF(LEFT - 34, y + dy, 30, fm.height()),
                    Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter,
                    f"{v:g}",
                )
            p.setPen(col)
            p.drawText(
                QRectF(2, r.center().y() - fm.height() / 2, 22, fm.height()),
                Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter,
                name,
            )
            if curve.size:
                path = QPainterPath(px(curve_a[0], curve[0, k]))
                for a, v in zip(curve_a[1:], curve[1:, k], strict=True):
                    path.lineTo(px(a, v))
                p.setPen(QPen(col, 1.5))
                p.drawPath(path)
            if self.points is not None:
                p.setPen(QPen(col, 1))
                p.setBrush(QColor(255, 255, 255))
                for a, v in zip(self.points[0], self.points[1][:, k], strict=True):
                    p.drawEllipse(px(a, v), 4, 4)
                p.setBrush(Qt.BrushStyle.NoBrush)
        # x tick labels under the last panel, then the axis title
        p.setPen(QColor(90, 90, 90))
        base = top + 3 * h - 4
        width = self.width() - LEFT - RIGHT
        for a in ANGLE_TICKS:
            if a_lo <= a <= a_hi:
                x = LEFT + (a - a_lo) / (a_hi - a_lo) * width
                p.drawText(self.tick_rect(x, base, fm.height()), Qt.AlignmentFlag.AlignCenter, f"{a:g}")
        p.drawText(
            QRectF(LEFT, base + fm.height(), width, fm.height()), Qt.AlignmentFlag.AlignCenter, X_TITLE
        )
        p.end()
