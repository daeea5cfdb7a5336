"""Exceptions of :mod:`station.design`, rooted at :class:`station.errors.StationError`.

``DesignInputError`` is the bad-input branch (it is also a :class:`station.errors.InputError` and a
``ValueError``): it names the field and the accepted range. The other classes are failures of an
operation that was given valid input.
"""

from __future__ import annotations

from station.errors import InputError, StationError


class DesignError(StationError):
    """Base class of every error raised by :mod:`station.design`."""


class DesignInputError(DesignError, InputError):
    """Bad input to a design operation (field, accepted range, value given)."""


class ImageLoadError(DesignInputError):
    """An image file that cannot be loaded safely (format, size cap, decompression bomb, corrupt)."""


class SketchFitError(DesignError):
    """A sketch fit that cannot run at all (no usable pixels); a fit that *fails* is flagged instead."""
