"""Fixtures of the renderer suite: a GL context when one can be made (tests that need it skip otherwise,
and fail under ``CI=true``: ``tests.services.service_missing``)."""

from __future__ import annotations

import pytest

from station.render.errors import GLUnavailableError
from station.render.gl_renderer import create_gl_context
from tests.services import service_missing


@pytest.fixture(scope="session")
def gl_ctx():
    """One shared headless EGL context for the session (released at the end)."""
    try:
        ctx = create_gl_context()
    except GLUnavailableError as exc:
        service_missing(f"no OpenGL context: {exc}")
    yield ctx
    ctx.release()
