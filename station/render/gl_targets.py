"""Render targets of :class:`station.render.gl_renderer.GLRenderer` and its anti-aliasing.

Anti-aliasing is supersampling: with ``aa`` = s² samples per pixel (:data:`AA_SAMPLES`) the frame is
shaded at s·W × s·H (every shape is ray-cast in its fragment shader, so multisampled rasterisation
alone would leave their silhouettes hard) and resolved on the GPU into W × H by the box mean of each
s × s block (``shaders/resolve.frag.glsl``): a pixel then holds the mean over its area sampled on a
regular s × s grid, i.e. the edge's pixel coverage to within 1/s² per pixel. ``aa`` = 1 draws at W × H
with no resolve pass. The 8-bit frame is resolved after tone mapping (display-referred, as a
multisample resolve of a display buffer is); the linear frame in linear radiance.
"""

from __future__ import annotations

import math
from typing import Any

from station.render.errors import RenderInputError
from station.render.gl_context import build_program

#: Accepted samples per pixel: an s × s supersampling grid, s = 1..4 (1: no anti-aliasing).
AA_SAMPLES = (1, 4, 9, 16)

#: Samples per pixel of ``station render`` unless ``--aa`` says otherwise.
DEFAULT_AA = 4


def check_aa(aa: object, width: int, height: int, max_size: int) -> int:
    """The grid side s of *aa* samples per pixel; RenderInputError naming ``aa`` when *aa* is not in
    :data:`AA_SAMPLES` or the supersampled frame (s·width × s·height pixels) exceeds *max_size*, the
    context's largest texture / viewport side."""
    if isinstance(aa, bool) or not isinstance(aa, int) or aa not in AA_SAMPLES:
        raise RenderInputError("aa", " | ".join(str(a) for a in AA_SAMPLES) + " samples per pixel", aa)
    side = math.isqrt(aa)
    if side * max(width, height) > max_size:
        largest = max(a for a in AA_SAMPLES if math.isqrt(a) * max(width, height) <= max_size)
        raise RenderInputError("aa", f"<= {largest} at {width}x{height} on this GL context", aa)
    return side


def max_target_size(ctx: Any) -> int:
    """The largest side of a colour target on *ctx* (texture and viewport limits), pixels."""
    info = ctx.info
    viewport = info.get("GL_MAX_VIEWPORT_DIMS", (16384, 16384))
    return int(min(info.get("GL_MAX_TEXTURE_SIZE", 16384), *viewport))


class FrameTargets:
    """The colour (and depth) targets a renderer draws into, at the shading size (s·W × s·H), and the
    W × H output targets the supersampled frame is resolved into; releases them all."""

    def __init__(self, ctx: Any, width: int, height: int, aa: int = 1) -> None:
        self.ctx = ctx
        self.width, self.height = width, height
        self.side = check_aa(aa, width, height, max_target_size(ctx))
        self.aa = aa
        #: The size the frame is shaded at (pixels).
        self.shade_size = (self.side * width, self.side * height)
        self._draw: dict[tuple[bool, bool], tuple] = {}
        self._out: dict[bool, tuple] = {}
        self._resolve: tuple | None = None

    def draw_target(self, linear: bool, depth: bool = False) -> Any:
        """Framebuffer to shade into: float (linear) or 8-bit colour, with a depth buffer for meshes only
        (llvmpipe is slower with one attached)."""
        key = (linear, depth)
        if key not in self._draw:
            tex = self.ctx.texture(self.shade_size, 4, dtype="f4" if linear else "f1")
            rb = self.ctx.depth_renderbuffer(self.shade_size) if depth else None
            fbo = self.ctx.framebuffer(color_attachments=[tex], depth_attachment=rb)
            self._draw[key] = (tex, fbo, rb)
        return self._draw[key][1]

    def output_target(self, linear: bool) -> Any:
        """Framebuffer of the resolved W × H frame (the draw target itself without anti-aliasing)."""
        if self.side == 1:
            return self.draw_target(linear)
        if linear not in self._out:
            tex = self.ctx.texture((self.width, self.height), 4, dtype="f4" if linear else "f1")
            self._out[linear] = (tex, self.ctx.framebuffer(color_attachments=[tex]))
        return self._out[linear][1]

    def resolve(self, src: Any, dst: Any) -> Any:
        """Box-mean each s × s block of framebuffer *src*'s colour into W × H framebuffer *dst*."""
        if self._resolve is None:
            prog = build_program(self.ctx, "fullscreen.vert.glsl", "resolve.frag.glsl", {"FACTOR": self.side})
            self._resolve = (prog, self.ctx.vertex_array(prog, []))
        prog, vao = self._resolve
        dst.use()
        src.color_attachments[0].use(0)
        prog["u_src"].value = 0
        vao.render(mode=self.ctx.TRIANGLES, vertices=3)
        return dst

    def release(self) -> None:
        """Free every target and the resolve program."""
        for tex, fbo, rb in self._draw.values():
            fbo.release()
            tex.release()
            if rb is not None:
                rb.release()
        for tex, fbo in self._out.values():
            fbo.release()
            tex.release()
        if self._resolve is not None:
            self._resolve[1].release()
            self._resolve[0].release()
        self._draw.clear()
        self._out.clear()
        self._resolve = None
