"""State handling shared by both render views (:class:`ui.widgets.gl_render_view.GLRenderView` and
:class:`ui.widgets.render_view.ImageRenderView`): the cached basis images and the worker QThread that
computes them at full resolution, the quarter-resolution preview, and the mouse orbit and zoom.

Mouse: left drag orbits (yaw/pitch), the wheel zooms.
"""

from __future__ import annotations

import time

from PySide6.QtCore import QPointF, Signal
from PySide6.QtGui import QMouseEvent, QWheelEvent
from PySide6.QtWidgets import QWidget

from station.render.prefilter import PrefilteredBasis
from ui.models.view import (
    PREFILTER_MAX_SIZE,
    PREVIEW_PREFILTER_SIZE,
    VIEW_AA,
    BasisImages,
    ViewModel,
    ViewSettings,
    environment_ready,
)
from ui.widgets.tasks import GcPausingThread

PREVIEW_DIVISOR = 4
ORBIT_DEG_PER_PIXEL = 0.4


class BasisWorker(GcPausingThread):
    """Computes full-resolution basis images off the GUI thread."""

    done = Signal(object, object)  # (ViewSettings, BasisImages)

    def __init__(
        self,
        settings: ViewSettings,
        width: int,
        height: int,
        env: PrefilteredBasis | None = None,
        parent=None,
        aa: int = VIEW_AA,
    ) -> None:
        super().__init__(parent)
        self.settings, self.width_px, self.height_px, self.env = settings, width, height, env
        self.aa = aa

    def run(self) -> None:
        """Compute and report (from *env* when given, else ``environment_basis``'s NumPy prefilter), edge
        pixels supersampled at ``aa`` samples per pixel."""
        basis = BasisImages.compute(self.settings, self.width_px, self.height_px, env=self.env, aa=self.aa)
        self.done.emit(self.settings, basis)


class ViewLogic(QWidget):
    """Shared state handling of both views (mouse orbit, basis refresh, worker)."""

    def _init_logic(self, model: ViewModel) -> None:
        self.model = model
        self.basis: BasisImages | None = None
        self._basis_key: tuple | None = None
        self._worker: BasisWorker | None = None
        self._pending: tuple | None = None
        self._drag: QPointF | None = None
        self.frames = 0
        self.last_frame_s = 0.0
        self._basis_settings: ViewSettings | None = None
        self._gl_full_key: tuple | None = None
        self.gl_frames = 0  # frames drawn by the core's GL renderer
        #: Samples per pixel of the final frames (:data:`ui.models.view.VIEW_AA`; 1: no anti-aliasing).
        self.aa = VIEW_AA
        self.setMinimumSize(160, 120)
        model.events.settings.connect(self._on_settings)
        model.events.paints.connect(self._on_paints)

    # ---------------------------------------------------------------- basis images
    def _pixel_size(self) -> tuple[int, int]:
        r = self.devicePixelRatioF()
        return max(8, round(self.width() * r)), max(8, round(self.height() * r))

    def _gl_frames(self) -> bool:
        """Whether view changes are drawn by the core's GL renderer until the basis is ready (GL view)."""
        return False

    def _refresh_basis(self) -> None:
        """Preview now (quarter size; coarse prefilter until the full one is in memory), full in the worker;
        with GL frames no preview: the core's GL renderer draws the view until the worker is done."""
        w, h = self._pixel_size()
        key = (self.model.settings, w, h)
        if key == self._basis_key:
            return
        self._basis_key = key
        if self._gl_frames():
            self._schedule_worker()
            return
        pw, ph = max(8, w // PREVIEW_DIVISOR), max(8, h // PREVIEW_DIVISOR)
        env = self.model.settings.environment
        size = PREFILTER_MAX_SIZE if environment_ready(env) else PREVIEW_PREFILTER_SIZE
        self._set_basis(BasisImages.compute(self.model.settings, pw, ph, size))
        self._start_worker(key)

    @property
    def basis_current(self) -> bool:
        """Whether the cached basis is the final one (full resolution, full prefilter) for the current view."""
        b = self.basis
        return (
            b is not None
            and self._basis_key is not None
            and self._basis_settings in (None, self._basis_key[0])
            and b.prefilter_size == PREFILTER_MAX_SIZE
            and b.size == self._basis_key[1:]
        )

    @property
    def full_quality(self) -> bool:
        """Whether the picture shown is final for the current view: the current basis, or a full-resolution
        frame of the core's GL renderer from the full prefilter."""
        return self.basis_current or (self._gl_full_key is not None and self._gl_full_key == self._basis_key)

    def _schedule_worker(self) -> None:
        """GL frames: start the worker for the current key later (GLRenderView)."""

    def _start_worker(self, key: tuple, env: PrefilteredBasis | None = None) -> None:
        if self._worker is not None and self._worker.isRunning():
            self._pending = key
            return
        settings, w, h = key
        self._worker = BasisWorker(settings, w, h, env, aa=self.aa)
        self._worker.done.connect(self._on_worker_done)
        self._worker.start()

    def _on_worker_done(self, settings: ViewSettings, basis: BasisImages) -> None:
        if (
            self._basis_key is not None
            and self._basis_key[0] == settings
            and basis.size == self._basis_key[1:]
        ):
            self._basis_settings = settings
            self._set_basis(basis)
        if self._worker is not None:
            self._worker.wait()
        if self._gl_frames():  # a stale result: start again once the view is still
            self._pending = None
            if not self.basis_current:
                self._schedule_worker()
        elif self._pending is not None:
            key, self._pending = self._pending, None
            self._start_worker(key)

    def wait_idle(self, timeout_ms: int = 30000) -> None:
        """Block until no basis computation is running (tests, screenshots)."""
        from PySide6.QtCore import QCoreApplication

        deadline = time.perf_counter() + timeout_ms / 1000
        while time.perf_counter() < deadline:
            QCoreApplication.processEvents()
            if (
                (self._worker is None or self._worker.isFinished())
                and self._pending is None
                and not self._busy()
            ):
                QCoreApplication.processEvents()
                return
            time.sleep(0.005)

    def _busy(self) -> bool:
        """Whether a worker start is still scheduled (GLRenderView's settle timer)."""
        return False

    def _shutdown(self) -> None:
        self.model.events.disconnect_all(self)
        self._pending = None
        if self._worker is not None:
            self._worker.wait()
            self._worker = None

    def _set_basis(self, basis: BasisImages) -> None:
        self.basis = basis
        self.request_frame()

    def request_frame(self) -> None:
        """Schedule a frame on the path that draws it (this widget by default)."""
        self.update()

    def _on_settings(self, settings: ViewSettings) -> None:
        self._refresh_basis()
        self.request_frame()

    def _on_paints(self, pair: object) -> None:
        self.request_frame()

    # ---------------------------------------------------------------- mouse
    def mousePressEvent(self, event: QMouseEvent) -> None:
        self._drag = event.position()

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        if self._drag is None:
            return
        d = event.position() - self._drag
        self._drag = event.position()
        s = self.model.settings
        pitch = max(-80.0, min(80.0, s.pitch_deg + d.y() * ORBIT_DEG_PER_PIXEL))
        self.model.update(yaw_deg=(s.yaw_deg - d.x() * ORBIT_DEG_PER_PIXEL) % 360.0, pitch_deg=pitch)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._drag = None

    def wheelEvent(self, event: QWheelEvent) -> None:
        s = self.model.settings
        z = s.zoom * (1.1 ** (event.angleDelta().y() / 120.0))
        self.model.update(zoom=max(0.5, min(4.0, z)))
