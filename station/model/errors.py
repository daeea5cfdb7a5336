"""Exceptions of :mod:`station.model`."""

from __future__ import annotations

from station.errors import InputError, StationError


class ModelError(StationError):
    """Base class of every error raised by the appearance model."""


class ModelInputError(InputError, ModelError):
    """Invalid model input; names the field and the accepted range."""


class FitError(ModelError):
    """A fit could not produce a defined answer (the message says why)."""
