"""QPainter plots of the designer: L, a, b against aspecular angle, and the a–b plane with the
face→flop arrow over a hue wheel (thesis Figs. 3.5–3.7). Dragging edits the design through
:class:`ui.models.designer.DesignerModel`; the plots redraw from the document's ``changed`` event.
Every axis carries tick labels (:func:`ticks`); on the a–b plot the arrowhead moves the face, the base
moves the flop and the shaft moves the whole arrow.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPointF, QRectF, Qt, Signal
from PySide6.QtGui import QColor, QImage, QMouseEvent, QPainter, QPainterPath, QPen, QPolygonF
from PySide6.QtWidgets import QSizePolicy, QWidget

from station.design.designer import Channel
from station.model import FaceFlopTravelGloss
from station.model.domain import LAB_PLOT_RANGES, LAB_RANGES, plot_range
from ui.models.designer import DesignerModel
from ui.widgets.common import lab_colour, lab_colours

CURVE_ANGLES = np.linspace(0.0, 120.0, 121)
#: Labelled aspecular angles on the curve plots (degrees).
ANGLE_TICKS = (0, 15, 45, 75, 110)
#: Default axes (display only); :meth:`CurvePlot.axis` widens them to show a bright silver's L* > 100.
RANGES = LAB_PLOT_RANGES
#: Labelled a* and b* values on the a–b plot.
AB_TICKS = (-80, -40, 0, 40, 80)
MARGIN = 34
BOTTOM = 30
HANDLE_PX = 8
#: Pixels from the shaft of the a–b arrow that grab the whole arrow.
SHAFT_PX = 5


def ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """Round tick values inside [*lo*, *hi*]: a 1-2-5 step giving about *count* ticks."""
    span = hi - lo
    if not np.isfinite(span) or span <= 0:
        return [lo]
    raw = span / max(1, count - 1)
    mag = 10.0 ** np.floor(np.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = np.ceil(lo / step) * step
    return [float(v) for v in np.arange(first, hi + 1e-9 * span, step)]


def _tick_text(v: float) -> str:
    return f"{v:.0f}" if abs(v - round(v)) < 1e-9 else f"{v:g}"


class _PlotBase(QWidget):
    """Mapping between data and pixels, binding to the designer model."""

    edited = Signal()

    def __init__(self, model: DesignerModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        self._drag: object | None = None
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)
        self.setMinimumSize(160, 120)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)  # Ctrl+Z after a drag undoes it, not a text box
        model.document.events.changed.connect(self._on_changed)

    def _on_changed(self, design: FaceFlopTravelGloss) -> None:
        self.update()

    def plot_rect(self) -> QRectF:
        """The data area in widget pixels."""
        return QRectF(MARGIN, 8, max(1, self.width() - MARGIN - 8), max(1, self.height() - BOTTOM - 8))

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None:
            self._drag = None
            self.model.end_drag()

    def closeEvent(self, event) -> None:
        self.model.document.events.changed.disconnect(self._on_changed)
        super().closeEvent(event)


class CurvePlot(_PlotBase):
    """One channel (``L``, ``a`` or ``b``) against aspecular angle 0–120°, points at the 5 angles."""

    #: The aspecular angle (degrees) of the point being dragged.
    _drag: float | None

    def __init__(self, model: DesignerModel, channel: Channel, parent: QWidget | None = None) -> None:
        super().__init__(model, parent)
        self.channel = channel
        self.k = "Lab".index(channel)
        self._axis: tuple[float, float] | None = None
        self.setToolTip(f"{channel}* against aspecular angle: drag a point to edit")

    def axis(self) -> tuple[float, float]:
        """Value axis: the default range widened to the design and its points (frozen while dragging)."""
        if self._axis is not None:
            return self._axis
        _, lab = self.model.points()
        vals = np.concatenate([self.model.design.lab_at(CURVE_ANGLES)[:, self.k], np.asarray(lab)[:, self.k]])
        return plot_range(self.channel, vals)

    def value_ticks(self) -> list[float]:
        """Labelled values of the value axis."""
        return ticks(*self.axis())

    def to_px(self, angle: float, value: float) -> QPointF:
        """Data (degrees, value) → pixels."""
        r = self.plot_rect()
        lo, hi = self.axis()
        return QPointF(
            r.left() + angle / 120.0 * r.width(), r.bottom() - (value - lo) / (hi - lo) * r.height()
        )

    def from_px(self, p: QPointF) -> tuple[float, float]:
        """Pixels → data (degrees, value)."""
        r = self.plot_rect()
        lo, hi = self.axis()
        return ((p.x() - r.left()) / r.width() * 120.0, lo + (r.bottom() - p.y()) / r.height() * (hi - lo))

    def point_positions(self) -> list[tuple[float, QPointF]]:
        """(angle, pixel position) of each editable point."""
        angles, lab = self.model.points()
        return [(a, self.to_px(a, row[self.k])) for a, row in zip(angles, lab, strict=True)]

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.fillRect(self.rect(), QColor(250, 250, 250))
        r = self.plot_rect()
        p.setPen(QPen(QColor(200, 200, 200), 1))
        lo, hi = self.axis()
        for a in (15, 45, 75, 110):
            p.drawLine(self.to_px(a, lo), self.to_px(a, hi))
        p.setPen(QPen(QColor(90, 90, 90), 1))
        p.drawRect(r)
        right = Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter
        for v in self.value_ticks():
            y = self.to_px(0.0, v).y()
            p.drawLine(QPointF(r.left() - 3, y), QPointF(r.left(), y))
            p.drawText(QRectF(0, y - 7, MARGIN - 5, 14), right, _tick_text(v))
        for a in ANGLE_TICKS:
            x = self.to_px(a, lo).x()
            p.drawLine(QPointF(x, r.bottom()), QPointF(x, r.bottom() + 3))
            p.drawText(QRectF(x - 14, r.bottom() + 2, 28, 13), Qt.AlignmentFlag.AlignCenter, str(a))
        p.drawText(
            QRectF(r.right() - 34, r.top() + 2, 30, 14), Qt.AlignmentFlag.AlignRight, f"{self.channel}*"
        )
        p.drawText(
            QRectF(r.left(), r.bottom() + 14, r.width(), 14),
            Qt.AlignmentFlag.AlignCenter,
            "aspecular angle θ (°)",
        )
        design = self.model.design
        vals = design.lab_at(CURVE_ANGLES)[:, self.k]
        path = QPainterPath(self.to_px(CURVE_ANGLES[0], vals[0]))
        for a, v in zip(CURVE_ANGLES[1:], vals[1:], strict=True):
            path.lineTo(self.to_px(a, v))
        p.setPen(QPen(QColor(30, 60, 160), 2))
        p.drawPath(path)
        if design.travel_deg is not None:
            p.setPen(QPen(QColor(200, 80, 40), 1, Qt.PenStyle.DashLine))
            p.drawLine(
                self.to_px(design.travel_deg, lo),
                self.to_px(design.travel_deg, hi),
            )
        p.setPen(QPen(QColor(20, 20, 20), 1))
        p.setBrush(QColor(255, 200, 60))
        for _a, pt in self.point_positions():
            p.drawEllipse(pt, HANDLE_PX / 2 + 1, HANDLE_PX / 2 + 1)
        p.end()

    def mousePressEvent(self, event: QMouseEvent) -> None:
        pos = event.position()
        for a, pt in self.point_positions():
            if abs(pt.x() - pos.x()) <= HANDLE_PX and abs(pt.y() - pos.y()) <= HANDLE_PX:
                self._axis = self.axis()
                self._drag = a
                return

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._axis = None
        super().mouseReleaseEvent(event)

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is None:
            return
        _, value = self.from_px(event.position())
        lo, hi = LAB_RANGES[self.channel]  # the domain's bound; the model refuses nothing inside it
        self.model.move_point(self.channel, float(self._drag), float(min(max(value, lo), hi)))
        self.edited.emit()


class ABPlot(_PlotBase):
    """The a–b plane (±80) over a hue wheel at the face's L*, the curve and the flop→face arrow.

    Drag the arrowhead (face) or the base (flop); the dashed circle is the chroma of the face.
    """

    #: What is dragged: ``"face"``, ``"flop"``, or ``("arrow", (a*, b*) where the drag started)``.
    _drag: str | tuple[str, tuple[float, float]] | None

    def __init__(self, model: DesignerModel, parent: QWidget | None = None) -> None:
        super().__init__(model, parent)
        self._wheel: tuple[float, int, QImage] | None = None  # (L*, size in pixels, hue wheel)
        self.setToolTip("a*–b*: drag the arrowhead (face), its base (flop) or the shaft (whole arrow)")

    def plot_rect(self) -> QRectF:
        """Square data area."""
        s = max(1, min(self.width(), self.height()) - 16)
        return QRectF((self.width() - s) / 2, (self.height() - s) / 2, s, s)

    def to_px(self, a: float, b: float) -> QPointF:
        """(a*, b*) → pixels."""
        r = self.plot_rect()
        return QPointF(r.center().x() + a / 160.0 * r.width(), r.center().y() - b / 160.0 * r.height())

    def from_px(self, p: QPointF) -> tuple[float, float]:
        """Pixels → (a*, b*)."""
        r = self.plot_rect()
        return ((p.x() - r.center().x()) / r.width() * 160.0, (r.center().y() - p.y()) / r.height() * 160.0)

    def _wheel_image(self, L: float, size: int) -> QImage:
        key = (round(L, 1), size)
        if self._wheel is None or self._wheel[:2] != key:
            c = (np.arange(size) + 0.5) / size * 160.0 - 80.0
            a, b = np.meshgrid(c, -c)
            lab = np.stack([np.full_like(a, key[0]), a, b], axis=-1)
            rgb = lab_colours(lab)
            rgb = (0.55 * rgb + 0.45 * 235).astype(np.uint8)  # washed out so the arrow reads
            self._wheel_buf = np.ascontiguousarray(rgb)
            img = QImage(self._wheel_buf.data, size, size, 3 * size, QImage.Format.Format_RGB888).copy()
            self._wheel = (*key, img)
        return self._wheel[2]

    def handles(self) -> dict[str, QPointF]:
        """Pixel positions of the face and flop handles."""
        d = self.model.design
        return {"face": self.to_px(d.face[1], d.face[2]), "flop": self.to_px(d.flop[1], d.flop[2])}

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.RenderHint.Antialiasing)
        p.fillRect(self.rect(), QColor(250, 250, 250))
        r = self.plot_rect()
        d = self.model.design
        p.drawImage(r, self._wheel_image(d.face[0], 96))
        p.setPen(QPen(QColor(150, 150, 150), 1))
        p.drawLine(self.to_px(-80, 0), self.to_px(80, 0))
        p.drawLine(self.to_px(0, -80), self.to_px(0, 80))
        p.drawText(self.to_px(62, 5), "a*")
        p.drawText(self.to_px(-24, 60), "b*")  # left of the axis, between the 40 and 80 ticks
        p.setPen(QPen(QColor(80, 80, 80), 1))
        for v in AB_TICKS:
            if v == 0:
                continue
            x = self.to_px(v, 0)
            p.drawLine(QPointF(x.x(), x.y() - 3), QPointF(x.x(), x.y() + 3))
            p.drawText(QRectF(x.x() - 14, x.y() + 3, 28, 13), Qt.AlignmentFlag.AlignCenter, _tick_text(v))
            y = self.to_px(0, v)
            p.drawLine(QPointF(y.x() - 3, y.y()), QPointF(y.x() + 3, y.y()))
            p.drawText(QRectF(y.x() + 4, y.y() - 7, 28, 14), Qt.AlignmentFlag.AlignLeft, _tick_text(v))
        lab = d.lab_at(CURVE_ANGLES)
        path = QPainterPath(self.to_px(lab[0, 1], lab[0, 2]))
        for row in lab[1:]:
            path.lineTo(self.to_px(row[1], row[2]))
        p.setPen(QPen(QColor(60, 60, 60), 1, Qt.PenStyle.DotLine))
        p.drawPath(path)
        h = self.handles()
        p.setPen(QPen(QColor(20, 20, 20), 2))
        p.drawLine(h["flop"], h["face"])
        shaft = h["face"] - h["flop"]
        n = max(1e-6, (shaft.x() ** 2 + shaft.y() ** 2) ** 0.5)
        u = QPointF(shaft.x() / n, shaft.y() / n)
        w = QPointF(-u.y(), u.x())
        tip = h["face"]
        p.setBrush(QColor(20, 20, 20))
        p.drawPolygon(QPolygonF([tip, tip - u * 12 + w * 5, tip - u * 12 - w * 5]))
        for name, pt in h.items():
            p.setBrush(lab_colour(d.face if name == "face" else d.flop))
            p.drawEllipse(pt, HANDLE_PX, HANDLE_PX)
        p.end()

    def on_shaft(self, pos: QPointF) -> bool:
        """Whether *pos* is within :data:`SHAFT_PX` of the arrow's shaft (between the handles)."""
        h = self.handles()
        p0, p1 = np.array([h["flop"].x(), h["flop"].y()]), np.array([h["face"].x(), h["face"].y()])
        q = np.array([pos.x(), pos.y()])
        d = p1 - p0
        n2 = float(d @ d)
        if n2 < 1e-9:
            return False
        t = float((q - p0) @ d) / n2
        return 0.0 < t < 1.0 and float(np.linalg.norm(p0 + t * d - q)) <= SHAFT_PX

    def mousePressEvent(self, event: QMouseEvent) -> None:
        pos = event.position()
        for name, pt in self.handles().items():
            if abs(pt.x() - pos.x()) <= HANDLE_PX + 2 and abs(pt.y() - pos.y()) <= HANDLE_PX + 2:
                self._drag = name
                return
        if self.on_shaft(pos):
            self._drag = ("arrow", self.from_px(pos))

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is None:
            return
        a, b = self.from_px(event.position())
        a, b = float(np.clip(a, -80, 80)), float(np.clip(b, -80, 80))
        if isinstance(self._drag, tuple):
            a0, b0 = self._drag[1]
            self.model.move_arrow(a - a0, b - b0)
        else:
            (self.model.move_face if self._drag == "face" else self.model.move_flop)(a, b)
        self.edited.emit()
