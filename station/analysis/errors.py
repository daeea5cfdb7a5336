"""Exceptions of :mod:`station.analysis` (one hierarchy, rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import InputError, StationError


class AnalysisError(StationError):
    """Base class of every error raised by the misalignment analysis."""


class AnalysisInputError(InputError, AnalysisError):
    """Invalid analysis input; names the field and the accepted range."""
