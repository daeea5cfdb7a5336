"""Errors of the scan path, rooted at :class:`station.errors.StationError`."""

from __future__ import annotations

from station.errors import InputError, StationError

__all__ = ["ScanError", "ScanInputError"]


class ScanError(StationError):
    """Base of every error the scan path raises itself (drivers and ingest raise their own)."""


class ScanInputError(ScanError, InputError):
    """A bad argument to the scan path: names the field (``device``, ``gloss_device``, ``instrument``…),
    the accepted values and what was given."""
