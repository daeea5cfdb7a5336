"""The GL display transform's sRGB encoding (``shaders/tonemap.glsl``: a polynomial in x^(1/16) instead
of ``pow``, :data:`station.render.tonemap.SRGB_POLY`) against colour-science's sRGB OETF."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from station.render.gl_programs import srgb_defines
from tests.render.fragment_pass import fragment_pass

WIDTH, ROWS = 4096, 16  # 65,536 values over [0, 1], both segments and the knee


def _glsl_encoded(gl_ctx) -> tuple[np.ndarray, np.ndarray]:
    """(x, srgb_encode(x)) as float32 from the shader, x = i / 65535 for every pixel index i."""
    from station.render.gl_context import load_shader

    defines = "\n".join(f"#define {k} {v}" for k, v in srgb_defines().items())
    frag = "\n".join(
        [
            "#version 430",
            defines,
            "#define CURVE 2",
            load_shader("tonemap.glsl"),
            "out vec4 f_color;",
            "void main() {",
            f"    float i = floor(gl_FragCoord.y) * {WIDTH}.0 + floor(gl_FragCoord.x);",
            f"    float x = i / {WIDTH * ROWS - 1}.0;",
            "    f_color = vec4(srgb_encode(vec3(x)).r, x, 0.0, 1.0);",
            "}",
        ]
    )
    with fragment_pass(gl_ctx, frag, (WIDTH, ROWS)) as fp:
        out = fp.draw().reshape(-1, 4)
    return out[:, 1].astype(float), out[:, 0].astype(float)


@pytest.mark.gl
def test_glsl_srgb_encoding_is_colour_sciences_oetf(gl_ctx) -> None:
    """Within 2.6e-4 of an 8-bit level (1e-6) at 65,536 values in [0, 1]; the 8-bit codes agree but
    where the exact value lies that close to a rounding boundary."""
    x, got = _glsl_encoded(gl_ctx)
    assert x[0] == 0.0 and x[-1] == 1.0 and np.all(np.diff(x) > 0)
    exact = np.asarray(colour.models.eotf_inverse_sRGB(x), dtype=float)
    err = np.abs(got - exact)
    assert err.max() <= 1e-6, f"max error {err.max() * 255:.2e} levels at x = {x[np.argmax(err)]:.6g}"
    codes, codes_exact = np.round(got * 255), np.round(exact * 255)
    boundary = np.abs(exact * 255 - np.floor(exact * 255) - 0.5) < 2e-3
    assert np.all((codes == codes_exact) | boundary)
    # both segments were met: the linear one below the knee and the power one above it
    assert np.sum(x <= 0.0031308) > 100 and np.sum(x > 0.0031308) > 60000
