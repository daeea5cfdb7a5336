"""Exceptions of :mod:`station.qc` (one hierarchy, rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import InputError, StationError


class QcError(StationError):
    """Base class of every error raised by colour QC (jobs, standards, repeats, reports)."""


class QcInputError(InputError, QcError):
    """Invalid QC input (a reading, a file, a job or part, a report option); names the field and range."""


class StandardMissingError(QcInputError):
    """A job and part has no standard to judge its samples against."""
