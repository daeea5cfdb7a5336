"""Vendor measurement files as measurement sources: CxF3, CGATS.17, MA-T12 workbooks, the CSV template.

No automotive multi-angle instrument publishes a wire protocol, so labs integrate through the files
their instrument software writes. :func:`read_measurement_file` reads any of the three formats
(and the MA-T12-style ``.xlsx`` workbook; chosen by suffix, else by content) into an :class:`ImportedFile` of validated
:class:`ImportedMeasurement`; :func:`readings_from_import` turns them into ingest
:class:`~station.ingest.Reading` records that go through the one ingest path
(:class:`~station.ingest.Ingestor`); :func:`write_measurement_file` writes the same formats (the
simulators use it, so every importer round-trips). docs/import.md documents the formats.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import Final

from station.ingest.errors import (
    CgatsImportError,
    CsvImportError,
    CxfImportError,
    ImportFileError,
    JsonImportError,
    UnknownFormatError,
    WorkbookImportError,
)
from station.ingest.formats import cgats, csv_template, cxf, measure_json, workbook
from station.ingest.formats._text import read_bytes
from station.ingest.formats.cgats import read_cgats, write_cgats
from station.ingest.formats.csv_template import read_csv, write_csv
from station.ingest.formats.cxf import read_cxf, write_cxf
from station.ingest.formats.measure_json import read_measure_json
from station.ingest.formats.measurement import (
    ImportedFile,
    ImportedMeasurement,
    Instrument,
    VendorValue,
    build_measurement,
    lab_of,
)
from station.ingest.formats.records import ImportOptions, import_client_id, readings_from_import
from station.ingest.formats.workbook import read_workbook, write_workbook

__all__ = [
    "FORMATS",
    "CgatsImportError",
    "CsvImportError",
    "CxfImportError",
    "ImportFileError",
    "ImportOptions",
    "ImportedFile",
    "ImportedMeasurement",
    "Instrument",
    "JsonImportError",
    "UnknownFormatError",
    "VendorValue",
    "WorkbookImportError",
    "build_measurement",
    "detect_format",
    "import_client_id",
    "is_complete",
    "lab_of",
    "load_measurement_file",
    "read_measurement_file",
    "readings_from_import",
    "write_measurement_file",
]

#: Format name → file suffixes it is recognised by.
FORMATS: Final[Mapping[str, tuple[str, ...]]] = MappingProxyType(
    {
        "cxf": (".cxf", ".cxf3", ".xml"),
        "cgats": (".cgats", ".txt", ".ti3", ".cgt"),
        "csv": (".csv",),
        "xlsx": (".xlsx", ".xlsm"),
        "json": (".json",),
    }
)
_READERS: Final[Mapping[str, Callable[[Path, bytes | None], ImportedFile]]] = MappingProxyType(
    {
        "cxf": read_cxf,
        "cgats": read_cgats,
        "csv": read_csv,
        "xlsx": read_workbook,
        "json": read_measure_json,
    }
)
#: Format name → whether a file's bytes are whole (not cut short by a writer still at work).
_COMPLETE: Final[Mapping[str, Callable[[bytes], bool]]] = MappingProxyType(
    {
        "cxf": cxf.is_complete,
        "cgats": cgats.is_complete,
        "csv": csv_template.is_complete,
        "xlsx": workbook.is_complete,
        "json": measure_json.is_complete,
    }
)


def detect_format(path: Path | str, data: bytes | None = None) -> str:
    """The format of *path* (a key of :data:`FORMATS`): by suffix, else by the first bytes (of *data*
    when given: the file's bytes, already read)."""
    path = Path(path)
    suffix = path.suffix.lower()
    for name, suffixes in FORMATS.items():
        if suffix in suffixes:
            return name
    if data is not None:
        head = data[:512]
    else:
        try:
            with path.open("rb") as fh:
                head = fh.read(512)
        except OSError as exc:
            raise UnknownFormatError(path.name, "", "file", "a readable file", str(exc)) from exc
    head = head.lstrip(b"\xef\xbb\xbf").lstrip()
    if head.startswith(b"<"):
        return "cxf"
    if head.startswith(b"{"):
        return "json"
    if head.startswith(b"PK\x03\x04"):
        return "xlsx"
    first = head.split(b"\n", 1)[0].strip().upper()
    if first.startswith((b"CGATS", b"CTI", b"LGOROWLENGTH", b"ISO28178")):
        return "cgats"
    if b"," in first and b"SAMPLE" in first:
        return "csv"
    raise UnknownFormatError(
        path.name,
        "line 1",
        "format",
        "CxF3 (.cxf), CGATS.17 (.cgats/.txt), an MA-T12 workbook (.xlsx) or the CSV template (.csv)",
        suffix,
    )


def read_measurement_file(
    path: Path | str, fmt: str | None = None, data: bytes | None = None
) -> ImportedFile:
    """Read *path* in format *fmt* (default: :func:`detect_format`); typed errors name file, place, field.

    *data*: the file's bytes when the caller has read them already (the watch folder reads through a
    descriptor it checked); *path* then only names the file.
    """
    fmt = fmt or detect_format(path, data)
    if fmt not in _READERS:
        raise UnknownFormatError(Path(path).name, "", "format", " | ".join(_READERS), fmt)
    return _READERS[fmt](Path(path), data)


def load_measurement_file(path: Path | str, fmt: str | None = None) -> tuple[ImportedFile, bytes]:
    """:func:`read_measurement_file` of *path* read once: the parsed file and the very bytes it was
    parsed from, so an import hashes what it stores (``records.readings_from_file(..., data=)``) even
    when the file is saved again meanwhile. A missing, unreadable or oversized file is refused
    (:class:`ImportFileError` naming it)."""
    data = read_bytes(Path(path), ImportFileError)
    return read_measurement_file(path, fmt, data), data


def is_complete(path: Path | str, data: bytes) -> bool:
    """Whether *data*, the bytes of *path*, are a whole file rather than one a writer is still writing.

    Empty is not whole. CxF: the root element is closed; CGATS: an ``END_DATA`` line is there; an
    ``.xlsx``: the zip's central directory (written last) is; JSON: every bracket and string is
    closed; CSV, which has no end marker: the last line is ended. Bytes that are none of the formats
    count as whole (they are refused as they are). docs/import.md: the watch folder's protocol.
    """
    if not data:
        return False
    try:
        fmt = detect_format(path, data)
    except UnknownFormatError:
        return True
    return _COMPLETE[fmt](data)


def write_measurement_file(
    measurements: Sequence[ImportedMeasurement], path: Path | str, fmt: str | None = None
) -> str:
    """Write *measurements* to *path* as *fmt* (default: from the suffix); returns the format written."""
    path = Path(path)
    if fmt is None:
        fmt = next((n for n, sfx in FORMATS.items() if path.suffix.lower() in sfx), None)
    if fmt == "cxf":
        write_cxf(measurements, path)
    elif fmt == "cgats":
        write_cgats(measurements, path)
    elif fmt == "csv":
        write_csv(measurements, path)
    elif fmt == "xlsx":
        write_workbook(measurements, path)
    else:
        raise UnknownFormatError(
            path.name, "", "format", "cxf | cgats | csv | xlsx (or a .cxf/.cgats/.csv/.xlsx suffix)", fmt
        )
    return fmt
