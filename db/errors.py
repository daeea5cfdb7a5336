"""Errors raised by the database layer (rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import StationError


class DatabaseError(StationError):
    """Base class of database-layer errors."""


class ImmutableRowError(DatabaseError):
    """An attempt to update or delete an append-only row (a measurement)."""


class DatabaseUnavailableError(DatabaseError, ConnectionError):
    """The database cannot be reached (ingest falls back to its outbox)."""


class MigrationError(DatabaseError):
    """The schema is not at the revision this code expects, or a migration failed."""


class TamperedError(DatabaseError):
    """A hash chain over the append-only tables does not recompute: rows were changed, removed or added."""
