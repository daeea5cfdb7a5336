"""Exceptions of :mod:`station.formulate`, rooted at :class:`station.errors.StationError`.

Bad input (a malformed library row, a hostile XML file, an out-of-range concentration) raises a
subclass of :class:`station.errors.InputError`, so every front shows the field and the accepted range.
"""

from __future__ import annotations

from station.errors import InputError, StationError


class FormulateError(StationError):
    """Base class of every error raised by :mod:`station.formulate`."""


class FormulateInputError(FormulateError, InputError):
    """Bad input to a formulation function (field, accepted range, value given)."""


class LibraryFormatError(FormulateInputError):
    """A library file (CSV or CxF3) breaks the format: names the row, the column and the accepted range.

    ``row`` is 1-based and counts the header as row 1 (what a spreadsheet shows); ``column`` is the
    header name. Either may be ``None`` when the fault is in the file as a whole.
    """

    def __init__(
        self, row: int | None, column: str | None, accepted: str, got: object = None, detail: str = ""
    ) -> None:
        self.row = row
        self.column = column
        where = []
        if row is not None:
            where.append(f"row {row}")
        if column is not None:
            where.append(f"column {column!r}")
        field = ", ".join(where) if where else "file"
        super().__init__(field, accepted, got, detail)


class XMLFormatError(FormulateInputError):
    """An XML file (thesis colour XML or CxF3) is malformed or breaks its schema."""


class HostileXMLError(XMLFormatError):
    """An XML file uses a construct that is refused on principle (DTD, entities, external references,
    or a size past the limit), whether or not it would have been harmless."""


class NotFormulableError(FormulateError):
    """Raised only where a caller asked for a recipe that must meet a tolerance (``strict=True``)."""
