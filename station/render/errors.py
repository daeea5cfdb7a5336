"""Errors of ``station.render``: one hierarchy rooted at :class:`station.errors.StationError`."""

from __future__ import annotations

from station.errors import InputError, StationError


class RenderError(StationError):
    """Something in the rendering pipeline failed (GL context, shader compile, cache I/O)."""


class GLUnavailableError(RenderError):
    """No OpenGL context could be created (no EGL, no Mesa DRI driver)."""


class RenderInputError(RenderError, InputError):
    """Bad rendering parameter (size, exponent, shape name, weights): names the field and range."""


class EnvironmentFileError(RenderError, InputError):
    """An environment file is not a usable HDR image: LDR, truncated, malformed or absurd values.

    ``field`` is the file path, ``accepted`` says what a valid file is, ``detail`` what was wrong.
    """

    def __init__(self, path: object, accepted: str, detail: str) -> None:
        super().__init__(str(path), accepted, None, detail)
        self.path = path
        self.detail = detail
