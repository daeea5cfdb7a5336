"""Errors of the ingest path (rooted at :class:`station.errors.StationError`)."""

from __future__ import annotations

from station.errors import InputError, StationError


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


class ImportFileError(IngestError, InputError):
    """A measurement file (CxF3, CGATS.17, CSV template) that cannot be imported: nothing is stored.

    Names the *file*, the place in it (*where*: ``"line 12"``, ``"element Object[2]/ColorValues"``),
    the *field* and the accepted form, so one line on stderr tells the user what to fix.
    """

    def __init__(self, file: str, where: str, field: str, accepted: str, got: object = None) -> None:
        self.file = file
        self.where = where
        InputError.__init__(self, field, accepted, got, detail=f"{file}, {where}" if where else file)


class UnknownFormatError(ImportFileError):
    """The file is none of the importable formats (by suffix and content)."""


class CxfImportError(ImportFileError):
    """A CxF3 file that is malformed, hostile (DTD, entities) or lacks MultiAngle data."""


class CgatsImportError(ImportFileError):
    """A CGATS.17 ASCII file that is malformed (truncated, missing fields, bad numbers)."""


class CsvImportError(ImportFileError):
    """A file in the station CSV import template that is malformed (docs/import.md)."""


class WorkbookImportError(ImportFileError):
    """An MA-T12-style workbook (.xlsx) that is not a workbook, lacks its sheet or holds bad cells."""


class JsonImportError(ImportFileError):
    """A ``station measure --json`` / ``station import --json`` document that cannot be read back."""
