"""Errors of the ingest path (rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import StationError


class IngestError(StationError):
    """Base class of ingest errors."""


class ClientIdConflictError(IngestError):
    """A reading reuses a client id already stored with a different payload (hash mismatch)."""

    def __init__(self, client_id: str, stored_sha256: str, got_sha256: str) -> None:
        self.client_id = client_id
        super().__init__(
            f"client_id {client_id} already stored with payload sha256 {stored_sha256[:12]}…, "
            f"this reading has {got_sha256[:12]}…"
        )


class ReferenceNotFoundError(IngestError, LookupError):
    """A reading names a panel (or other row) that does not exist."""


class DestinationUnreachableError(IngestError):
    """The database or service that stores readings is away: the reading stays queued in the outbox."""


class ReadingRefusedError(IngestError):
    """The destination refused the reading (not unreachable: refused), e.g. HTTP 4xx from a service."""
