"""The GL render view: the core's GL frames while the view changes, cached basis images re-weighted by the
paint (the method is described in :mod:`ui.widgets.render_view`).

:class:`GLRenderView` draws with moderngl on the context of a child :class:`_GLSurface` window; the basis
worker starts once the view has been still for ``SETTLE_MS``; the environment is prefiltered on the same
context and the last ``GL_ENV_KEEP`` prefilters are kept.
"""

from __future__ import annotations

import time
import weakref
from typing import TYPE_CHECKING

import numpy as np
from PySide6.QtCore import QTimer, Signal
from PySide6.QtGui import QImage, QMouseEvent, QPainter, QWheelEvent
from PySide6.QtOpenGL import QOpenGLWindow
from PySide6.QtWidgets import QWidget

from station.render.gl_context import GL_RGB9_E5, prepare_context
from station.render.numpy_renderer import BACKGROUND
from station.render.prefilter import PrefilteredBasis
from ui.models.view import BasisImages, ViewModel
from ui.widgets.gl_composite import SHADER_DIR, composite_program, set_composite_uniforms, uniform
from ui.widgets.tasks import collector_paused
from ui.widgets.view_logic import ViewLogic

#: The GL view starts the basis worker once the view has not changed for this long (ms): during an orbit
#: the worker's NumPy ray cast would take the CPU that llvmpipe draws the frames with.
SETTLE_MS = 250
#: Prefiltered environments a GL view keeps in memory (the current one and the last few).
GL_ENV_KEEP = 4

if TYPE_CHECKING:
    import moderngl

    from station.render.gl_renderer import GLRenderer
    from station.render.weights import LobeWeights


def _same_key(held: tuple | None, key: tuple) -> bool:
    """Whether a cache keyed by *held* serves *key*: the same object first (compared by identity, not by
    its id, which a later object could take) and equal remaining fields."""
    return held is not None and held[0] is key[0] and held[1:] == key[1:]


class _GLSurface(QOpenGLWindow):
    """The GL surface of a :class:`GLRenderView`: a native child window (``createWindowContainer``), so Qt
    draws it straight to the screen instead of compositing a widget texture into the window."""

    def __init__(self, view: GLRenderView) -> None:
        super().__init__()
        # A weak reference: a strong one made a cycle (view -> surface -> view), so a closed view was
        # freed only by the cyclic collector, at whatever allocation triggered it, and a view closed
        # before another opened crashed the next one's paint (SIGSEGV in QOpenGLContext::isValid).
        self._view = weakref.ref(view)

    def paintGL(self) -> None:
        view = self._view()
        if view is not None:
            with collector_paused():  # no collection inside the frame's GL work (ui.widgets.tasks)
                view._paint_gl()

    def resizeGL(self, w: int, h: int) -> None:
        view = self._view()
        if view is not None:
            view._screen = None

    def _forward(self, handler: str, event: QMouseEvent | QWheelEvent) -> None:
        """Hand *event* to the view's *handler* (none once the view is gone)."""
        view = self._view()
        if view is not None:
            getattr(view, handler)(event)

    def mousePressEvent(self, event: QMouseEvent) -> None:
        self._forward("mousePressEvent", event)

    def mouseMoveEvent(self, event: QMouseEvent) -> None:
        self._forward("mouseMoveEvent", event)

    def mouseReleaseEvent(self, event: QMouseEvent) -> None:
        self._forward("mouseReleaseEvent", event)

    def wheelEvent(self, event: QWheelEvent) -> None:
        self._forward("wheelEvent", event)


class GLRenderView(ViewLogic):
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
        #: Whether the view has been still for SETTLE_MS: a GL frame is then supersampled (``aa``).
        self._still = False
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
        key = (basis, ev)
        reuse = self._frame if _same_key(self._frame_key, key) else None
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

    def _on_settings(self, settings) -> None:
        self._still = False  # a view or scene change: shaded once per pixel until still again
        super()._on_settings(settings)

    def _on_settle(self) -> None:
        """The view is still: redraw a GL frame the view stays on supersampled (``aa``), and start the
        worker on the environment prefiltered on this context."""
        if not self._still and self.aa > 1 and self._core_ok and self._core is not None:
            self._still = True
            if not self._raster():
                self.request_frame()
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
        prepare_context(ctx)  # as the core's contexts (gl_context)
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
            key = (basis, w, h)
            if self._core is None or not _same_key(self._core_key, key):
                if self._core is not None:
                    self._core.release()
                self._core = GLRenderer(basis, w, h, ctx=ctx)
                self._core_key = key
            self._core.set_aa(self.aa if self._still else 1)
            flakes, mesh = self._flake_layer(), self.model.mesh()
            # A ray-cast shape without flakes is shown from the cached basis images once they are ready,
            # whose object is unshadowed and whose ground is the NumPy stage's, shadowed by the shape
            # itself: the GL frames before them shadow the ground alone, so neither the object nor the
            # shape of its shadow changes when the cache takes over.
            self._core.shadows = True
            self._core.object_shadows = mesh is not None or flakes is not None
            self._core.draw(
                settings.scene(),
                list(weights),
                settings.exposure_ev,
                coat=settings.clear_coat(),
                flakes=flakes,
                target=screen,
                mesh=mesh,
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
        uniform(p, "u_frame").value = 0
        uniform(p, "u_viewport").value = (float(w), float(h))
        uniform(p, "u_size").value = (bw, bh)
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
        uniform(prog, "u_basis").value = 0
        uniform(prog, "u_geom").value = 1
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
                with collector_paused():
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
