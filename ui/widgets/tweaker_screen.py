"""Tweaker (thesis §3.6, Figs. 3.15, 3.17–3.18): edit the design on the rendered object.

A point-lit sphere (``station.design.scene``) is shaded with the design; the HUD draws the iso-angle
rings at 15° (face), 45° and θ_clamp (flop), the highlight's half-maximum edge, and a gloss checkerboard
off the object. Click the object to place the crosshair; the buttons around it make it lighter/darker,
more/less chroma, hue ± there (``station.design.tweaker.adjust_at``: the blend ratio R of eq 3.6.4 depends
on θ under the crosshair). Dragging the θ_clamp ring sets travel, dragging the highlight edge sets gloss,
dragging the highlight centre moves the light. Every edit is one undo step.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, QPointF
from PySide6.QtGui import QColor, QImage, QMouseEvent, QPainter, QPen
from PySide6.QtWidgets import QHBoxLayout, QLabel, QToolButton, QVBoxLayout, QWidget

from station.design.scene import shade, sphere_scene, srgb_encode, to_uint8
from station.design.tweaker import (
    adjust_at,
    drag_highlight_centre,
    drag_highlight_edge,
    drag_travel,
    highlight_edge_deg,
    hit_test,
)
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from ui.models.document import DesignDocument

SIZE = 400
STEPS = {"L": 3.0, "C": 0.1, "H": 5.0}
BUTTONS = (
    ("lighter", "L", +1, (0, -34)),
    ("darker", "L", -1, (0, 34)),
    ("chroma +", "C", +1, (44, -12)),
    ("chroma −", "C", -1, (-44, -12)),
    ("hue +", "H", +1, (44, 14)),
    ("hue −", "H", -1, (-44, 14)),
)
RING_COLOURS = {
    "15°": QColor(255, 220, 0),
    "45°": QColor(255, 255, 255),
    "θ_clamp": QColor(0, 200, 255),
    "highlight edge": QColor(255, 80, 80),
}


class TweakerCanvas(QWidget):
    """The shaded object, HUD and crosshair; mouse edits go to the document."""

    def __init__(self, document: DesignDocument, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.document = document
        self.scene = sphere_scene(SIZE)
        self.crosshair: tuple[int, int] | None = None
        self._drag: str | None = None
        self.message = ""
        self.setFixedSize(SIZE + 120, SIZE)
        self.buttons: dict[str, QToolButton] = {}
        for label, kind, sign, _off in BUTTONS:
            b = QToolButton(self)
            b.setText(label)
            b.clicked.connect(lambda _=False, k=kind, s=sign: self.adjust(k, s * STEPS[k]))
            b.hide()
            self.buttons[label] = b
        document.events.changed.connect(self._on_changed)
        self._render()

    # ------------------------------------------------------------------ drawing
    def _render(self) -> None:
        d = self.document.design
        rgb = to_uint8(srgb_encode(shade(self.scene, d, background=(0.05, 0.05, 0.06))))
        self._buf = np.ascontiguousarray(rgb)
        self._image = QImage(self._buf.data, SIZE, SIZE, 3 * SIZE, QImage.Format.Format_RGB888)
        self.update()

    def rings(self) -> dict[str, float]:
        """Angles (degrees) of the HUD rings for the current design."""
        d = self.document.design
        out = {"15°": 15.0, "45°": 45.0, "highlight edge": highlight_edge_deg(d.gloss_gu)}
        if d.travel_deg is not None:
            out["θ_clamp"] = d.travel_deg
        return out

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.fillRect(self.rect(), QColor(30, 30, 34))
        p.drawImage(0, 0, self._image)
        theta, mask = self.scene.aspecular_deg, self.scene.mask
        for name, angle in self.rings().items():
            edge = mask & (np.abs(theta - angle) < 0.9)
            ys, xs = np.nonzero(edge)
            p.setPen(QPen(RING_COLOURS[name], 1))
            for x, y in zip(xs[::2], ys[::2], strict=True):
                p.drawPoint(int(x), int(y))
        # gloss checkerboard off the object: contrast of the squares ∝ gloss (0–100 GU)
        g = self.document.design.gloss_gu / 100.0
        for i in range(6):
            for j in range(6):
                v = int(128 + (1 if (i + j) % 2 else -1) * 110 * g)
                p.fillRect(SIZE + 20 + 12 * i, 20 + 12 * j, 12, 12, QColor(v, v, v))
        p.setPen(QColor(220, 220, 220))
        p.drawText(SIZE + 20, 104, f"gloss {self.document.design.gloss_gu:.0f} GU")
        y = 124
        for name, col in RING_COLOURS.items():
            p.setPen(col)
            p.drawText(SIZE + 20, y, name)
            y += 16
        if self.crosshair is not None:
            x, yy = self.crosshair
            p.setPen(QPen(QColor(255, 255, 255), 1))
            p.drawLine(QPointF(x - 10, yy), QPointF(x + 10, yy))
            p.drawLine(QPointF(x, yy - 10), QPointF(x, yy + 10))
        p.end()

    def _place_buttons(self) -> None:
        if self.crosshair is None:
            return
        x, y = self.crosshair
        for label, _k, _s, (dx, dy) in BUTTONS:
            b = self.buttons[label]
            b.adjustSize()
            b.move(
                QPoint(
                    int(min(max(x + dx - b.width() / 2, 0), SIZE - b.width())),
                    int(min(max(y + dy - b.height() / 2, 0), SIZE - b.height())),
                )
            )
            b.show()

    # ------------------------------------------------------------------ editing
    def _pixel(self, pos: QPointF) -> tuple[int, int] | None:
        x, y = int(pos.x()), int(pos.y())
        if 0 <= x < SIZE and 0 <= y < SIZE and self.scene.mask[y, x]:
            return x, y
        return None

    def adjust(self, kind: str, delta: float) -> bool:
        """Lighter/darker (ΔL*), chroma (relative) or hue (degrees) at the crosshair."""
        if self.crosshair is None:
            return False
        xy = self.crosshair
        return self.document.apply(
            lambda d: (
                adjust_at(
                    d,
                    self.scene.aspecular_deg,
                    xy,
                    kind,
                    delta,  # type: ignore[arg-type]
                    self.scene.mask,
                ).design
            ),
            f"tweak {kind}",
        )

    def press(self, xy: tuple[int, int]) -> str:
        """Act on a press at pixel *xy* of the object; returns the hit target."""
        theta = float(self.scene.aspecular_deg[xy[1], xy[0]])
        target = hit_test(self.document.design, theta)
        if target == "object":
            self.crosshair = xy
            self._place_buttons()
            self.update()
        else:
            self._drag = target
            self.drag(xy)
        return target

    def drag(self, xy: tuple[int, int]) -> None:
        """Continue a drag of the ring, highlight edge or highlight centre to pixel *xy*."""
        s, d = self.scene, self.document
        try:
            if self._drag == "travel-ring":
                d.apply(lambda x: drag_travel(x, s.aspecular_deg, xy, s.mask), "drag travel ring", "tw:ring")
            elif self._drag == "highlight-edge":
                d.apply(
                    lambda x: drag_highlight_edge(x, s.aspecular_deg, xy, s.mask),
                    "drag highlight edge",
                    "tw:edge",
                )
            elif self._drag == "highlight-centre":
                self.scene = s.with_light(drag_highlight_centre(s.light_dirs, xy, s.mask))
                self._render()
        except InputError as exc:
            self.message = str(exc)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        xy = self._pixel(event.position())
        if xy is not None:
            self.press(xy)

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        xy = self._pixel(event.position())
        if self._drag is not None and xy is not None:
            self.drag(xy)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        if self._drag is not None:
            self._drag = None
            self.document.end_merge()

    def _on_changed(self, design: FaceFlopTravelGloss) -> None:
        self._render()

    def closeEvent(self, event) -> None:
        self.document.events.changed.disconnect(self._on_changed)
        super().closeEvent(event)


class TweakerScreen(QWidget):
    """The canvas and a short legend."""

    def __init__(self, document: DesignDocument, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.canvas = TweakerCanvas(document)
        help_text = QLabel(
            "Click the object to place the crosshair, then use the buttons around it. Drag the "
            "θ_clamp ring (blue) to set travel, the highlight edge (red) to set gloss, the "
            "highlight centre to move the light."
        )
        help_text.setWordWrap(True)
        row = QHBoxLayout()
        row.addWidget(self.canvas)
        row.addStretch(1)
        lay = QVBoxLayout(self)
        lay.addWidget(help_text)
        lay.addLayout(row)
        lay.addStretch(1)

    def closeEvent(self, event) -> None:
        self.canvas.close()
        super().closeEvent(event)
