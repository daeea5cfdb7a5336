"""Tweaker (thesis §3.6, Figs. 3.15, 3.17–3.18): edit the design on the rendered object.

In the viewer the tweaker shows the 3D view's scene — its shape, orbit camera and environment
(:func:`ui.models.tweaker.main_scene`, computed off the GUI thread, again after a shape, camera or
environment change: first a preview of at most :data:`PREVIEW_PX` pixels a side, shown scaled up within a
second, then the scene at the canvas size) — with θ per pixel taken against the environment's dominant
light. Without a view model (a bare canvas) a point-lit sphere (``station.design.scene``) is used. The
HUD draws the iso-angle
rings at 15° (face), 45° and θ_clamp (flop), the highlight's half-maximum edge, and a gloss checkerboard
off the object. Click the object to place the crosshair; the buttons around it make it lighter/darker,
more/less chroma, hue ± there (``station.design.tweaker.adjust_at``: the blend ratio R of eq 3.6.4 depends
on θ under the crosshair). Dragging the θ_clamp ring sets travel, dragging the highlight edge sets gloss,
dragging the highlight centre moves the light. Every edit is one undo step.
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, QPointF, Signal
from PySide6.QtGui import QColor, QImage, QMouseEvent, QPainter, QPen
from PySide6.QtWidgets import QHBoxLayout, QLabel, QToolButton, QVBoxLayout, QWidget

from station.design.scene import shade, sphere_scene, srgb_encode, to_uint8
from station.design.tweaker import (
    Adjustment,
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
from ui.models.tweaker import MainScene, main_scene
from ui.models.view import (
    PREFILTER_MAX_SIZE,
    PREVIEW_PREFILTER_SIZE,
    ViewModel,
    ViewSettings,
    environment_ready,
)
from ui.widgets.tasks import GcPausingThread

SIZE = 400
#: Side panel (gloss checkerboard and legend) width, pixels.
SIDE = 120
#: Largest main-scene render of the tweaker, pixels per side.
MAX_SCENE_PX = 900
#: Longest side of the preview scene shown first, pixels (it takes a tenth of a second to compute).
PREVIEW_PX = 160
#: One button press: ΔL* (L* units), relative ΔC (0.1 = +10 %) or ΔH (degrees).
STEPS: dict[Adjustment, float] = {"L": 3.0, "C": 0.1, "H": 5.0}
#: (label, adjustment, sign, offset from the crosshair in pixels) of the buttons around the crosshair.
BUTTONS: tuple[tuple[str, Adjustment, int, tuple[int, int]], ...] = (
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


def preview_size(width: int, height: int) -> tuple[int, int]:
    """(width, height) of the preview scene for a *width* × *height* scene: the same aspect, longest
    side at most :data:`PREVIEW_PX` pixels."""
    k = min(1.0, PREVIEW_PX / max(width, height))
    return max(16, round(width * k)), max(16, round(height * k))


class SceneWorker(GcPausingThread):
    """Computes the main scene's basis images and tweaker geometry off the GUI thread: the preview
    first, then the full size (skipped when a newer request interrupts the worker)."""

    done = Signal(object)  # MainScene

    def __init__(self, settings: ViewSettings, width: int, height: int, parent=None) -> None:
        super().__init__(parent)
        self.settings, self.width_px, self.height_px = settings, width, height

    def run(self) -> None:
        """Compute and report each size."""
        sizes = [preview_size(self.width_px, self.height_px), (self.width_px, self.height_px)]
        if sizes[0] == sizes[1]:
            sizes.pop(0)
        env = self.settings.environment
        for i, (w, h) in enumerate(sizes):
            if self.isInterruptionRequested():
                return
            # a cold environment cache: the preview uses the coarse prefilter (~0.1 s instead of seconds)
            coarse = i == 0 and len(sizes) > 1 and not environment_ready(env, PREFILTER_MAX_SIZE)
            size = PREVIEW_PREFILTER_SIZE if coarse else PREFILTER_MAX_SIZE
            self.done.emit(main_scene(self.settings, w, h, size))


class TweakerCanvas(QWidget):
    """The shaded object, HUD and crosshair; mouse edits go to the document.

    With *view_model* the object is the 3D view's scene (any shape, environment lit) filling the canvas;
    without, a point-lit sphere of :data:`SIZE` pixels.
    """

    #: A main scene (preview or full size) has been drawn for the first time.
    scene_shown = Signal()

    def __init__(
        self, document: DesignDocument, view_model: ViewModel | None = None, parent: QWidget | None = None
    ) -> None:
        super().__init__(parent)
        self.document = document
        self.view_model = view_model
        # with a view model the object arrives from the scene worker: nothing to shade here meanwhile
        self.scene = sphere_scene(SIZE if view_model is None else 16)
        #: Canvas pixels per scene pixel (above 1 while the preview is shown).
        self.zoom = 1.0
        #: How many main scenes (previews included) have been drawn.
        self.scenes_shown = 0
        self._announce = False
        self.main: MainScene | None = None
        self.crosshair: tuple[int, int] | None = None
        self._drag: str | None = None
        self._worker: SceneWorker | None = None
        self._pending = False
        self.message = ""
        if view_model is None:
            self.setFixedSize(SIZE + SIDE, SIZE)
        else:
            self.setMinimumSize(320 + SIDE, 320)
            view_model.events.settings.connect(self._on_settings)
        self.buttons: dict[str, QToolButton] = {}
        for label, kind, sign, _off in BUTTONS:
            b = QToolButton(self)
            b.setText(label)
            b.clicked.connect(lambda _=False, k=kind, s=sign: self.adjust(k, s * STEPS[k]))
            b.hide()
            self.buttons[label] = b
        document.events.changed.connect(self._on_changed)
        self._render()

    # ------------------------------------------------------------------ main scene
    def scene_size(self) -> tuple[int, int]:
        """(width, height) of the object image: the canvas less the side panel."""
        if self.view_model is None:
            return SIZE, SIZE
        w = max(64, min(MAX_SCENE_PX, self.width() - SIDE))
        h = max(64, min(MAX_SCENE_PX, self.height()))
        return w, h

    def _on_settings(self, _settings) -> None:
        self.refresh_scene()

    def refresh_scene(self) -> None:
        """Recompute the main scene at the current size (one worker at a time; the latest request wins)."""
        if self.view_model is None:
            return
        if self._worker is not None and self._worker.isRunning():
            self._pending = True
            self._worker.requestInterruption()
            return
        self._pending = False
        w, h = self.scene_size()
        self.message = "preparing the scene…"
        self._worker = SceneWorker(self.view_model.settings, w, h)  # owned here, not by the widget
        self._worker.done.connect(self._on_scene)
        self._worker.finished.connect(self._on_worker_finished)
        self._worker.start()
        self.update()

    def _on_scene(self, main: MainScene) -> None:
        if self._pending:  # a newer request is waiting: this scene is already stale
            return
        old = self.main
        self.main = main
        self.scene = main.scene
        self.zoom = self.scene_size()[0] / main.scene.shape[1]
        if self.crosshair is not None and old is not None and old.settings == main.settings:
            # the same scene at another resolution: the crosshair stays on the same spot of the object
            k = main.scene.shape[1] / old.scene.shape[1]
            h, w = main.scene.shape
            x, y = min(w - 1, int(self.crosshair[0] * k)), min(h - 1, int(self.crosshair[1] * k))
            self.crosshair = (x, y) if main.scene.mask[y, x] else None
        else:
            self.crosshair = None
        for b in self.buttons.values():
            b.hide()
        self._place_buttons()
        self.message = "" if self.zoom <= 1.0 else "preview: the full-size scene follows…"
        self._announce = True
        self._render()

    def _on_worker_finished(self) -> None:
        if self._pending:
            self.refresh_scene()

    def wait_idle(self, timeout_ms: int = 60000) -> None:
        """Block until the scene worker (and a queued refresh) has finished (tests, screenshots)."""
        from PySide6.QtCore import QCoreApplication

        while self._worker is not None and (self._worker.isRunning() or self._pending):
            self._worker.wait(timeout_ms)
            QCoreApplication.processEvents()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        if self.view_model is not None and (
            self.main is None or self.main.scene.shape[::-1] != self.scene_size()
        ):
            self.refresh_scene()

    # ------------------------------------------------------------------ drawing
    def _render(self) -> None:
        d = self.document.design
        if self.main is not None:
            rgb = self.main.image(d)
        elif self.view_model is not None:  # the scene is being prepared
            rgb = np.full((*self.scene.shape, 3), 30, np.uint8)
        else:
            rgb = to_uint8(srgb_encode(shade(self.scene, d, background=(0.05, 0.05, 0.06))))
        self._buf = np.ascontiguousarray(rgb)
        h, w = self._buf.shape[:2]
        self._image = QImage(self._buf.data, w, h, 3 * w, QImage.Format.Format_RGB888)
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
        p.save()
        p.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        p.scale(self.zoom, self.zoom)
        p.drawImage(0, 0, self._image)
        theta, mask = self.scene.aspecular_deg, self.scene.mask
        for name, angle in self.rings().items() if self.main is not None or self.view_model is None else ():
            edge = mask & (np.abs(theta - angle) < 0.9)
            ys, xs = np.nonzero(edge)
            p.setPen(QPen(RING_COLOURS[name], 1))
            for x, y in zip(xs[::2], ys[::2], strict=True):
                p.drawPoint(int(x), int(y))
        p.restore()
        side = round(self._image.width() * self.zoom)
        # gloss checkerboard off the object: contrast of the squares ∝ gloss (0–100 GU)
        g = self.document.design.gloss_gu / 100.0
        for i in range(6):
            for j in range(6):
                v = int(128 + (1 if (i + j) % 2 else -1) * 110 * g)
                p.fillRect(side + 20 + 12 * i, 20 + 12 * j, 12, 12, QColor(v, v, v))
        p.setPen(QColor(220, 220, 220))
        p.drawText(side + 20, 104, f"gloss {self.document.design.gloss_gu:.0f} GU")
        y = 124
        for name, col in RING_COLOURS.items():
            p.setPen(col)
            p.drawText(side + 20, y, name)
            y += 16
        if self.message:
            p.setPen(QColor(230, 230, 230))
            p.drawText(12, self.height() - 12, self.message)
        if self.crosshair is not None:
            x, yy = self.crosshair[0] * self.zoom, self.crosshair[1] * self.zoom
            p.setPen(QPen(QColor(255, 255, 255), 1))
            p.drawLine(QPointF(x - 10, yy), QPointF(x + 10, yy))
            p.drawLine(QPointF(x, yy - 10), QPointF(x, yy + 10))
        p.end()
        if self._announce:
            self._announce = False
            self.scenes_shown += 1
            self.scene_shown.emit()

    def _place_buttons(self) -> None:
        if self.crosshair is None:
            return
        x, y = self.crosshair[0] * self.zoom, self.crosshair[1] * self.zoom
        h, w = self.scene.shape[0] * self.zoom, self.scene.shape[1] * self.zoom
        for label, _k, _s, (dx, dy) in BUTTONS:
            b = self.buttons[label]
            b.adjustSize()
            b.move(
                QPoint(
                    int(min(max(x + dx - b.width() / 2, 0), w - b.width())),
                    int(min(max(y + dy - b.height() / 2, 0), h - b.height())),
                )
            )
            b.show()

    # ------------------------------------------------------------------ editing
    def _pixel(self, pos: QPointF) -> tuple[int, int] | None:
        x, y = int(pos.x() / self.zoom), int(pos.y() / self.zoom)
        h, w = self.scene.shape
        if 0 <= x < w and 0 <= y < h and self.scene.mask[y, x]:
            return x, y
        return None

    def adjust(self, kind: Adjustment, delta: float) -> bool:
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
                    delta,
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
                if self.main is not None:
                    self.message = (
                        "the environment lights the object: orbit the 3D view to move the highlight"
                    )
                    self.update()
                    return
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
        if self.view_model is not None:
            self.view_model.events.settings.disconnect(self._on_settings)
        self._pending = False
        if self._worker is not None:
            self._worker.requestInterruption()
            self._worker.wait()
        super().closeEvent(event)


class TweakerScreen(QWidget):
    """The canvas and a short legend (with *view_model*: the 3D view's scene, filling the tab)."""

    def __init__(
        self, document: DesignDocument, view_model: ViewModel | None = None, parent: QWidget | None = None
    ) -> None:
        super().__init__(parent)
        self.canvas = TweakerCanvas(document, view_model)
        help_text = QLabel(
            "Click the object to place the crosshair, then use the buttons around it. Drag the "
            "θ_clamp ring (blue) to set travel, the highlight edge (red) to set gloss"
            + (
                ". The object, camera and environment are the Design view's: change them there."
                if view_model is not None
                else ", the highlight centre to move the light."
            )
        )
        help_text.setWordWrap(True)
        row = QHBoxLayout()
        row.addWidget(self.canvas, 1 if view_model is not None else 0)
        if view_model is None:
            row.addStretch(1)
        lay = QVBoxLayout(self)
        lay.addWidget(help_text)
        lay.addLayout(row, 1)
        if view_model is None:
            lay.addStretch(1)

    def closeEvent(self, event) -> None:
        self.canvas.close()
        super().closeEvent(event)
