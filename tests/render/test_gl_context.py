"""The renderers' GL contexts (station.render.gl_context.prepare_context)."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.mark.gl
def test_a_texture_made_mid_frame_leaves_the_frames_units_bound(gl_ctx) -> None:
    """A frame binds a texture at unit 31 (in the range its shadow and light maps use), then a texture is
    made and written: the program still reads the frame's texture. With moderngl's default scratch unit
    (31) the new texture would be read instead."""
    from station.render.gl_context import load_shader

    assert gl_ctx.default_texture_unit == gl_ctx.info["GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS"] - 1
    frag = "\n".join(
        [
            "#version 430",
            "uniform sampler2D u_tex;",
            "out vec4 f_color;",
            "void main() { f_color = texelFetch(u_tex, ivec2(0, 0), 0); }",
        ]
    )
    prog = gl_ctx.program(vertex_shader=load_shader("fullscreen.vert.glsl"), fragment_shader=frag)
    vao = gl_ctx.vertex_array(prog, [])
    frames = gl_ctx.texture((1, 1), 4, np.full(4, 1.0, np.float32).tobytes(), dtype="f4")
    out = gl_ctx.texture((1, 1), 4, dtype="f4")
    fbo = gl_ctx.framebuffer(color_attachments=[out])
    made = None
    try:
        frames.use(31)
        prog["u_tex"].value = 31
        made = gl_ctx.texture((1, 1), 4, np.full(4, 2.0, np.float32).tobytes(), dtype="f4")
        made.write(np.full(4, 3.0, np.float32).tobytes())
        fbo.use()
        vao.render(vertices=3)
        assert np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).tolist() == [1.0] * 4
    finally:
        for obj in (fbo, out, frames, made, vao, prog):
            if obj is not None:
                obj.release()
