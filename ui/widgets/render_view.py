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
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from PySide6.QtCore import QPointF, QThread, QTimer, Signal
from PySide6.QtGui import QImage, QMouseEvent, QPainter, QSurfaceFormat, QWheelEvent
from PySide6.QtOpenGL import QOpenGLWindow
from PySide6.QtWidgets import QWidget

from station.render.gl_context import GL_TEXTURE_CUBE_MAP_SEAMLESS
from station.render.numpy_renderer import BACKGROUND
from station.render.prefilter import PrefilteredBasis
from ui.models.view import (
    PREFILTER_MAX_SIZE,
    PREVIEW_PREFILTER_SIZE,
    BasisImages,
    ViewModel,
    ViewSettings,
    environment_ready,
    layer_weights,
)

SHADER_DIR = Path(__file__).resolve().parents[1] / "shaders"
PREVIEW_DIVISOR = 4
ORBIT_DEG_PER_PIXEL = 0.4
#: The GL view starts the basis worker once the view has not changed for this long (ms): during an orbit
#: the worker's NumPy ray cast would take the CPU that llvmpipe draws the frames with.
SETTLE_MS = 250
#: Prefiltered environments a GL view keeps in memory (the current one and the last few).
GL_ENV_KEEP = 4
GL_RGB9_E5 = 0x8C3D

if TYPE_CHECKING:
    import moderngl

    from station.render.gl_renderer import GLRenderer
    from station.render.weights import LobeWeights


def configure_default_format() -> None:
    """Ask for an OpenGL 3.3 core context for every GL widget (call before the QApplication exists)."""
    fmt = QSurfaceFormat()
    fmt.setVersion(3, 3)
    fmt.setProfile(QSurfaceFormat.OpenGLContextProfile.CoreProfile)
    fmt.setSwapInterval(0)
    QSurfaceFormat.setDefaultFormat(fmt)


def composite_program(ctx: moderngl.Context, layers: int) -> moderngl.Program:
    """Compile ``shaders/composite.*.glsl`` for a basis of *layers* cached images."""
    frag = (
        (SHADER_DIR / "composite.frag.glsl")
        .read_text()
        .replace("#version 330", f"#version 330\n#define MAX_LAYERS {layers}", 1)
    )
    return ctx.program(vertex_shader=(SHADER_DIR / "composite.vert.glsl").read_text(), fragment_shader=frag)


def _uniform(prog: moderngl.Program, name: str) -> moderngl.Uniform:
    """The uniform *name* of *prog* (a program member of another kind is a shader error)."""
    import moderngl

    member = prog[name]
    if not isinstance(member, moderngl.Uniform):
        raise TypeError(f"{name}: expected a uniform of the program, got {type(member).__name__}")
    return member


def set_composite_uniforms(
    prog: moderngl.Program,
    basis: BasisImages,
    weights: tuple[LobeWeights, LobeWeights],
    exposure_ev: float,
    viewport: tuple[int, int],
) -> None:
    """Write both paints' per-image weights (:func:`ui.models.view.layer_weights`) and display settings."""
    (a0, b0), (a1, b1) = (layer_weights(basis.layout, w) for w in weights)
    k = len(basis.layout)
    active = [j for j in range(k) if a0[j].any() or b0[j].any() or a1[j].any() or b1[j].any()]
    pad = np.zeros((k - len(active), 3))
    _uniform(prog, "u_n_active").value = len(active)
    _uniform(prog, "u_layer").write(np.array(active + [0] * (k - len(active)), "i4").tobytes())
    for name, arr in (("u_a0", a0), ("u_b0", b0), ("u_a1", a1), ("u_b1", b1)):
        _uniform(prog, name).write(np.concatenate([arr[active], pad]).astype("f4").tobytes())
    _uniform(prog, "u_exposure").value = float(2.0**exposure_ev)
    _uniform(prog, "u_background").value = (BACKGROUND,) * 3
    _uniform(prog, "u_viewport").value = tuple(map(float, viewport))
    _uniform(prog, "u_size").value = basis.size


class BasisWorker(QThread):
    """Computes full-resolution basis images off the GUI thread."""

    done = Signal(object, object)  # (ViewSettings, BasisImages)

    def __init__(
        self,
        settings: ViewSettings,
        width: int,
        height: int,
        env: PrefilteredBasis | None = None,
        parent=None,
    ) -> None:
        super().__init__(parent)
        self.settings, self.width_px, self.height_px, self.env = settings, width, height, env

    def run(self) -> None:
        """Compute and report (from *env* when given, else ``environment_basis``'s NumPy prefilter)."""
        basis = BasisImages.compute(self.settings, self.width_px, self.height_px, env=self.env)
        self.done.emit(self.settings, basis)


class _ViewLogic(QWidget):
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
        self._worker = BasisWorker(settings, w, h, env)
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


class _GLSurface(QOpenGLWindow):
    """The GL surface of a :class:`GLRenderView`: a native child window (``createWindowContainer``), so Qt
    draws it straight to the screen instead of compositing a widget texture into the window."""

    def __init__(self, view: GLRenderView) -> None:
        super().__init__()
        self._view = view

    def paintGL(self) -> None:
        self._view._paint_gl()

    def resizeGL(self, w: int, h: int) -> None:
        self._view._screen = None

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self._view.mousePressEvent(event)

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self._view.mouseMoveEvent(event)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._view.mouseReleaseEvent(event)

    def wheelEvent(self, event: QWheelEvent) -> None:
        self._view.wheelEvent(event)


class GLRenderView(_ViewLogic):
    """The GL view: moderngl on the context of a child :class:`_GLSurface` window (framebuffer =
    ``defaultFramebufferObject()``) for the core's GL frames, and a plain raster widget for paint edits.

    View changes are drawn by the core's GL renderer in the GL surface. Two ways to re-weight the cached
    basis images on a paint edit (``mode``):

    * ``"cpu"`` (default): the core's NumPy edit (weighted sum + tone-map LUT,
      ``station.render.basis_images.BasisImages.edit_rgba``) makes the 8-bit frame, which this widget
      paints as an image while the GL surface is hidden. No GL and no OpenGL compositing is involved: a
      QOpenGLWidget (or any in the window) makes Qt composite the whole window through OpenGL on every
      frame, which on llvmpipe costs more than the edit itself (bench/viewer.py).
    * ``"gpu"``: the basis images live in GPU memory and ``shaders/composite.frag.glsl`` does the sum
      and the display transform per fragment in the GL surface (the path for a real GPU).
    """

    frame_rendered = Signal()
    MODES = ("cpu", "gpu")

    def __init__(self, model: ViewModel, parent: QWidget | None = None, mode: str = "cpu") -> None:
        super().__init__(parent)
        if mode not in self.MODES:
            raise ValueError(f"mode: expected one of {self.MODES}, got {mode!r}")
        self.mode = mode
        self._surface = _GLSurface(self)
        self._container = QWidget.createWindowContainer(self._surface, self)
        self._frame_prog: moderngl.Program | None = None
        self._frame_vao: moderngl.VertexArray | None = None
        self._tex_frame: moderngl.Texture | None = None
        self._frame: np.ndarray | None = None
        self._frame_key: tuple | None = None
        self._init_logic(model)
        self.ctx: moderngl.Context | None = None
        self._prog: moderngl.Program | None = None
        self._vao: moderngl.VertexArray | None = None
        self._vbo: moderngl.Buffer | None = None
        self._tex_basis: moderngl.Texture | None = None
        self._tex_geom: moderngl.Texture | None = None
        self._uploaded: BasisImages | None = None
        self._layers = 0
        self._screen: moderngl.Framebuffer | None = None
        self._screen_id = -1
        self.gl_renderer = ""
        self._core: GLRenderer | None = None  # the core's GLRenderer on this context, for view changes
        self._core_key: tuple | None = None
        self._core_ok = True  # False when the context cannot build the core's shaders (GL < 4.3)
        #: What the level of detail did with the flake layer in the last GL frame (None: flakes off).
        self.flake_report: str | None = None
        self._gl_envs: dict[str, PrefilteredBasis] = {}  # full prefilters made on this context
        self._settle = QTimer(self)
        self._settle.setSingleShot(True)
        self._settle.setInterval(SETTLE_MS)
        self._settle.timeout.connect(self._on_settle)
        self._surface.frameSwapped.connect(self._on_swapped)

    # ---------------------------------------------------------------- GL surface or raster
    def makeCurrent(self) -> None:
        """Make the GL surface's context current."""
        self._surface.makeCurrent()

    def doneCurrent(self) -> None:
        self._surface.doneCurrent()

    def defaultFramebufferObject(self) -> int:
        return self._surface.defaultFramebufferObject()

    def _raster(self) -> bool:
        """Whether the picture is the core's 8-bit edit frame painted by this widget (cpu mode, cached basis
        current or no GL frames) rather than a GL frame in the GL surface."""
        if self.basis is None or self.model.weights() is None:
            return False
        if self.mode == "gpu" and self.basis.core.background is None:
            return False
        if (self.model.settings.flakes or self.model.settings.model is not None) and self._core_ok:
            return False  # flakes and own models are drawn by the core's GL renderer only
        return self.basis_current or not self._core_ok

    def request_frame(self) -> None:
        """Schedule a frame on the path that draws it now (this widget, or the GL surface)."""
        if self._raster():
            if not self._container.isHidden():
                self._container.hide()
            self.update()
        else:
            if self._container.isHidden():
                self._container.show()
            self._surface.update()

    def resizeEvent(self, event) -> None:
        self._container.setGeometry(self.rect())
        self._screen = None
        self._refresh_basis()
        super().resizeEvent(event)

    def _edit_frame(self) -> np.ndarray:
        """The core's 8-bit RGBA edit frame of the current paints (buffer reused while basis and exposure
        stay); only called while :meth:`_raster` holds or the GL path has a basis and a design."""
        basis, weights, ev = self.basis, self.model.weights(), self.model.settings.exposure_ev
        if basis is None or weights is None:
            raise RuntimeError("no edit frame before the first basis images and design")
        key = (id(basis), ev)
        reuse = self._frame if key == self._frame_key else None
        frame = basis.core.edit_rgba(list(weights), ev, out=reuse)
        self._frame, self._frame_key = frame, key
        return frame

    def _paint_raster(self, painter: QPainter, frame: np.ndarray) -> None:
        h, w = frame.shape[:2]
        qimg = QImage(frame.data, w, h, 4 * w, QImage.Format.Format_RGBX8888)
        painter.drawImage(self.rect(), qimg)

    def paintEvent(self, event) -> None:
        if not self._raster():  # the state changed since request_frame(): the GL surface draws
            self.request_frame()
            return
        t0 = time.perf_counter()
        frame = self._edit_frame()
        painter = QPainter(self)
        self._paint_raster(painter, frame)
        painter.end()
        self.frames += 1
        self.last_frame_s = time.perf_counter() - t0
        self.frame_rendered.emit()

    def _gl_frames(self) -> bool:
        return self._core_ok

    def _schedule_worker(self) -> None:
        self._settle.start()  # restarted by every view change: the worker waits for a still view

    def _busy(self) -> bool:
        return self._settle.isActive()

    def _on_swapped(self) -> None:
        """A frame is on screen: the view counts as still from now (llvmpipe finishes the frame while Qt
        composites it, which can outlast SETTLE_MS on a loaded machine)."""
        if self._settle.isActive():
            self._settle.start()

    def _on_settle(self) -> None:
        """The view is still: start the worker on the environment prefiltered on this context."""
        key = self._basis_key
        if key is None or self.basis_current or not self._core_ok:
            return
        if self._worker is not None and self._worker.isRunning():
            return  # its done handler schedules again
        env = self._gl_envs.get(key[0].environment)
        if env is None and self.ctx is not None:  # e.g. an environment change while hidden
            from station.render.errors import RenderError

            self.makeCurrent()
            try:
                env = self._gl_env(key[0].environment)
            except RenderError:  # no GL 4.3 here: the preview path and the NumPy prefilter
                self._core_ok = False
                self._basis_key = None
                self._refresh_basis()
                return
            finally:
                self.doneCurrent()
        if env is None:  # never drawn: the first paintGL prefilters and schedules again
            if self.isVisible():
                self.request_frame()
                self._settle.start()
            return
        self._start_worker(key, env)

    def environment_prefilter(self, env_name: str) -> PrefilteredBasis | None:
        """The full prefilter of *env_name* made on this view's context, or None before its first frame."""
        return self._gl_envs.get(env_name)

    def _gl_env(self, env_name: str) -> PrefilteredBasis:
        """The full prefilter of *env_name* on this context (made now when new; the last GL_ENV_KEEP kept)."""
        from ui.models.view import environment_basis_gl

        basis = self._gl_envs.pop(env_name, None)
        if basis is None:
            basis = environment_basis_gl(env_name, self.ctx)
        self._gl_envs[env_name] = basis  # most recent last
        while len(self._gl_envs) > GL_ENV_KEEP:
            del self._gl_envs[next(iter(self._gl_envs))]
        return basis

    def _build(self) -> moderngl.Context:
        """Create this view's moderngl context on the current GL context and the programs it draws with."""
        import moderngl

        ctx = self.ctx = moderngl.create_context()
        ctx.enable_direct(GL_TEXTURE_CUBE_MAP_SEAMLESS)  # as the core's contexts (gl_context)
        self.gl_renderer = ctx.info["GL_RENDERER"]
        quad = np.array([-1, -1, 1, -1, -1, 1, 1, 1], dtype="f4")
        vbo = self._vbo = ctx.buffer(quad.tobytes())
        if self.basis is not None:  # else built on the first upload (GL frames come first)
            self._prog = composite_program(ctx, len(self.basis.layout))
            self._vao = ctx.vertex_array(self._prog, [(vbo, "2f", "in_pos")])
            self._layers = len(self.basis.layout)
        self._frame_prog = ctx.program(
            vertex_shader=(SHADER_DIR / "composite.vert.glsl").read_text(),
            fragment_shader=(SHADER_DIR / "frame.frag.glsl").read_text(),
        )
        self._frame_vao = ctx.vertex_array(self._frame_prog, [(vbo, "2f", "in_pos")])
        return ctx

    def _upload(
        self, ctx: moderngl.Context, basis: BasisImages
    ) -> tuple[moderngl.Program, moderngl.VertexArray]:
        """Put *basis* in GPU textures (the composite program rebuilt for a new layer count); the program and
        its vertex array."""
        import moderngl

        for t in (self._tex_basis, self._tex_geom):
            if t is not None:
                t.release()
        w, h = basis.size
        if self._prog is None or self._vao is None or self._layers != len(basis.layout):
            if self._prog is not None:
                self._prog.release()
            if self._vao is not None:
                self._vao.release()
            self._prog = composite_program(ctx, len(basis.layout))
            self._vao = ctx.vertex_array(self._prog, [(self._vbo, "2f", "in_pos")])
        self._layers = len(basis.layout)
        layers = basis.layers
        self._tex_basis = ctx.texture(
            (w, h * layers.shape[0]), 3, layers.tobytes(), dtype="f4", internal_format=GL_RGB9_E5
        )
        geom = np.stack([basis.n_dot_v, basis.paint.astype(np.float32)], axis=-1).astype("f2")
        self._tex_geom = ctx.texture((w, h), 2, geom.tobytes(), dtype="f2")
        for t in (self._tex_basis, self._tex_geom):
            t.filter = (moderngl.NEAREST, moderngl.NEAREST)
            t.repeat_x = t.repeat_y = False
        self._uploaded = basis
        return self._prog, self._vao

    def _paint_gl(self, target: moderngl.Framebuffer | None = None) -> None:
        """Draw a frame into the GL surface (its context current), or into the moderngl *target*."""
        t0 = time.perf_counter()
        if self.basis is None:
            self._refresh_basis()
        ctx = self.ctx if self.ctx is not None else self._build()
        if target is not None:
            self._screen, self._screen_id = target, -1
        else:
            fbo = self.defaultFramebufferObject()
            if self._screen is None or self._screen_id != fbo:  # Qt may recreate its FBO (resize)
                self._screen, self._screen_id = ctx.detect_framebuffer(fbo), fbo
        screen = self._screen
        screen.use()
        w, h = self._pixel_size()
        ctx.viewport = (0, 0, w, h)
        weights = self.model.weights()
        flakes_on = self.model.settings.flakes
        model_on = self.model.settings.model is not None  # an own model: drawn by the core only
        if weights is not None and self._core_ok and (flakes_on or model_on or not self.basis_current):
            if self._draw_core_frame(ctx, screen, weights, w, h):
                self._settle.start()  # still means no new view for SETTLE_MS after this frame
                self.frames += 1
                self.gl_frames += 1
                self.last_frame_s = time.perf_counter() - t0
                self.frame_rendered.emit()
                return
        basis = self.basis
        if weights is None or basis is None:
            ctx.clear(BACKGROUND, BACKGROUND, BACKGROUND)
            return
        if self.mode == "cpu" or basis.core.background is not None:  # the stage: per-pixel background
            self._draw_cpu_frame(ctx, basis, w, h)
        else:
            self._draw_gpu(ctx, basis, weights, w, h)
        self.frames += 1  # no glFinish: Qt flushes when it swaps the surface (bench/viewer.py times that)
        self.last_frame_s = time.perf_counter() - t0
        self.frame_rendered.emit()

    def _draw_core_frame(
        self,
        ctx: moderngl.Context,
        screen: moderngl.Framebuffer,
        weights: tuple[LobeWeights, LobeWeights],
        w: int,
        h: int,
    ) -> bool:
        """Draw the current view with the core's GL renderer straight into the widget's framebuffer (full
        resolution, full prefilter made on this context); False when the context cannot."""
        from station.render.errors import RenderError
        from station.render.gl_renderer import GLRenderer

        settings = self.model.settings
        try:
            basis = self._gl_env(settings.environment)
            key = (id(basis), w, h)
            if self._core is None or self._core_key != key:
                if self._core is not None:
                    self._core.release()
                self._core = GLRenderer(basis, w, h, ctx=ctx)
                self._core_key = key
            self._core.draw(
                settings.scene(),
                list(weights),
                settings.exposure_ev,
                coat=settings.clear_coat(),
                flakes=self._flake_layer(),
                target=screen,
                mesh=self.model.mesh(),
            )
            last = self._core.last_flakes
            self.flake_report = None if last is None else last.reason
        except RenderError:  # no GL 4.3 here: fall back to the quarter-resolution preview path
            self._core_ok = False
            self._core = None
            self._basis_key = None
            screen.use()
            self._refresh_basis()
            return False
        self._gl_full_key = self._basis_key
        return True

    @property
    def draws_flakes(self) -> bool:
        """Whether this view can draw the flake layer (the core's GL renderer works on its context)."""
        return self._core_ok

    def _flake_layer(self):
        """The flake layer drawn (``settings.flakes``): the first design's paint-type default with the
        view's size, density and spread put in (:meth:`ViewSettings.flake_layer`), or None."""
        designs = self.model.designs
        if designs is None:
            return None
        return self.model.settings.flake_layer(designs[0])

    def _draw_cpu_frame(self, ctx: moderngl.Context, basis: BasisImages, w: int, h: int) -> None:
        """The edit frame as a texture in the GL surface (the stage in gpu mode; a surface exposed late)."""
        import moderngl

        frame = self._edit_frame()
        bw, bh = basis.size
        tex = self._tex_frame
        if tex is None or tex.size != (bw, bh):
            if tex is not None:
                tex.release()
            tex = self._tex_frame = ctx.texture((bw, bh), 4)
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
        tex.write(frame)
        tex.use(0)
        p, vao = self._frame_prog, self._frame_vao
        if p is None or vao is None:
            raise RuntimeError("the frame program is made by _build before the first frame")
        _uniform(p, "u_frame").value = 0
        _uniform(p, "u_viewport").value = (float(w), float(h))
        _uniform(p, "u_size").value = (bw, bh)
        vao.render(mode=ctx.TRIANGLE_STRIP)

    def _draw_gpu(
        self,
        ctx: moderngl.Context,
        basis: BasisImages,
        weights: tuple[LobeWeights, LobeWeights],
        w: int,
        h: int,
    ) -> None:
        prog, vao = self._prog, self._vao
        if self._uploaded is not basis or prog is None or vao is None:
            prog, vao = self._upload(ctx, basis)
        set_composite_uniforms(prog, basis, weights, self.model.settings.exposure_ev, (w, h))
        for unit, tex in enumerate((self._tex_basis, self._tex_geom)):
            if tex is not None:  # both made by _upload
                tex.use(unit)
        _uniform(prog, "u_basis").value = 0
        _uniform(prog, "u_geom").value = 1
        vao.render(mode=ctx.TRIANGLE_STRIP)

    def grab_image(self) -> np.ndarray:
        """The current frame as (H, W, 3) uint8 at the view's pixel size (renders it, on the path that
        shows it: the raster edit frame, or a GL frame drawn into an offscreen framebuffer)."""
        w, h = self._pixel_size()
        if self._raster():
            img = QImage(w, h, QImage.Format.Format_RGB888)
            painter = QPainter(img)
            frame = self._edit_frame()
            fh, fw = frame.shape[:2]
            painter.drawImage(img.rect(), QImage(frame.data, fw, fh, 4 * fw, QImage.Format.Format_RGBX8888))
            painter.end()
            return (
                np.frombuffer(img.constBits(), np.uint8)
                .reshape(h, img.bytesPerLine())[:, : 3 * w]
                .reshape(h, w, 3)
                .copy()
            )
        if self.ctx is None:  # never drawn yet: show the surface and let it make its context
            self.request_frame()
            from PySide6.QtCore import QCoreApplication

            deadline = time.perf_counter() + 30.0
            while self.ctx is None and time.perf_counter() < deadline:
                QCoreApplication.processEvents()
                time.sleep(0.005)
        ctx = self.ctx
        if ctx is None:
            raise RuntimeError("the GL surface made no context within 30 s of being shown")
        self.makeCurrent()
        try:
            fbo = ctx.simple_framebuffer((w, h), components=4)
            try:
                self._paint_gl(target=fbo)
                pixels = np.frombuffer(fbo.read(viewport=(0, 0, w, h), components=3), np.uint8)
            finally:
                fbo.release()
                self._screen = None
        finally:
            self.doneCurrent()
        return pixels.reshape(h, w, 3)[::-1].copy()

    def close_view(self) -> None:
        """Join the worker and release GPU objects."""
        self._settle.stop()
        self._shutdown()
        if self.ctx is not None:
            self.makeCurrent()
            if self._core is not None:
                self._core.release()
                self._core = None
            for obj in (
                self._vao,
                self._vbo,
                self._prog,
                self._tex_basis,
                self._tex_geom,
                self._frame_vao,
                self._frame_prog,
                self._tex_frame,
            ):
                if obj is not None:
                    obj.release()
            self.ctx = None
            self._screen = None
            self.doneCurrent()

    def closeEvent(self, event) -> None:
        self.close_view()
        super().closeEvent(event)


class ImageRenderView(_ViewLogic):
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
