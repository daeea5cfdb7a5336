"""A full-screen pass of a test's own fragment shader (``shaders/fullscreen.vert.glsl`` under it) into a
float RGBA target: how the tests run a GLSL function of the renderer's shaders on chosen inputs."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np


class FragmentPass:
    """The program and its target (:func:`fragment_pass`): set uniforms on :attr:`prog`, then
    :meth:`draw`."""

    def __init__(self, ctx: Any, fragment: str, size: tuple[int, int]) -> None:
        from station.render.gl_context import load_shader

        self.size = size
        self.prog = ctx.program(vertex_shader=load_shader("fullscreen.vert.glsl"), fragment_shader=fragment)
        self.vao = ctx.vertex_array(self.prog, [])
        self.tex = ctx.texture(size, 4, dtype="f4")
        self.fbo = ctx.framebuffer(color_attachments=[self.tex])

    def draw(self) -> np.ndarray:
        """Draw the pass and read its target: (height, width, 4) float32, row 0 at gl_FragCoord.y 0.5."""
        self.fbo.use()
        self.vao.render(vertices=3)
        data = np.frombuffer(self.fbo.read(components=4, dtype="f4"), np.float32)
        return data.reshape(self.size[1], self.size[0], 4)

    def release(self) -> None:
        for obj in (self.fbo, self.tex, self.vao, self.prog):
            obj.release()


@contextmanager
def fragment_pass(ctx: Any, fragment: str, size: tuple[int, int]) -> Iterator[FragmentPass]:
    """A :class:`FragmentPass` of the fragment shader source *fragment* on *ctx* over a target of *size*
    (width, height) pixels, released on the way out."""
    p = FragmentPass(ctx, fragment, size)
    try:
        yield p
    finally:
        p.release()
