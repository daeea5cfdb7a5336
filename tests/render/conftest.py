"""Fixtures of the renderer suite: a GL context when one can be made (tests marked ``gl`` skip otherwise)."""

from __future__ import annotations

import pytest

from station.render.errors import GLUnavailableError
from station.render.gl_renderer import create_gl_context


@pytest.fixture(scope="session")
def gl_ctx():
    """One shared headless EGL context for the session (released at the end)."""
    try:
        ctx = create_gl_context()
    except GLUnavailableError as exc:
        pytest.skip(f"no OpenGL context: {exc}")
    yield ctx
    ctx.release()
