"""Exceptions of :mod:`station.reproduce` (one hierarchy, rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import InputError, StationError


class ReproduceError(StationError):
    """Base class of every error raised while reproducing a thesis experiment."""


class ReproduceInputError(InputError, ReproduceError):
    """Invalid reproduction request (unknown figure, bad option); names the field and the accepted values."""
