"""The renderers' GL contexts (station.render.gl_context.prepare_context)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.render.fragment_pass import fragment_pass

FRAGMENT = """#version 430
uniform sampler2D u_tex;
out vec4 f_color;
void main() { f_color = texelFetch(u_tex, ivec2(0, 0), 0); }
"""


@pytest.mark.gl
def test_a_texture_made_mid_frame_leaves_the_frames_units_bound(gl_ctx) -> None:
    """A frame binds a texture at unit 31 (in the range its shadow and light maps use), then a texture is
    made and written: the program still reads the frame's texture. With moderngl's default scratch unit
    (31) the new texture would be read instead."""
    assert gl_ctx.default_texture_unit == gl_ctx.info["GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS"] - 1
    frames = gl_ctx.texture((1, 1), 4, np.full(4, 1.0, np.float32).tobytes(), dtype="f4")
    made = None
    try:
        with fragment_pass(gl_ctx, FRAGMENT, (1, 1)) as fp:
            frames.use(31)
            fp.prog["u_tex"].value = 31
            made = gl_ctx.texture((1, 1), 4, np.full(4, 2.0, np.float32).tobytes(), dtype="f4")
            made.write(np.full(4, 3.0, np.float32).tobytes())
            assert fp.draw().ravel().tolist() == [1.0] * 4
    finally:
        frames.release()
        if made is not None:
            made.release()
