"""The 3D view: the core's GL frames while the view changes, cached basis images re-weighted by the paint.

A camera, shape, environment or size change recomputes the basis images (NumPy, the core's ray
caster and prefiltered maps) in a worker QThread (joined on close). Meanwhile the GL view draws every
frame with the core's GL renderer (:class:`station.render.gl_renderer.GLRenderer` on the widget's own
context, straight into the framebuffer of a child GL window, full resolution, full prefilter): orbiting is at full
quality from the first frame. The environment is prefiltered on the same context
(:func:`ui.models.view.environment_basis_gl`, one render-to-texture pass per lobe), so an environment
change reaches full quality in about a second, cold cache included. The worker starts only once the
view has been still for ``SETTLE_MS`` (it would take the CPU llvmpipe draws the orbit with); paint
edits switch to its cached basis images as soon as it has them. Without a GL 4.3 context (and in
:class:`ImageRenderView`) a view change shows a quarter-resolution preview of the basis images in the
GUI thread instead, then full resolution from the worker; on a cold prefilter cache that preview is
rendered from a coarse NumPy prefilter of the same environment (``PREVIEW_PREFILTER_SIZE`` faces,
~0.1 s) while the worker makes the full one (docs/viewer.md). A paint edit re-weights the cached images
(the core's NumPy edit painted as an image, the GL window hidden; gpu mode: new weights for the fragment
shader), so the picture follows the mouse. :class:`ImageRenderView` is the same view without GL (the NumPy
composite drawn as a QImage) for platforms that have no OpenGL (Qt's offscreen QPA).

Mouse: left drag orbits (yaw/pitch), the wheel zooms.

Modules
-------
This module holds the image view, the factory and the GL format, and gathers the public names: the
shared state, worker and mouse orbit are in :mod:`ui.widgets.view_logic`, the GL view in
:mod:`ui.widgets.gl_render_view`, the GL composite of the basis images in :mod:`ui.widgets.gl_composite`.
"""

from __future__ import annotations

import os
import time

import numpy as np
from PySide6.QtCore import Signal
from PySide6.QtGui import QImage, QPainter, QSurfaceFormat
from PySide6.QtWidgets import QWidget

from station.render.gl_context import GL_RGB9_E5
from station.render.numpy_renderer import BACKGROUND
from ui.models.view import ViewModel
from ui.widgets.gl_composite import SHADER_DIR, composite_program, set_composite_uniforms
from ui.widgets.gl_render_view import GL_ENV_KEEP, SETTLE_MS, GLRenderView
from ui.widgets.view_logic import ORBIT_DEG_PER_PIXEL, PREVIEW_DIVISOR, BasisWorker, ViewLogic

__all__ = [
    "GL_ENV_KEEP",
    "GL_RGB9_E5",
    "ORBIT_DEG_PER_PIXEL",
    "PREVIEW_DIVISOR",
    "SETTLE_MS",
    "SHADER_DIR",
    "BasisWorker",
    "GLRenderView",
    "ImageRenderView",
    "composite_program",
    "configure_default_format",
    "gl_supported",
    "make_render_view",
    "set_composite_uniforms",
]


#: Milliseconds Qt's platform window waits before it delivers a requested frame (its
#: ``QT_QPA_UPDATE_IDLE_TIME``, 5 by default): 0, so a view change reaches the screen as soon as the event
#: loop is free; llvmpipe's threads would otherwise sit idle for that long on every orbit frame.
UPDATE_IDLE_MS = 0


def configure_default_format() -> None:
    """Ask for an OpenGL 3.3 core context for every GL widget, without vertical sync, and frames delivered
    without Qt's idle wait (:data:`UPDATE_IDLE_MS`, unless the environment sets ``QT_QPA_UPDATE_IDLE_TIME``).
    Call before the QApplication exists: Qt reads the wait once, at the first frame requested."""
    os.environ.setdefault("QT_QPA_UPDATE_IDLE_TIME", str(UPDATE_IDLE_MS))
    fmt = QSurfaceFormat()
    fmt.setVersion(3, 3)
    fmt.setProfile(QSurfaceFormat.OpenGLContextProfile.CoreProfile)
    fmt.setSwapInterval(0)
    QSurfaceFormat.setDefaultFormat(fmt)


class ImageRenderView(ViewLogic):
    """The same view drawn from the NumPy composite (no GL); used where Qt has no OpenGL."""

    frame_rendered = Signal()
    #: Flakes are drawn by the core's GL renderer only.
    draws_flakes = False
    flake_report: str | None = None

    def __init__(self, model: ViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._init_logic(model)
        self.gl_renderer = "none (NumPy composite)"
        self._image: np.ndarray | None = None

    def resizeEvent(self, event) -> None:
        self._refresh_basis()
        super().resizeEvent(event)

    def render_image(self) -> np.ndarray | None:
        """The current frame (H, W, 3) uint8 at basis resolution, or None before the first design."""
        weights = self.model.weights()
        if self.basis is None:
            self._refresh_basis()
        if weights is None or self.basis is None:
            return None
        return self.basis.core.edit(list(weights), self.model.settings.exposure_ev)

    def paintEvent(self, event) -> None:
        t0 = time.perf_counter()
        painter = QPainter(self)
        img = self.render_image()
        if img is None:
            g = round(255 * BACKGROUND)
            painter.fillRect(self.rect(), _grey(g))
        else:
            self._image = np.ascontiguousarray(img)
            h, w = img.shape[:2]
            qimg = QImage(self._image.data, w, h, 3 * w, QImage.Format.Format_RGB888)
            painter.drawImage(self.rect(), qimg)
        painter.end()
        self.frames += 1
        self.last_frame_s = time.perf_counter() - t0
        self.frame_rendered.emit()

    def close_view(self) -> None:
        """Join the worker."""
        self._shutdown()

    def closeEvent(self, event) -> None:
        self.close_view()
        super().closeEvent(event)


def _grey(v: int):
    from PySide6.QtGui import QColor

    return QColor(v, v, v)


def gl_supported() -> bool:
    """Whether the running Qt platform can give widgets an OpenGL context."""
    from PySide6.QtGui import QGuiApplication

    return QGuiApplication.platformName() not in ("offscreen", "minimal", "vnc")


def make_render_view(
    model: ViewModel, parent: QWidget | None = None, mode: str = "cpu"
) -> GLRenderView | ImageRenderView:
    """The GL view where the platform has OpenGL, else the NumPy image view."""
    return GLRenderView(model, parent, mode) if gl_supported() else ImageRenderView(model, parent)
